"""Does the stimulus ever activate a mutation (sim/flow/toggle.py): the value each fault needs,
sampled at every clock edge of the unmutated runs; a survivor whose fault is never activated is
``not_exercised`` (a stimulus gap), one that is, ``exercised``."""

from __future__ import annotations

import json
import shutil

import pytest
from rasterhw.sim.flow import mutate as M
from rasterhw.sim.flow import toggle as T
from rasterhw.sim.report.mutation import RECORD


def test_each_mode_needs_its_own_value():
    seen = {1: {0}, 2: {1}, 3: {0, 1}}
    act = lambda mode, bit, ctrl=None: T.activated({"mode": mode, "bit": bit, "ctrl": ctrl}, seen)[0]  # noqa: E731
    assert not act("const0", 1) and act("const1", 1)      # always 0: tying it to 0 changes nothing
    assert act("const0", 2) and not act("const1", 2)      # always 1
    assert act("const0", 3) and act("const1", 3)
    assert act("inv", 1) and act("inv", 2)                # an inversion always changes the bit
    assert not act("cnot1", 3, 1) and act("cnot0", 3, 1)  # cnot1 flips the bit only where its control is 1
    assert act("cnot1", 3, 2) and not act("cnot0", 3, 2)
    assert not act("const0", "0") and act("const1", "0")  # a bit tied to a constant
    assert act("const0", "x") and act("const1", "x")      # an undefined constant: never called a gap
    assert not act("const1", 9)                           # never sampled: never activated


def test_the_probe_samples_both_edges_of_every_clock_and_writes_at_the_end():
    mod = {"ports": {"clocks": {"direction": "input", "bits": [2, 3]}, "status": {"direction": "output", "bits": [4]}}}
    text = "module other(a);\nendmodule\nmodule rasterhw_bench(clocks, status);\n  wire x;\nendmodule\n"
    out = T.probe_verilog(text, mod, 5)
    bench = out.split("module rasterhw_bench(")[1]
    assert "posedge clocks[0] or negedge clocks[0] or posedge clocks[1] or negedge clocks[1]" in bench
    assert "reg [4:0] tgl_seen0" in bench and "final begin" in bench and bench.rstrip().endswith("endmodule")
    assert "tgl" not in out.split("module rasterhw_bench(")[0]


def test_no_killed_mutant_of_the_record_was_never_activated():
    """A mutant whose fault the unmutated runs never activate runs exactly as the block does: no
    check can kill it. Every killed mutant of the record with an ``activated`` was activated, and
    the record has survivors of both classes (the pass tells them apart)."""
    rec = json.loads(RECORD.read_text())["campaign"]["blocks"]
    killed = [k for b in rec for k in b.get("killed_by", []) if "activated" in k]
    assert len(killed) > 100 and all(k["activated"] for k in killed)
    classes = {s.get("exercise") for b in rec for s in b.get("survivors", [])}
    assert {"exercised", "not_exercised"} <= classes
    for b in rec:
        for s in b.get("survivors", []):
            if s.get("reach_class") in ("compared", "uncompared"):
                assert s.get("exercise") in ("exercised", "not_exercised", None)
                if s.get("exercise") == "not_exercised":
                    assert "never" in s["exercise_why"]


def _dff(clk, d, q):
    return {"hide_name": 1, "type": "$dff", "parameters": {"CLK_POLARITY": "1", "WIDTH": "1"}, "attributes": {},
            "port_directions": {"CLK": "input", "D": "input", "Q": "output"},
            "connections": {"CLK": [clk], "D": [d], "Q": [q]}}


@pytest.mark.heavy
def test_a_planted_never_toggling_bit_is_not_activated_and_a_planted_toggling_one_is(tmp_path):
    """pixelbus-bank at its small configuration: two flip-flops planted in its bench's netlist, one
    that holds 0 for ever (``q <= q``, initial 0) and one that toggles every clock (``q <= ~q``).
    Tying the held bit to 0 is never activated, to 1 is; both ties of the toggling bit are."""
    block, p = "pixelbus-bank", M.all_configs()["pixelbus-bank"]
    m = M.mutated_bench(block, p, mutants=30, seed=1)
    M.survivor_reach(block, p, 1, m["dir"], m["mutations"])   # reach.json: the unmutated netlist
    shutil.copy(m["dir"] / "reach.json", tmp_path / "reach.json")
    full = json.loads((tmp_path / "reach.json").read_text())
    mod = full["modules"]["rasterhw_bench"]
    clk = mod["ports"]["clk"]["bits"][0]
    top = max(b for c in mod["cells"].values() for bits in c["connections"].values() for b in bits
              if isinstance(b, int)) + 1000
    hold, tog, ntog = top, top + 1, top + 2
    mod["cells"]["ff_hold"] = _dff(clk, hold, hold)
    mod["cells"]["ff_tog"] = _dff(clk, ntog, tog)
    mod["cells"]["not_tog"] = {"hide_name": 1, "type": "$not", "attributes": {},
                                   "parameters": {"A_SIGNED": "0", "A_WIDTH": "1", "Y_WIDTH": "1"},
                                   "port_directions": {"A": "input", "Y": "output"},
                                   "connections": {"A": [tog], "Y": [ntog]}}
    mod["netnames"]["planted_hold"] = {"hide_name": 0, "bits": [hold], "attributes": {"init": "0"}}
    mod["netnames"]["planted_tog"] = {"hide_name": 0, "bits": [tog], "attributes": {"init": "0"}}
    mod["netnames"]["planted_ntog"] = {"hide_name": 0, "bits": [ntog], "attributes": {}}
    (tmp_path / "reach.json").write_text(json.dumps(full))
    muts = [{"mutant": k, "command": f"mutate -ctrl mutsel 3 {k} -mode {mode} -module rasterhw_bench -cell {cell} "
                                     f"-port Q -portbit 0"}
            for k, mode, cell in ((1, "const0", "ff_hold"), (2, "const1", "ff_hold"),
                                  (3, "const0", "ff_tog"), (4, "const1", "ff_tog"))]
    got = T.activation(block, p, 1, tmp_path, muts)["mutants"]
    assert [got[k]["activated"] for k in (1, 2, 3, 4)] == [False, True, True, True]
    assert "never 1" in got[1]["why"] and "is always 0" in got[1]["why"]


def test_the_page_says_why_each_survivor_lives_and_shows_the_single_all_campaign():
    from rasterhw.sim.report import mutation as R

    surv = [{"mutant": 2, "src": ["hdl/experts/dmm.py:76"], "mutation": "const0 on $x port Q bit 0",
             "reaches": ["words o"], "reach_class": "compared", "exercise": "not_exercised",
             "exercise_why": "the bit is never 1 (always 0): const0 never changes it"},
            {"mutant": 3, "src": ["hdl/experts/dmm.py:80"], "mutation": "inv on $y port Y bit 1",
             "reaches": ["words o"], "reach_class": "compared", "exercise": "exercised",
             "exercise_why": "an inversion changes the bit at every edge"},
            {"mutant": 4, "src": [], "mutation": "inv on $z port Y bit 0", "reaches": [],
             "reach_class": "unobservable", "equivalence": "equivalent",
             "equivalence_how": "structural: no path to any output"}]
    block = {"block": "experts-dmm", "params": {"depth": 16}, "config": "small", "seed": 1, "mutants": 5, "killed": 2,
             "equivalent": 1, "survived": 2, "bounded_equivalent": 0, "score": 0.5, "baseline_passed": True,
             "survivors": surv, "killed_by": [], "yosys_s": 1.5, "build_s": 0.0}
    camp = {"mutants": 5, "seed": 1, "config": "each block's Flow.small", "wall_s": 12.0, "scheduler": "tcp://x:1",
            "computed": 6, "reused": 0, "blocks": [block]}
    record = {"commands": ["x"], "campaign": camp, "proofs": {"blocks": []}}
    md = "\n".join(R.sections(record))
    assert "| `experts-dmm` | 0.500 | 2 | 1 | 1 | 0 |" in md
    assert "| all | | 2 | 1 | 1 | 0 |" in md
    assert ("const0 on $x port Q bit 0 — **compared** (reaches words o); **not exercised**: the bit is never 1 "
            "(always 0): const0 never changes it") in md
    assert "Under the stimulus (`sim/flow/toggle.py`, computed on mutant 0's runs): not exercised 1, exercised 1." in md
    run = {"command": "rasterhw mutate --all --mutants 5", "commit": "abc1234", "notes": ["Load 8."],
           "time": {"wall_s": 600.0, "user_s": 900.0, "sys_s": 50.0, "max_rss_mb": 700.0},
           "result": {**camp, "blocks": [{**block, "score": 0.6}]}}
    md = "\n".join(R.all_section(run, record))
    assert "Wall time 600 s (10.0 min), CPU 900 s user + 50 s system" in md and "Load 8." in md
    assert "| `experts-dmm` | 0.600 | 0.500 | 2 | 1 | 2 | 1 | 1 | 2 | 0 |" in md
    assert "#### `experts-dmm` (0.600; 2 survived of 5)" in md and "mutant 4" not in md   # equivalent: not listed


@pytest.mark.heavy
def test_mutate_all_gives_every_survivor_its_exercise_and_every_killed_mutant_was_activated(tmp_path):
    r = M.campaign_all(mutants=4, seed=1, blocks=["zbm-merger"], store=tmp_path)
    b = r["blocks"][0]
    assert b["baseline_passed"] and b["toggle_build_s"] >= 0 and "toggle_error" not in b
    assert b["killed_by"] and all(k["activated"] for k in b["killed_by"])
    alive = [s for s in b["survivors"] if s.get("equivalence") != "equivalent"]
    assert all(s["exercise"] in ("exercised", "not_exercised") and s["exercise_why"] for s in alive)


def test_the_bank_bench_orders_writes_and_commands_and_its_golden_model_applies_them():
    """pixelbus-bank's testbench (sim/snu/testbench.py): CLEAR and SWAP in the one ordered stream,
    both buffers read out; on pysim the words and the cycle count equal the golden model's, and a
    model that ignored the commands would not."""
    import numpy as np
    from rasterhw.golden_model.snu.pixelstream import PixelStream
    from rasterhw.sim.engines import run
    from rasterhw.sim.snu.testbench import CLEAR, SWAP, bank_frame
    from rasterhw.sim.testbench import compare, find_testbench

    tb = find_testbench("pixelbus-bank")
    p = tb.params(depth=16)
    rng = np.random.default_rng(7)
    n = 30
    s = PixelStream(16, 1, rng.integers(0, 16, n), rng.integers(0, 1 << 24, n), rng.integers(0, 8, n),
                    np.zeros(n, np.int64))
    cmds = [(5, SWAP), (5, CLEAR), (20, SWAP), (n, CLEAR)]
    stim = tb.stimulus_of(p, s, rng.integers(0, 4, n), commands=cmds)
    exp = tb.expect(p, stim)
    r = run(tb, p, stim, engine="pysim", expect_words={"o": 32})
    c = compare(exp, r, cycle_exact=True)
    assert c["mismatches"] == 0 and c["cycle_mismatches"] == 0 and r.protocol_errors == 0
    rgb, z, draw = bank_frame(16, s, cmds)
    assert draw == 0 and not rgb[0].any() and not z.any() and rgb[1].any()   # the last CLEAR: draw buffer black
    plain = tb.expect(p, tb.stimulus_of(p, s, rng.integers(0, 4, n)))
    assert plain.words["o"] != exp.words["o"] and plain.cycles < exp.cycles


def test_a_mutation_of_a_constant_bit_to_its_own_value_is_equivalent_and_leaves_the_score():
    from rasterhw.sim.flow.toggle import CONSTANT

    mod = {"cells": {"c": {"connections": {"A": ["0", 5], "Y": [6]}}}}
    t = T.targets(mod, "mutate -mode const0 -cell c -port A -portbit 0")
    assert t["bit"] == "0" and T.activated(t, {})[0] is False
    mu = {"mutant": 1, "src": ["hdl/x.py:1"], "mutation": "const0 on c port A bit 0"}
    act = {1: {"activated": False, "why": "the bit is never 1 (it is tied to constant 0)", "constant": True}}
    got = M._survivor({"mutant": 1}, mu, None, {"reaches": {1: ["words o"]}, "compared": ["o"]}, act)
    assert got["equivalence"] == "equivalent" and got["equivalence_how"] == CONSTANT
    act[1].pop("constant")   # the same value never taken under the stimulus only: a gap, not an equivalence
    got = M._survivor({"mutant": 1}, mu, None, {"reaches": {1: ["words o"]}, "compared": ["o"]}, act)
    assert "equivalence" not in got and got["exercise"] == "not_exercised"
    res = M._summary("b", {}, 1, [mu], [{"mutant": 0, "killed": False, "why": ""}, {"mutant": 1, "killed": False,
                                                                                      "why": ""}],
                     None, {"reaches": {1: ["words o"]}, "compared": ["o"]},
                     {"mutants": {"1": {**act[1], "constant": True}}})
    assert res["equivalent"] == 1 and res["survived"] == 0 and res["score"] is None
