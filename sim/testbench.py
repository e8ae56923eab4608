# amaranth: UnusedElaboratable=no
"""One testbench per HDL block: what makes the block different, declared once.

A :class:`Testbench` (one per block, in its machine's ``sim/NAME/testbench.py``, registered in
``Machine.testbenches``) knows how to build the block from typed parameters, which of its
stream ports the engines drive and collect, how to turn a random seed (or a scene) into stimulus
words through the golden model, and what the golden model expects on every output port (words
in order, and the cycle count where the golden cycle model gives one). The engines
(``sim/engines/``: Amaranth pysim, plain Verilator with the one C++ main) run any testbench the
same way: they own clocks, stream sources with idle gaps, sinks with seeded back-pressure, cycle
stamps, build caches and run folders. This module and the engines know no machine.

Words are integers: a stream's payload as one packed word (``payload.as_value()``); a port's words
in a :class:`Stimulus` or an :class:`Expected` are a list of ints or, for millions of words, the
same values packed as ``(N, bytes)`` uint8 rows, big-endian (``sim/packed.py``); a
:class:`Run`'s are ints, or such rows where the run asked for them (``engines.run(...,
packed=True)``: the Verilator engine reads its binary dumps so, no Python int per word).
:func:`compare` takes either form on either side.

Cycles: clock edges are counted from 0 at the first rising edge of the run (no reset: the
design starts at its ``init`` values in every engine); a transfer's stamp is the index of the
edge at which it happened, and a run's ``cycles`` is the last output stamp + 1.

Clocks: by default every clock domain of the block runs off one clock (one edge each per cycle).
A run may give every domain its own :class:`Clock` instead (``engines.run(..., clocks=...)``: a
half period and the time of its first rising edge, in steps of one common time unit); a port's
stamps then count the edges of its own domain, and :meth:`Run.cycles_at` turns an edge of one
domain into the edges of the run's first domain (its reference clock) that came before it.
Edges of two clocks at the same time are one step: every domain's registers see the values from
before it (as in an HDL simulator, where the flops' updates are non-blocking).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from operator import ne

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.packed import as_ints

__all__ = ["Clock", "Expected", "Run", "Stimulus", "Testbench", "clocks_of", "compare", "find_testbench", "port_of"]


@dataclass(frozen=True)
class Clock:
    """One domain's clock in a run with separate clocks: ``half`` period and the time of its first
    rising edge (edge 0) ``first``, integers in a time unit common to every domain of the run."""

    half: int
    first: int = 0

    def __post_init__(self):
        for name, v, lo in (("half period", self.half, 1), ("first edge", self.first, 0)):
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < lo:
                raise RasterhwError(f"clock {name} must be an integer >= {lo}, not {v!r}")

    def edge_time(self, k: int) -> int:
        """The time of rising edge ``k`` (from 0)."""
        return self.first + 2 * self.half * k

    def edges_before(self, t: int) -> int:
        """Rising edges strictly before time ``t`` (an edge at ``t`` itself is not counted)."""
        return 0 if t <= self.first else -(-(t - self.first) // (2 * self.half))


def clocks_of(given, domains: tuple[str, ...]) -> dict[str, Clock]:
    """``{domain: Clock}`` from a run's ``clocks`` argument: a :class:`Clock`, a half period, or
    ``(half, first)`` for every domain of ``domains`` (the first domain is the reference); the
    domains in ``domains``' order; a one-line error for a missing, unknown or bad one."""
    if not isinstance(given, dict):
        raise RasterhwError(f"clocks must be a dict {{domain: half period or (half, first)}}, not {given!r}")
    if set(given) != set(domains):
        raise RasterhwError(f"clocks: give every clock domain of the block ({', '.join(domains)}), "
                            f"not {', '.join(map(str, given)) or 'none'}")
    out = {}
    for d in domains:
        c = given[d]
        if isinstance(c, Clock):
            out[d] = c
        elif isinstance(c, tuple) and len(c) == 2:
            out[d] = Clock(*c)
        else:
            out[d] = Clock(c)
    return out


@dataclass(frozen=True)
class Stimulus:
    """Words for every input port, and the idle clocks before each word (none: back to back)."""

    words: dict[str, list[int]]                  # or (N, bytes) uint8 rows per port (module docstring)
    gaps: dict[str, list[int]] = field(default_factory=dict)
    what: str = ""                               # one line for logs: scene / seed / settings
    source: object = None                        # the golden model's input the words were made from

    def gaps_of(self, port: str) -> np.ndarray:
        """The idle clocks before each word of ``port``, (N,) int64 (zeros where none are given)."""
        g = self.gaps.get(port)
        return np.zeros(len(self.words[port]), np.int64) if g is None else np.asarray(g, dtype=np.int64)


@dataclass(frozen=True)
class Expected:
    """What the golden model says comes out: every word of every output port, in order, and the
    cycle count when the golden cycle model gives it (input back to back, output always ready)."""

    words: dict[str, list[int]]
    cycles: int | None = None
    golden: object = None                        # the golden model's result the words were made from (a frame)


@dataclass(frozen=True)
class Run:
    """What an engine saw: the words and the edge of every transfer, per output port."""

    engine: str
    words: dict[str, list[int]]
    stamps: dict[str, list[int]]                 # an int64 array per port in a Verilator run with packed=True
    wall_s: float = 0.0
    build_s: float = 0.0
    run_s: float = 0.0
    cpu_s: float | None = None                   # CPU seconds (user + sys) of the simulation; None: not measured
    protocol_errors: int = 0                     # clocks that broke the stream rules, every port
    status: dict = field(default_factory=dict)   # the testbench's status values at the end (Testbench.status)
    build: dict = field(default_factory=dict)    # how the model was built (engine's words: opt, pgo, ...)
    clocks: dict = field(default_factory=dict)   # {domain: Clock} of a run with separate clocks (else empty)
    port_domains: dict = field(default_factory=dict)   # {output port: its domain} (separate clocks)

    def cycles_at(self, port: str, edge: int) -> int:
        """Edges of the reference clock (the first domain's) before edge ``edge`` of ``port``'s
        domain; with one clock, ``edge`` itself."""
        if not self.clocks:
            return edge
        ref = next(iter(self.clocks.values()))
        return ref.edges_before(self.clocks[self.port_domains[port]].edge_time(edge))

    @property
    def cycles(self) -> int:
        """Reference-clock edges until the edge after the last transfer (one clock: the last stamp + 1)."""
        return max((self.cycles_at(p, int(s[-1]) + 1) for p, s in self.stamps.items() if len(s)), default=0)


class Testbench:
    """Base of every block's testbench; a subclass sets the class attributes and the two methods.

    ``block``: the registry name (``rasterhw verilog --list``); ``inputs`` / ``outputs``: stream
    ports as attribute paths (``"i"``, ``"o_merge[3]"``; :meth:`outputs_of` may depend on the
    parameters); ``domains``: the clock domains the block uses, ``sync`` first (the engines clock
    them together, one edge each per cycle, unless a run gives each its own :class:`Clock`);
    ``port_domains``: the ports not in ``sync``.
    """

    block: str = ""
    inputs: tuple[str, ...] = ("i",)
    outputs: tuple[str, ...] = ("o",)
    domains: tuple[str, ...] = ("sync",)
    port_domains: dict[str, str] = {}   # port (or port array, e.g. "o_merge") -> its domain; default sync
    #: output ports whose sink is always ready, whatever the run's ``stall`` (a log the block writes
    #: as things happen and cannot hold back, e.g. a per-line counter)
    always_ready: tuple[str, ...] = ()
    #: C++ optimisation of the Verilator engine's model: -O1 builds fast for the many short runs;
    #: a testbench of one long run (millions of clocks) may ask for -O2 (``$RASTERHW_VERILATOR_OPT``
    #: then applies, as for every -O2 build)
    verilator_opt: str = "-O1"
    #: ``{domain: (half period, first edge)}`` of every domain for a third run of each mutant in
    #: ``rasterhw mutate`` (``sim/flow/mutate.py``), with separate clocks, idle gaps and back-pressure:
    #: a block whose domains meet in a clock-domain crossing (an asynchronous FIFO) has logic that
    #: only matters when the clocks differ. None: every run clocks the domains together
    mutation_clocks: dict | None = None

    # ------------------------------------------------------------------ parameters and the DUT
    def params(self, **given) -> dict:
        """The block's parameters: its factory's defaults, overridden by ``given`` (checked by
        the factory, which raises on a bad one)."""
        names, defaults = self.signature()
        unknown = sorted(set(given) - set(names))
        if unknown:
            raise RasterhwError(f"{self.block}: no parameter {', '.join(unknown)}; "
                                f"parameters: {', '.join(names)}")
        return {**defaults, **given}

    def signature(self) -> tuple[list[str], dict]:
        """(parameter names, defaults) of the block's factory (its module imported); a testbench may
        give them from the build cache instead (``verilog_cache.factory_params``: no HDL import)."""
        sig = inspect.signature(registry.load(registry.blocks()[self.block]))
        return list(sig.parameters), {k: p.default for k, p in sig.parameters.items()
                                      if p.default is not inspect.Parameter.empty}

    def dut(self, params: dict):
        """A fresh instance of the block (engines elaborate it once per run)."""
        return registry.load(registry.blocks()[self.block])(**params)

    def inputs_of(self, params: dict) -> tuple[str, ...]:
        return self.inputs

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        return self.outputs

    def status(self, dut, params: dict) -> dict:
        """Values of the block read when the run ends, beside its streams (``{name: Amaranth value}``,
        64 bits together at most, e.g. a frame counter or a sticky overflow): ``Run.status``."""
        return {}

    def hier_blocks(self, params: dict) -> tuple[str, ...]:
        """Verilog modules of the bench that the Verilator engine may verilate and compile once,
        however many instances there are (``build={"hier": True}``: Verilator's hierarchical
        verilation), e.g. a matrix's cell instantiated by name. None by default."""
        return ()

    def stall_of(self, port: str, stall: int) -> int:
        """The back-pressure of output ``port`` in a run with ``stall`` (0 for :attr:`always_ready` ports)."""
        return 0 if port in self.always_ready else stall

    def sink_seed(self, params: dict, port: int, seed: int) -> int:
        """The back-pressure seed of output ``port`` (its index) in a run seeded ``seed``."""
        return seed + port

    # ------------------------------------------------------------------ the speed build (optional)
    def sim_verilog(self, params: dict, text: str) -> str:
        """The Verilog a simulator compiles for a speed build (``build={"speed": True}``): ``text``
        (the bench top with the block) reshaped for speed, the same circuit; default unchanged."""
        return text

    def train_stimulus(self, params: dict) -> Stimulus | None:
        """The stimulus a speed build's gcc profile is trained on (None: no profile)."""
        return None

    def domain_of(self, port: str) -> str:
        """The clock domain of stream port ``port`` (``o_merge[3]`` looks up ``o_merge`` too)."""
        return self.port_domains.get(port, self.port_domains.get(port.split("[")[0], "sync"))

    # ------------------------------------------------------------------ what differs per block
    def stimulus(self, params: dict, seed: int) -> Stimulus:   # pragma: no cover - abstract
        raise NotImplementedError

    def expect(self, params: dict, stim: Stimulus) -> Expected:   # pragma: no cover - abstract
        raise NotImplementedError


def port_of(dut, path: str):
    """``"o_merge[3]"`` -> ``dut.o_merge[3]``; ``"i"`` -> ``dut.i``."""
    obj = dut
    for part in path.replace("]", "").split("."):
        name, *idx = part.split("[")
        obj = getattr(obj, name)
        for i in idx:
            obj = obj[int(i)]
    return obj


def compare(exp: Expected, got: Run, *, cycle_exact: bool = True) -> dict:
    """``{"mismatches": words that differ or are missing/extra, per port summed, "ports": {...},
    "cycles", "cycles_golden", "cycle_mismatches"}``; a cycle mismatch is counted only where the
    golden model gives cycles and ``cycle_exact`` (a run with idle gaps or back-pressure may take
    longer, never fewer cycles)."""
    ports, total = {}, 0
    for p, want in exp.words.items():
        have = got.words.get(p, [])
        if isinstance(want, np.ndarray) and isinstance(have, np.ndarray) and want.shape[1:] == have.shape[1:]:
            n = min(len(want), len(have))   # packed rows on both sides: rows that differ, in NumPy
            if want.shape == have.shape and np.array_equal(want, have):
                bad = 0                       # the usual run: one pass over the bytes, no row test
            else:
                bad = int(np.count_nonzero((want[:n] != have[:n]).reshape(n, -1).any(axis=1))) + abs(len(want) - len(have))
        else:
            want, have = _ints(want), _ints(have)
            # equal lists (the usual run) compare in C at once; otherwise count the differing words
            bad = 0 if want == have else sum(map(ne, want, have)) + abs(len(want) - len(have))
        ports[p] = {"words": len(want), "mismatches": bad}
        total += bad
    cyc = None
    if exp.cycles is not None:
        cyc = int(got.cycles != exp.cycles) if cycle_exact else int(got.cycles < exp.cycles)
    return {"mismatches": total, "ports": ports, "cycles": got.cycles, "cycles_golden": exp.cycles,
            "cycle_mismatches": cyc}


def _ints(words) -> list:
    """A port's words as a list of ints (packed rows converted: ``packed.as_ints``)."""
    if isinstance(words, np.ndarray):
        return as_ints(words)
    return words if isinstance(words, list) else list(words)


def find_testbench(block: str) -> Testbench:
    """The registered testbench of ``block`` (``Machine.testbenches``), a one-line error if none."""
    known = registry.entries("testbenches")
    if block not in known:
        raise RasterhwError(f"no testbench for block {block!r}; testbenches: {', '.join(sorted(known))}")
    return registry.load(known[block])()
