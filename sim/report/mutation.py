"""``rasterhw report mutation``: ``docs/reproduction/mutation.md`` from the records of the mutation
campaign (``rasterhw mutate --all``) and of the proofs (``rasterhw prove --all``).

The record :data:`RECORD` (``docs/reproduction/mutation_runs.json``) holds the two commands' JSON
as they printed it (``{"commands", "campaign", "proofs"}``); the report is made from it and runs
nothing, unless ``--rerun``: then both commands run again (:data:`MUTANTS` mutants a block, seed
:data:`SEED`, on ``--scheduler``) and the record is rewritten. Per block: mutants, killed,
equivalent, survived, score (rows, ``source`` ``hdl:verilator``: the mutants' runs), and in the
page the proofs (kind, depth, passed) and every survivor's location and mutation. A report not
tied to one machine (``EXTRA_REPORTS`` in :mod:`rasterhw.sim.report.rows`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from rasterhw.sim import registry
from rasterhw.sim.paths import REPO_ROOT
from rasterhw.sim.report.rows import make_row

__all__ = ["ALL_RECORD", "MUTANTS", "RECORD", "SEED", "all_section", "classify_all", "classify_record", "merge_blocks",
           "rows", "sections", "why_table", "write_record"]

#: where the campaign's and the proofs' results are kept
RECORD = REPO_ROOT / "docs" / "reproduction" / "mutation_runs.json"
#: the campaign of the record: mutants a block, seed
MUTANTS, SEED = 30, 1
#: the one ``mutate --all`` campaign run as a single command (issue 50's must-show), its survivors
#: classified, with its time and the load it ran under: ``{"command", "commit", "result", "time",
#: "notes"}``
ALL_RECORD = REPO_ROOT / "docs" / "reproduction" / "mutation_all.json"


def write_record(campaign: dict, proofs: dict, commands: list[str], path=None) -> None:
    """Keep ``mutate --all`` 's and ``prove --all`` 's JSON (as printed) in the record."""
    (path or RECORD).write_text(json.dumps({"commands": commands, "campaign": campaign, "proofs": proofs},
                                           indent=1, sort_keys=True) + "\n")


def merge_blocks(results: list[dict], commands: list[str], path=None) -> None:
    """Single-block campaigns (``rasterhw mutate BLOCK -p ... --mutants 30 --seed 1 --json`` at the
    block's small configuration, :data:`MUTANTS` and :data:`SEED`, as printed) in the record in place
    of those blocks' results of the ``--all`` campaign, and ``commands`` (the commands that printed
    them) added to the record's: how the record follows a testbench change of a few blocks without
    a campaign over every block. A result at another size, mutant count or seed is refused."""
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.flow.mutate import all_configs

    record = _read(path)
    if record is None:
        raise RasterhwError("no record to merge into: rasterhw report mutation --rerun")
    small = all_configs()
    blocks = record["campaign"]["blocks"]
    for r in results:
        want = small.get(r["block"], {"": None})
        if "error" in r:   # a block that could not be mutated at its small configuration: said, no score
            r = {"block": r["block"], "params": r.get("params") or want, "seed": SEED, "mutants": MUTANTS,
                 "error": r["error"], "score": None}
        if (r["mutants"], r["seed"]) != (MUTANTS, SEED) or any(r["params"].get(k) != v for k, v in want.items()):
            raise RasterhwError(f"{r['block']}: the record holds {MUTANTS} mutants, seed {SEED}, at the small "
                                f"configuration {want}; not {r['mutants']}, {r['seed']}, {r['params']}")
        at = [k for k, b in enumerate(blocks) if b["block"] == r["block"]]
        entry = {**r, "config": "small"}
        if at:
            blocks[at[0]] = entry
        else:
            blocks.append(entry)
    write_record(record["campaign"], record["proofs"], [*record["commands"], *commands], path)


def _rescore(b: dict, survivors: list[dict]) -> dict:
    """A block's result with ``survivors`` in place of its own and its counts and score from them."""
    equivalent = sum(s.get("equivalence") == "equivalent" for s in survivors)
    n, killed = b["mutants"], b["killed"]
    score = killed / (n - equivalent) if b["baseline_passed"] and n > equivalent else None
    return {**b, "survivors": survivors, "equivalent": equivalent, "survived": n - killed - equivalent,
            "score": None if score is None else round(score, 4)}


def classify_record(blocks: list[str] | None = None, path=None, folders: dict | None = None,
                    toggle: bool = True) -> list[str]:
    """Every survivor of the record's blocks (``blocks``: only those) with the outputs its fault
    reaches and its class (:mod:`rasterhw.sim.flow.reach`; a survivor that reaches no output becomes
    ``equivalent``, ``equivalence_how`` ``structural``, and leaves the score) and, ``toggle``, whether
    mutant 0's runs ever activate it (:mod:`rasterhw.sim.flow.toggle`: ``exercise``; every killed
    mutant gets ``activated``), from the block's mutated bench made again at the record's parameters,
    mutants and seed, or taken from ``folders`` (block -> a campaign's folder holding its
    ``bench.v``, ``done.json`` and ``reach.json``, e.g. a copy of another tree's ``mutate --all``
    folders: only read). A block whose mutations today differ from the record's (its design changed
    since) is left as it is; its name is returned with why."""
    from rasterhw.sim.flow.mutate import _activation, _survivor, mutated_bench, survivor_reach

    record = _read(path)
    camp, skipped = record["campaign"], []
    for i, b in enumerate(camp["blocks"]):
        if "error" in b or not b.get("survivors") or (blocks is not None and b["block"] not in blocks):
            continue
        if folders and b["block"] in folders:
            bdir = Path(folders[b["block"]])
            muts = json.loads((bdir / "done.json").read_text())["mutations"]
        else:
            m = mutated_bench(b["block"], b["params"], mutants=b["mutants"], seed=b["seed"])
            bdir, muts = m["dir"], m["mutations"]
        by = {mu["mutant"]: mu for mu in muts}
        if any(_same(by.get(s["mutant"], {}).get("mutation", "")) != _same(s["mutation"]) for s in b["survivors"]) \
                or len(by) != b["mutants"]:
            skipped.append(f"{b['block']}: its mutations today differ from the record's (the design changed)")
            continue
        reached = survivor_reach(b["block"], b["params"], b["seed"], bdir, muts)
        act = _activation(b["block"], b["params"], b["seed"], bdir, muts) if toggle else None
        if act is not None and "error" in act:
            skipped.append(f"{b['block']}: toggle pass: {act['error']}")
        acts = act["mutants"] if act and "mutants" in act else None
        kept = []
        for s in b["survivors"]:
            eq = ({"equivalence": s["equivalence"], "why": s.get("equivalence_why", "")}
                  if s.get("equivalence") and s.get("equivalence_how", "").split(":")[0] != "structural" else None)
            kept.append(_survivor({"mutant": s["mutant"]}, by[s["mutant"]], eq, reached, acts))
        camp["blocks"][i] = {**_rescore(b, kept), "killed_by": [
            {**k, "reaches": reached["reaches"][k["mutant"]],
             **({"activated": acts[k["mutant"]]["activated"]} if acts else {})} for k in b.get("killed_by", [])]}
        if acts:
            camp["blocks"][i].update(toggle_build_s=act["build_s"], toggle_runs_s=act["runs_s"])
    write_record(camp, record["proofs"], record["commands"], path)
    return skipped


def classify_all(result: dict, folders: dict) -> list[str]:
    """The survivors of a ``mutate --all`` result (as printed; changed in place) with ``exercise``
    and its killed mutants with ``activated`` (:mod:`rasterhw.sim.flow.toggle`), from the
    campaign's own folders (``folders``: block -> its folder, or a copy: only read). Returns the
    blocks left without, with why."""
    from rasterhw.sim.flow.mutate import _activation
    from rasterhw.sim.flow.toggle import CONSTANT, exercise

    left = []
    for b in result["blocks"]:
        if "error" in b or b.get("score") is None or b["block"] not in folders:
            left.append(f"{b['block']}: " + ("not run" if "error" in b else "void" if b.get("score") is None
                                              else "no campaign folder"))
            continue
        muts = json.loads((Path(folders[b["block"]]) / "done.json").read_text())["mutations"]
        act = _activation(b["block"], b["params"], b["seed"], folders[b["block"]], muts)
        if "error" in act:
            left.append(f"{b['block']}: {act['error']}")
            continue
        acts = {int(k): v for k, v in act["mutants"].items()}
        for s in b["survivors"]:
            if s.get("equivalence") != "equivalent":
                s.update(exercise=exercise(acts[s["mutant"]]), exercise_why=acts[s["mutant"]]["why"])
                if acts[s["mutant"]].get("constant"):
                    s.update(equivalence="equivalent", equivalence_how=CONSTANT)
        for k in b.get("killed_by", []):
            k["activated"] = acts[k["mutant"]]["activated"]
        b.update(_rescore(b, b["survivors"]), toggle_build_s=act["build_s"], toggle_runs_s=act["runs_s"])
    return left


def all_section(run: dict, record: dict | None) -> list[str]:
    """The page's section on the single ``mutate --all`` campaign (:data:`ALL_RECORD`): per block its
    score beside the record's, its survivors' classes, its time and the load; for each block below
    0.9 its survivors and why no check kills them."""
    res, t = run["result"], run["time"]
    rec = {b["block"]: b for b in record["campaign"]["blocks"]} if record else {}
    md = ["", "## The single `mutate --all` campaign", "",
          f"`{run['command']}` at commit {run['commit']}, {res['mutants']} mutants a block, seed {res['seed']}, "
          f"every block at {res['config']}. Wall time {t['wall_s']:.0f} s ({t['wall_s'] / 60:.1f} min), "
          f"CPU {t['user_s']:.0f} s user + {t['sys_s']:.0f} s system (`/usr/bin/time -v`, the command and all "
          f"its workers), peak resident {t['max_rss_mb']:.0f} MB; the campaign's own `wall_s` "
          f"{res['wall_s']:.0f} s; {res['computed']} tasks run, {res['reused']} from the store. "
          + " ".join(run.get("notes", [])), "",
          "| block | score | record's score | killed | equivalent | survived | not exercised | exercised | "
          "Yosys s | build s |", "|---|---|---|---|---|---|---|---|---|---|"]
    for b in res["blocks"]:
        r = rec.get(b["block"], {})
        rs = "—" if r.get("score") is None else f"{r['score']:.3f}"
        if "error" in b:
            md.append(f"| `{b['block']}` | not run: {b['error']} | {rs} | | | | | | | |")
            continue
        sc = "void" if b["score"] is None else f"{b['score']:.3f}"
        ne, ex, _nc = _exercise_counts(b)
        md.append(f"| `{b['block']}` | {sc} | {rs} | {b['killed']} | {b['equivalent']} | {b['survived']} | {ne} | "
                  f"{ex} | {_num(b.get('yosys_s'))} | {_num(b.get('build_s'))} |")
    low = [b for b in res["blocks"] if "error" not in b and b.get("score") is not None and b["score"] < 0.9]
    md += ["", f"Blocks below 0.9: {len(low)} of {len(res['blocks'])}. Their survivors and why no check "
           "kills them (the classes as in \"Why the survivors live\"):", ""]
    for b in low:
        md += [f"#### `{b['block']}` ({b['score']:.3f}; {b['survived']} survived of {b['mutants']})", ""]
        md += [f"- mutant {s['mutant']}: {', '.join(f'`{x}`' for x in s['src']) or '(no Amaranth source)'}: "
               f"{s['mutation'].replace('|', '/')}" + _survivor_note(s)
               for s in b["survivors"] if s.get("equivalence") != "equivalent"]
        md.append("")
    return md


def _num(x) -> str:
    return "—" if x is None else f"{x:.0f}"


def _same(mutation: str) -> str:
    """A mutation in words without the serial number Yosys gives its cell (``$add$bench.v:829$216``,
    ``$procdff$1801``: it counts every cell of the file, so it moves when the bench top around the
    block gains or loses one) and without the wire's name (Yosys picks one of the names a net has);
    the kind of cell, its source line, port and bit stay)."""
    return re.sub(r" \(wire .*\)$", "", re.sub(r"\$\d+ port ", " port ", mutation))


def _read(path=None) -> dict | None:
    try:
        return json.loads((path or RECORD).read_text())
    except (OSError, ValueError):
        return None


def _cfg(params: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in params.items())


def _proof_cell(p: dict | None) -> str:
    if p is None:
        return "—"
    if p.get("passed") is None:
        f = p.get("fits_result")
        fits = (f"; fits at {_cfg(p['fits'])}: {f['kind']}, depth {f['depth']}, "
                f"{'passed' if f['passed'] else '**failed**'}" if f else
                "; no configuration tried fits" if "fits" in p else "")
        return f"unproven: {p.get('reason')}{fits}"
    s = f"{p['kind']}, depth {p['depth']}, {'passed' if p['passed'] else '**failed**'}"
    if p.get("latency") is not None:
        s += f" (latency {p['latency']})"
    return s


def sections(record: dict) -> list[str]:
    """The page below the table: per block the counts, the proofs and the survivors."""
    camp, proofs = record["campaign"], {b["block"]: b for b in record["proofs"]["blocks"]}
    md = ["## Per block", "",
          "From the record `docs/reproduction/mutation_runs.json`, made by: "
          + "; ".join(f"`{c}`" for c in record["commands"]) + ". "
          f"{camp['mutants']} mutants a block (seed {camp['seed']}), every block at {camp['config']}; "
          f"campaign wall time {camp['wall_s']:.0f} s on `{camp['scheduler'].split(':')[0]}` "
          f"({camp['computed']} tasks run, {camp['reused']} from the store). A mutant is killed when its "
          "testbench (words against the golden model, cycles, stream rules, watchdog) fails; "
          "`equivalent`: survivors proven equivalent to the block, by structure (the mutated bit has no path "
          "to any output, `sim/flow/reach.py`, every block) or by Yosys's equivalence flow (`mutate BLOCK` "
          "only; `mutate --all` tries none); they leave the score (docs/mutation.md). Every other survivor "
          "has a class: `uncompared` (it reaches only outputs no check reads) or `compared` (it reaches "
          "compared outputs: the stimulus never makes the fault visible, or an equivalence not shown). "
          "Stream proof: "
          "`rasterhw prove --all` (sim/flow/stream_proof.py); own proof: the block's registered proof.", "",
          "| block | configuration | mutants | killed | equivalent | survived | score | stream proof | own proof |",
          "|---|---|---|---|---|---|---|---|---|"]
    for b in camp["blocks"]:
        pr = proofs.get(b["block"])
        own = pr.get("own") if pr else None
        if "error" in b:
            md.append(f"| `{b['block']}` | {_cfg(b['params'])} | — | — | — | — | not run: {b['error']} | "
                      f"{_proof_cell(pr)} | {_proof_cell(own)} |")
            continue
        score = f"void (mutant 0 fails: {b['baseline_why']})" if b["score"] is None else f"{b['score']:.3f}"
        md.append(f"| `{b['block']}` | {_cfg(b['params'])} | {b['mutants']} | {b['killed']} | {b['equivalent']} | "
                  f"{b['survived']} | {score} | {_proof_cell(pr)} | {_proof_cell(own)} |")
    md += why_table(camp["blocks"])
    md += ["", "## Survivors", ""]
    for b in camp["blocks"]:
        if not b.get("survivors"):
            continue
        md += [f"### `{b['block']}` ({b['survived']} of {b['mutants']})", ""]
        classes = [s.get("reach_class") for s in b["survivors"]]
        if any(classes):
            md += ["Survivors by class (`sim/flow/reach.py`, computed): "
                   + ", ".join(f"{c} {classes.count(c)}" for c in _CLASSES if c in classes) + ".", ""]
        ex = [s.get("exercise") for s in b["survivors"]]
        if any(ex):
            md += ["Under the stimulus (`sim/flow/toggle.py`, computed on mutant 0's runs): "
                   + ", ".join(f"{c.replace('_', ' ')} {ex.count(c)}" for c in ("not_exercised", "exercised")
                               if c in ex) + ".", ""]
        md += [f"- mutant {s['mutant']}: {', '.join(f'`{x}`' for x in s['src']) or '(no Amaranth source)'}: "
               f"{s['mutation'].replace('|', '/')}" + _survivor_note(s) for s in b["survivors"]]
        md.append("")
    return md


#: a survivor's class (:mod:`rasterhw.sim.flow.reach`) and what it says about the checks
_CLASSES = {"unobservable": "no path to any output: equivalent by structure",
            "uncompared": "reaches only outputs no check reads",
            "compared": "reaches compared outputs; the stimulus never makes it visible there, or it is equivalent "
                        "in a way neither the structure nor the proof shows"}


def _exercise_counts(b: dict) -> tuple[int, int, int]:
    """(not exercised, exercised, not classed) among a block's survivors that are not equivalent."""
    alive = [s for s in b.get("survivors", []) if s.get("equivalence") != "equivalent"]
    ex = [s.get("exercise") for s in alive]
    return ex.count("not_exercised"), ex.count("exercised"), len(alive) - ex.count("not_exercised") - ex.count("exercised")


def why_table(blocks: list[dict]) -> list[str]:
    """Per block: the survivors that are not equivalent, split by whether the stimulus ever activates
    their fault (:mod:`rasterhw.sim.flow.toggle`)."""
    md = ["", "## Why the survivors live", "",
          "For every survivor that is not equivalent, the toggle pass (`sim/flow/toggle.py`: the unmutated "
          "bench with every mutated bit probed, sampled at both edges of every clock over the runs every "
          "mutant gets) says whether the value its fault needs ever occurs. **not exercised**: it never does "
          "(an `inv` always does; `const0` needs the bit at 1, `const1` at 0, `cnot1` its control bit at 1, "
          "`cnot0` at 0): the mutant runs exactly as the block does, so no check on these runs can kill it: "
          "a stimulus gap, the bit and value named below. **exercised**: the fault changes the bit at some "
          "clock edge, yet no compared output differs in any run (masked downstream, or equivalent in a way "
          "neither the tracing nor the proof shows). **not classed**: no toggle pass for the block (its "
          "mutations today differ from the record's, so the record's survivors cannot be mapped, or its "
          "campaign's folder was not at hand).", "",
          "| block | score | survived | not exercised | exercised | not classed |", "|---|---|---|---|---|---|"]
    tot = [0, 0, 0, 0]
    for b in blocks:
        if "error" in b or b.get("score") is None:
            continue
        counts = (b["survived"], *_exercise_counts(b))
        tot = [t + c for t, c in zip(tot, counts, strict=True)]
        md.append(f"| `{b['block']}` | {b['score']:.3f} | " + " | ".join(map(str, counts)) + " |")
    md.append("| all | | " + " | ".join(map(str, tot)) + " |")
    return md


def _survivor_note(s: dict) -> str:
    """A survivor's class, the outputs it reaches, its equivalence and whether the stimulus ever
    activates it, for the page."""
    out = ""
    if s.get("reach_class"):
        out += f" — **{s['reach_class']}**"
        if s["reach_class"] == "unobservable":
            out += " (no path to any output)"
        else:
            out += f" (reaches {', '.join(s['reaches'])})"
    if "equivalence" in s and s.get("equivalence_how", "").split(":")[0] != "structural":
        how = f", {s['equivalence_how']}" if s.get("equivalence_how") else ""
        why = f": {s['equivalence_why']}" if s.get("equivalence_why") else ""
        out += f"; equivalence: **{s['equivalence']}**{how}{why}"
    if s.get("exercise"):
        out += f"; **{s['exercise'].replace('_', ' ')}**: {s['exercise_why']}"
        if s.get("equivalence") == "equivalent" and s.get("reach_class") != "unobservable":
            out += " — **equivalent** by structure (the netlist is unchanged)"
    return out


def rows(*, engine: str = "pysim", progress: bool = False, out_dir=None, fast: bool = False, rerun: bool = False,
         scheduler: str = "serial", store=None, fresh: bool = False):
    """Rows per block (mutants, killed, survived, score) and the page's sections, from the record;
    ``rerun``: run the campaign and the proofs again first (``fast`` never reruns)."""
    if rerun and not fast:
        from rasterhw.sim.flow.mutate import campaign_all
        from rasterhw.sim.flow.stream_proof import prove_all

        camp = campaign_all(mutants=MUTANTS, seed=SEED, scheduler=scheduler, store=store, fresh=fresh,
                            progress=progress)
        write_record(camp, prove_all(scheduler=scheduler),
                     [f"rasterhw mutate --all --mutants {MUTANTS} --seed {SEED} --scheduler {scheduler} --json",
                      f"rasterhw prove --all --scheduler {scheduler} --json"])
    record = _read()
    from rasterhw.sim.flow.mutate import all_configs

    blocks = {b["block"]: b for b in record["campaign"]["blocks"]} if record else {}
    out = []
    for block, params in all_configs().items():
        b = blocks.get(block)
        why = ("no record: rasterhw report mutation --rerun" if record is None else
               f"not in the record's campaign ({RECORD.name})" if b is None else
               f"not run: {b['error']}" if "error" in b else
               f"void: mutant 0 (no mutation) fails its testbench here ({b['baseline_why']})" if b["score"] is None
               else None)
        system = registry.block_machine(block).name
        fig = f"{block} mutation campaign ({_cfg(b['params'] if b else params)})"
        for q, key, unit in (("mutants", "mutants", "mutants"), ("killed", "killed", "mutants"),
                             ("survived", "survived", "mutants"), ("mutation score", "score", "")):
            v = None if why else b[key]
            # a block the record has no run of (or whose run stopped on an error) is "not run"; a void
            # baseline is a finding the run produced
            out.append(make_row(system, fig, q, paper=None, formula=None, measured=v, unit=unit,
                                source="hdl:verilator", reason=why,
                                run=b is not None and "error" not in b))
    run_all = _read(ALL_RECORD) if record else None
    return out, (sections(record) if record else []) + (all_section(run_all, record) if run_all else [])
