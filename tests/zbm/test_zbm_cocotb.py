"""cocotb on the generated ZB/M Verilog: units (edge pairs in, merged scan lines out) and one
chip (segments + upstream pixels in), Verilator always, Icarus when ``iverilog`` is on PATH.

Each run uses random idle gaps on every input stream, seeded random back-pressure on every
output stream, a segment:merge clock ratio (half periods in ns), the Python stream checker of
cocotb_tests/common.py on every stream feeding in-order scoreboards (which must end empty),
the Verilog stream checkers, and compares every scan line bit for bit (both samples, Z and
colour) with golden_model/zbm/.  Frames are 64x16.  The unit's Verilator runs are ``slow`` (the
fast suite compares the engine with their committed records, tests/zbm_cocotb/records.py); the
chip's too (tests/zbm_cocotb/chip_records.py); the default set keeps the bench's argument checks and
Table 1 on the plain engine (and the Icarus runs, when ``iverilog`` is on PATH).
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import doublez_words
from zbm_cocotb.chip_bench import run_chip_bench
from zbm_cocotb.chip_records import chip_case
from zbm_cocotb.unit_bench import plusargs, run_unit_bench

pytestmark = pytest.mark.cocotb

SIMS = ["verilator", pytest.param("icarus", marks=pytest.mark.skipif(
    shutil.which("iverilog") is None, reason="iverilog not on PATH"))]
W, H = 64, 16
# (segment, merge) half periods in ns: 1:1, merge slower (3:2 periods), merge faster
RATIOS = [(5, 5), (2, 3), (3, 2)]
#: the first ratio builds the bench (heavy: handed out first, tests/conftest.py); the others reuse it.
#: The unit's cocotb runs on Verilator are all slow (the cocotb unit builds, ~30 s each cold, left
#: the fast suite): there the engine runs the same cases against the cocotb bench's recorded runs
#: (tests/zbm_cocotb/records.py; ratio (5, 5) and the full-rate run: test_zbm_unit_engine.py::
#: test_unit_engine_equals_the_cocotb_record[ratio-5-5-*]; the unequal ratios: test_engine_clocks.py)
HEAVY_FIRST = [pytest.param(RATIOS[0], marks=pytest.mark.heavy), *RATIOS[1:]]
UNIT_RATIOS = [pytest.param(RATIOS[0], marks=[pytest.mark.heavy, pytest.mark.slow]),
               *(pytest.param(r, marks=pytest.mark.slow) for r in RATIOS[1:])]
#: Verilator (slow, see above and below), Icarus when ``iverilog`` is on PATH
UNIT_SIMS = [pytest.param("verilator", marks=pytest.mark.slow), SIMS[1]]


def _scene(seed: int, n: int = 30):
    return random_triangles(np.random.default_rng(seed), n, W, H, size=10)


def _unit_run(sim, interleave, units, ratio, stall, seed):
    tris = _scene(seed)
    gold = G.render_zbm(tris, interleave=interleave, units=units)
    eps = G.edge_pairs(tris)
    per = [eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)]
    exp = doublez_words(gold.pixels)
    r = run_unit_bench(per, width=W, height=H, interleave=interleave, sim=sim, ratio=ratio, stall=stall,
                         seed=seed, gap_seed=seed, expect=exp, check_protocol=True)
    # the cocotb test already compared; check the returned dump here as well
    assert np.array_equal(r["s0"], exp[0]) and np.array_equal(r["s1"], exp[1])
    assert r["proto_errors"] == 0 and r["frames_ok"] and gold.stats["z_writes"] > 0
    return r


@pytest.mark.parametrize("ratio", UNIT_RATIOS)
def test_unit_verilator_ratios(ratio):
    _unit_run("verilator", 2, 1, ratio, stall=80, seed=sum(ratio))


@pytest.mark.parametrize("sim", UNIT_SIMS)
def test_unit_no_gaps_full_rate(sim):
    _unit_run(sim, 2, 1, (5, 5), stall=0, seed=11)


@pytest.mark.slow
@pytest.mark.parametrize("sim", SIMS)
def test_two_chained_units(sim):
    _unit_run(sim, 2, 2, (3, 2), stall=60, seed=4)


def _chip_run(sim, ratio, stall, seed, interleave=4, chip=1):
    seg_w, up_w, exp = chip_case(seed, interleave=interleave, chip=chip)
    r = run_chip_bench(seg_w, up_w, lines=H, chip=chip, interleave=interleave, width=W, sim=sim,
                         ratio=ratio, stall=stall, seed=seed, gap_seed=seed, expect=exp, check_protocol=True)
    assert np.array_equal(r["s0"], exp[0]) and np.array_equal(r["s1"], exp[1])
    assert r["lines"] == H and r["proto_errors"] == 0
    return r


# the chip's cocotb runs on Verilator are slow too: in the fast suite the engine runs each of them at
# the bench's clocks, gaps and back-pressure against the bench's recorded run (tests/zbm_cocotb/
# chip_records.py: tests/zbm/test_zbm_chip_engine.py::test_engine_chip_at_the_cocotb_benchs_clocks_equals_its_record)
@pytest.mark.slow
@pytest.mark.parametrize("ratio", HEAVY_FIRST)
def test_chip_verilator_ratios(ratio):
    _chip_run("verilator", ratio, stall=80, seed=ratio[0] * 7 + ratio[1])


@pytest.mark.parametrize("sim", UNIT_SIMS)
def test_chip_sims(sim):
    _chip_run(sim, (5, 5), stall=40, seed=3)


def test_bench_rejects_bad_settings():
    with pytest.raises(RasterhwError, match="stall"):
        plusargs((5, 5), 300, 1, 10)
    with pytest.raises(RasterhwError, match="clock ratio"):
        plusargs((0, 5), 0, 1, 10)
    with pytest.raises(RasterhwError, match="phase"):
        plusargs((5, 5), 0, 1, 10, phase=2)


@pytest.mark.heavy
@pytest.mark.slow
def test_unit_paper_schedule_verilator_protocol():
    """The paper-schedule unit under random gaps, back-pressure and a 3:2 clock ratio: same words.
    Slow (its own cocotb build, ~35 s cold); in the fast suite the paper schedule's Verilog gives the
    golden words on Verilator (test_table1_paper_schedule_verilator) and its HDL at a 3:2 clock
    ratio under back-pressure with protocol checkers on every stream on pysim
    (tests/zbm/test_zbm_unit_pysim.py::test_units_match_render_zbm[...-paper])."""
    tris = _scene(5)
    gold = G.render_zbm(tris, interleave=2)
    exp = doublez_words(gold.pixels)
    r = run_unit_bench([G.edge_pairs(tris)], width=W, height=H, interleave=2, sim="verilator", ratio=(3, 2),
                         stall=60, seed=5, gap_seed=5, expect=exp, check_protocol=True, schedule="paper")
    assert np.array_equal(r["s0"], exp[0]) and np.array_equal(r["s1"], exp[1]) and r["proto_errors"] == 0


# interleave 1 is slow: its Verilator model differs from the ZB/M report's skew "alone" unit only in
# the frame height (40 lines, the skew's 42), one more build in every fresh run; the fast suite holds
# the same paper-schedule Verilog at interleave 1 giving 74 cycles per edge pair with every merge
# word golden in tests/test_reports_committed.py::test_zbm_report_measures_its_hdl_rows (the skew's
# "alone" run), and the exact model = the formula at 1 on pysim in the same test
@pytest.mark.parametrize("interleave", [pytest.param(1, marks=[pytest.mark.heavy, pytest.mark.slow]),
                                        pytest.param(8, marks=pytest.mark.heavy(2))])
def test_table1_paper_schedule_verilator(interleave):
    """Table 1 from Verilator, paper schedule: 74 / 54 cycles per edge pair (= the paper's formula
    and the exact model), every merge word equal to the golden model's."""
    from rasterhw.golden_model.zbm.cycles import formula_cycles_per_edge_pair
    from rasterhw.sim.zbm.cycles_hdl import measure_table1

    r = measure_table1(interleave, schedule="paper", engine="verilator", n_edge_pairs=4)   # the report's runs
    assert r["mismatches"] == 0
    assert r["per_edge_pair"] == r["model_marginal"] == formula_cycles_per_edge_pair(interleave)


@pytest.mark.slow
@pytest.mark.parametrize("interleave", [1, 8])
def test_table1_overlap_verilator(interleave):
    """Ours on Verilator: 70 / 54 (4 L + max(L, 18)), = the model, golden words."""
    from rasterhw.sim.zbm.cycles_hdl import measure_table1

    r = measure_table1(interleave, schedule="overlap", engine="verilator", n_edge_pairs=4)
    assert r["per_edge_pair"] == r["model_marginal"] == {1: 70, 8: 54}[interleave] and r["mismatches"] == 0


@pytest.mark.slow
def test_chain_scaling_verilator():
    """Chained units on Verilator (the report's runs): golden words, more units -> fewer cycles,
    never below the merge bus's own bound."""
    from rasterhw.sim.zbm.scaling import chain

    a, b = chain(1), chain(2)
    assert a["mismatches"] == b["mismatches"] == 0
    assert b["cycles"] < a["cycles"] and b["cycles"] >= b["merge_bound_cycles"]
    assert 0 < a["merge_occupancy"] < b["merge_occupancy"] <= 1


@pytest.mark.slow
def test_skew_two_neighbours_verilator():
    """Condition 7 simulated: two neighbouring units with offset loads lose less than the paper's half."""
    from rasterhw.sim.zbm.scaling import skew

    s = skew()
    assert s["pair"] >= s["alone"] == 74 and 0 <= s["loss"] < 0.5
