"""The engines that run any registered :class:`~rasterhw.sim.testbench.Testbench`: Amaranth pysim
(``pysim.py``), plain Verilator with the one C++ main (``verilator.py``), and cocotb on Verilator
or Icarus (``cocotb.py``: the plain engine's bench top, clocked by one generic cocotb test), all
with the same stream sources (idle gaps from the stimulus) and sinks (seeded back-pressure,
``pattern.py``), so a run gives the same words and the same cycle stamps on each. They know no
machine.

Usage::

    tb = find_testbench("zbm-seggen")
    p = tb.params(width=48, height=24)
    stim = tb.stimulus(p, seed=3)
    got = run(tb, p, stim, engine="verilator", stall=64, seed=5)
    compare(tb.expect(p, stim), got)
"""

from __future__ import annotations

import threading
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import verilator
from rasterhw.sim.engines.runner import SIMULATORS as _COCOTB_SIMS
from rasterhw.sim.testbench import Run, Stimulus, Testbench, clocks_of

__all__ = ["ALIASES", "ENGINES", "Tally", "run", "tally", "with_gaps"]


def _pysim(*args, **kw) -> Run:
    """The pysim engine (``pysim.run``), imported at its first run: Amaranth's simulator is not
    loaded by a run on another engine."""
    from rasterhw.sim.engines import pysim

    return pysim.run(*args, **kw)


def _cocotb(*args, sim: str, **kw) -> Run:
    """The cocotb engine on simulator ``sim`` (``cocotb.run``), imported at its first run, as pysim."""
    from rasterhw.sim.engines import cocotb

    return cocotb.run(*args, sim=sim, **kw)


#: engine name -> cocotb simulator: one per simulator of the cocotb runner (``runner.SIMULATORS``)
_COCOTB = {f"cocotb-{sim}": sim for sim in _COCOTB_SIMS}
ENGINES = {"pysim": _pysim, "verilator": verilator.run,
           **{name: partial(_cocotb, sim=sim) for name, sim in _COCOTB.items()}}
#: the command line's simulator names for engines: ``icarus`` (cocotb benches' name) is cocotb on Icarus
ALIASES = {"icarus": "cocotb-icarus"}


@dataclass
class Tally:
    """Every engine run made inside :func:`tally` (any thread), summed: ``sim_cycles`` (each run's
    ``cycles``), ``run_s``, ``build_s``, ``cpu_s`` (None if a run's CPU was not measured: the cocotb
    engines)."""

    runs: list = field(default_factory=list)

    @property
    def sim_cycles(self) -> int:
        return int(sum(r.cycles for r in self.runs))

    @property
    def run_s(self) -> float:
        return float(sum(r.run_s for r in self.runs))

    @property
    def build_s(self) -> float:
        return float(sum(r.build_s for r in self.runs))

    @property
    def cpu_s(self) -> float | None:
        cpu = [r.cpu_s for r in self.runs]
        return None if not cpu or None in cpu else float(sum(cpu))


_tallies: list[Tally] = []
_tally_lock = threading.Lock()


@contextmanager
def tally():
    """Collect every :func:`run` made inside the ``with`` (every thread of this process) in a :class:`Tally`."""
    t = Tally()
    with _tally_lock:
        _tallies.append(t)
    try:
        yield t
    finally:
        with _tally_lock:
            _tallies.remove(t)


def run(tb: Testbench, params: dict, stim: Stimulus, *, engine: str = "pysim", idle: float = 0.0, stall: int = 0,
        seed: int = 1, expect_words: dict[str, int] | None = None, max_cycles: int | None = None,
        build: dict | None = None, clocks: dict | None = None, packed: bool = False) -> Run:
    """Run ``stim`` through block ``tb.block`` with ``params`` on ``engine``.

    ``idle`` (0 <= idle < 1): every input word without a gap of its own in ``stim`` waits a random
    number of idle clocks (geometric: each clock idle with probability ``idle``, at most 255),
    drawn from ``seed`` and the port, the same on every engine.
    ``stall`` (0..255): every output's ``ready`` is low on a clock when the low byte of a seeded
    xorshift is below it (0: always ready); ``seed`` seeds it (port k uses ``tb.sink_seed(params, k, seed)``,
    ``seed + k`` unless the testbench says otherwise); a testbench's ``always_ready`` outputs are
    never back-pressured.
    ``expect_words``: words to collect per output port (the run ends when all have come);
    ``max_cycles``: a watchdog (default: 10,000 + 64 clocks per word in and out, scaled up by the
    idle gaps and the stalls; a block that stops gives a one-line error, not a hang), in edges of
    the reference clock (the block's first domain, ``sync``).
    ``clocks``: ``{domain: Clock | half period | (half, first edge)}`` for every domain of the block
    (``tb.domains``): separate clocks (``sim/testbench.py``: :class:`Clock`); each port's gaps,
    back-pressure and stamps then count its own domain's edges. None: every domain on one clock.
    ``packed``: the Verilator engine gives the output words as packed rows (``packed.py``: ``(N,
    bytes)`` uint8, big-endian), read from its binary dumps without a Python int per word (262,144
    128-bit words: 0.2 CPU-s as ints), and each port's stamps as one int64 array (1.3 M stamps:
    ~0.04 CPU-s as ints); the other engines give ints (``testbench.compare`` and the
    testbenches that ask for rows take either).
    """
    engine = ALIASES.get(engine, engine)
    if engine not in ENGINES:
        raise RasterhwError(f"engine must be one of {', '.join((*ENGINES, *ALIASES))}, not {engine!r}")
    if not (isinstance(stall, int) and 0 <= stall <= 255):
        raise RasterhwError(f"stall must be an integer in 0..255, not {stall!r}")
    if not (isinstance(idle, (int, float)) and 0 <= idle < 1):
        raise RasterhwError(f"idle must be a probability in [0, 1), not {idle!r}")
    outs = tb.outputs_of(params)
    if stall and any(tb.sink_seed(params, k, seed) & 0xFFFF_FFFF == 0 for k, n in enumerate(outs)
                     if tb.stall_of(n, stall)):
        # output k's back-pressure is the xorshift seeded seed + k: from 0 it stays 0 (never ready)
        raise RasterhwError(f"seed {seed} gives an output a back-pressure seed of 0 (xorshift stays 0: "
                            "ready never rises); use another seed")
    kw = {}
    if clocks is not None:
        if tb.domains[0] != "sync":
            raise RasterhwError(f"{tb.block}: separate clocks need the domains with sync first, not {tb.domains}")
        kw["clocks"] = clocks_of(clocks, tb.domains)
    if idle:
        stim = with_gaps(stim, idle, seed, tb.inputs_of(params))
    if expect_words is None:
        raise RasterhwError("say how many words to collect per output port (expect_words)")
    if max_cycles is None:
        words = sum(len(w) for w in stim.words.values()) + sum(expect_words.values())
        gaps = sum(int(np.sum(g, dtype=np.int64)) for g in stim.gaps.values())
        max_cycles = (10_000 + 64 * words + gaps) * (1 + stall // 32)
        if "clocks" in kw:   # a slower clock than the reference takes more reference edges
            slow = max(c.half for c in kw["clocks"].values()) / kw["clocks"]["sync"].half
            max_cycles = int(max_cycles * max(1.0, slow))
    if build and engine != "verilator" and (engine not in _COCOTB or set(build) - {"depth", "out_depth"}):
        raise RasterhwError(f"build settings are for the verilator engine (cocotb's: depth, out_depth), not {engine}")
    if build:
        kw["build"] = build
    if packed and engine == "verilator":
        kw["packed"] = True
    got = ENGINES[engine](tb, params, stim, stall=stall, seed=seed, expect_words=expect_words,
                          max_cycles=max_cycles, **kw)
    with _tally_lock:
        for t in _tallies:
            t.runs.append(got)
    return got


def with_gaps(stim: Stimulus, idle: float, seed: int, ports) -> Stimulus:
    """``stim`` with random idle gaps before every word of the ``ports`` that have none."""
    gaps = dict(stim.gaps)
    for k, p in enumerate(ports):
        if p not in gaps:
            rng = np.random.default_rng([seed, k])
            gaps[p] = np.minimum(rng.geometric(1 - idle, len(stim.words[p])) - 1, 255).tolist()
    return replace(stim, gaps=gaps)
