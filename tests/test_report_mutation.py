"""``rasterhw report mutation`` (sim/report/mutation.py): the page and rows come from the record of
the campaign and the proofs, nothing is run without --rerun."""

from __future__ import annotations

import pytest
from rasterhw.sim.report import mutation as R
from rasterhw.sim.report.rows import NOT_RUN, run_report


def _record():
    camp = {"mutants": 2, "seed": 1, "config": "each block's Flow.small", "wall_s": 12.0, "scheduler": "tcp://x:1",
            "computed": 3, "reused": 0,
            "blocks": [{"block": "experts-dmm", "params": {"depth": 16}, "config": "small", "mutants": 2, "killed": 1,
                        "equivalent": 0, "survived": 1, "bounded_equivalent": 0, "score": 0.5,
                        "baseline_passed": True,
                        "survivors": [{"mutant": 2, "src": ["hdl/experts/dmm.py:76"], "mutation": "inv on $x port Q bit 0"}]},
                       {"block": "zbm-merger", "params": {"fifo_depth": 4}, "config": "small", "seed": 1,
                        "error": "Yosys took too long", "score": None}]}
    proofs = {"blocks": [{"block": "experts-dmm", "params": {"depth": 16}, "kind": "k-induction", "depth": 7,
                          "passed": True, "latency": 3, "reason": None, "own": None},
                         {"block": "zbm-merger", "params": {"fifo_depth": 4}, "kind": None, "depth": None,
                          "passed": None, "latency": None, "reason": "the solver did not finish", "own":
                          {"kind": "bmc", "depth": 16, "passed": True}}]}
    return camp, proofs


def test_report_is_made_from_the_record(tmp_path, monkeypatch):
    rec = tmp_path / "mutation_runs.json"
    camp, proofs = _record()
    R.write_record(camp, proofs, ["rasterhw mutate --all --mutants 2 --json"], path=rec)
    monkeypatch.setattr(R, "RECORD", rec)
    monkeypatch.setattr("rasterhw.sim.flow.mutate.campaign_all", lambda **k: pytest.fail("ran a campaign"))
    rows = run_report("mutation", out_dir=tmp_path, fast=True)
    dmm = {r["quantity"]: r for r in rows if r["figure"].startswith("experts-dmm ")}
    assert dmm["mutation score"]["measured"] == 0.5 and dmm["killed"]["measured"] == 1
    assert dmm["survived"]["measured"] == 1 and dmm["mutants"]["measured"] == 2
    assert dmm["mutation score"]["source"] == "hdl:verilator"
    zbm = [r for r in rows if r["figure"].startswith("zbm-merger ")]
    assert zbm and all(r["measured"] is None and "Yosys took too long" in r["reason"] for r in zbm)
    assert all(r["source"] == NOT_RUN and r["source_when_run"] == "hdl:verilator" for r in zbm)   # stopped on an error
    # a block of the registry that the record lacks stays, unmeasured, with why, and says nothing ran it
    lacking = [r for r in rows if r["figure"].startswith("pixelbus-bank ")]
    assert lacking and all("not in the record" in r["reason"] and r["source"] == NOT_RUN for r in lacking)
    md = (tmp_path / "mutation.md").read_text()
    assert "| `experts-dmm` | depth 16 | 2 | 1 | 0 | 1 | 0.500 | k-induction, depth 7, passed (latency 3) | — |" in md
    assert "`hdl/experts/dmm.py:76`: inv on $x port Q bit 0" in md
    assert "unproven: the solver did not finish" in md and "bmc, depth 16, passed" in md


def test_without_a_record_every_row_says_how_to_make_one(tmp_path, monkeypatch):
    monkeypatch.setattr(R, "RECORD", tmp_path / "none.json")
    rows, sections = R.rows(out_dir=tmp_path)
    assert rows and sections == []
    assert all(r["measured"] is None and "--rerun" in r["reason"] and r["source"] == NOT_RUN for r in rows)


def test_survivors_show_their_class_and_a_block_that_could_not_be_mutated_is_merged_with_why(tmp_path):
    rec = tmp_path / "mutation_runs.json"
    camp, proofs = _record()
    camp["blocks"][0]["survivors"] = [
        {"mutant": 2, "src": ["hdl/experts/dmm.py:76"], "mutation": "inv on $x port Q bit 0", "reaches": [],
         "reach_class": "unobservable", "equivalence": "equivalent",
         "equivalence_how": "structural: no path to any output"},
        {"mutant": 3, "src": ["hdl/experts/dmm.py:80"], "mutation": "const0 on $y port Y bit 1",
         "reaches": ["words o"], "reach_class": "compared", "equivalence": "not proven",
         "equivalence_why": "Yosys took more than 120 s"}]
    R.write_record(camp, proofs, ["rasterhw mutate --all --mutants 2 --json"], path=rec)
    md = "\n".join(R.sections(R._read(rec)))
    assert "Survivors by class (`sim/flow/reach.py`, computed): unobservable 1, compared 1." in md
    assert "inv on $x port Q bit 0 — **unobservable** (no path to any output)" in md
    assert ("const0 on $y port Y bit 1 — **compared** (reaches words o); equivalence: **not proven**: "
            "Yosys took more than 120 s") in md
    small = {"block": "experts-slp-setup", "error": "Yosys took more than 600 s"}
    R.write_record(camp, proofs, ["x"], path=rec)
    R.merge_blocks([small], ["rasterhw mutate experts-slp-setup ..."], path=rec)
    got = [b for b in R._read(rec)["campaign"]["blocks"] if b["block"] == "experts-slp-setup"]
    assert got and got[0]["error"] == "Yosys took more than 600 s" and got[0]["score"] is None
    assert got[0]["params"] == {"height": 64}
