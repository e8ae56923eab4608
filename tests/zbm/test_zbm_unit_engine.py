"""The ``zbm-unit`` testbench on the generic Verilator engine (``rasterhw.sim.zbm.scene.run_scene``,
what ``rasterhw sim zbm --engine verilator``, the bench and the soak run; its speed Verilog) against
the cocotb unit bench (``run_unit_bench`` with equal, in-phase clocks) and the golden model: the same
frame bit for bit, the same segment-clock cycle count and per-line log, under random idle gaps and
back-pressure. Cold: one engine build (g++ -O1, ~30 s). One-unit cases compare with the cocotb
bench's committed records (``tests/zbm_cocotb/records.py``); the two-unit chains (slow) run it. (Was test_zbm_unit_fast.py, on the plain bench ``sim/zbm/fast.py``.)"""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import doublez_words
from rasterhw.sim.zbm.scene import run_scene
from rasterhw.sim.zbm.testbench import unit_watchdog
from zbm_cocotb import records as R
from zbm_cocotb.stimfiles import stimulus_depth
from zbm_cocotb.unit_bench import run_unit_bench

pytestmark = pytest.mark.cocotb

W, H = 64, 16


def _compare(units: int, stall: int, gap_seed, seed: int, schedule: str = "overlap"):
    tris = random_triangles(np.random.default_rng(seed), 30, W, H, size=10)
    gold = doublez_words(G.render_zbm(tris, interleave=2, units=units).pixels)
    eps = G.edge_pairs(tris)
    per = [eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)]
    fast = run_scene(per, width=W, height=H, interleave=2, stall=stall, seed=seed, gap_seed=gap_seed,
                     line_log=True, build={"speed": True, "opt": "-O1"}, schedule=schedule)
    ref = run_unit_bench(per, width=W, height=H, interleave=2, sim="verilator", ratio=(5, 5), phase=0,
                           stall=stall, seed=seed, gap_seed=gap_seed, speed_run=True, line_log=True,
                           schedule=schedule)
    assert np.array_equal(fast["s0"], gold[0]) and np.array_equal(fast["s1"], gold[1])
    assert np.array_equal(ref["s0"], gold[0]) and np.array_equal(ref["s1"], gold[1])
    assert fast["cycles"] == ref["cycles"] > H
    assert fast["line_cycles"] == ref["line_cycles"]
    assert fast["proto_errors"] == 0 and fast["frames_ok"] == 1 and fast["overflow"] == 0
    return fast


@pytest.mark.parametrize("case", ["eq-s0-11", "eq-s90-g7-101", "ratio-5-5-s80-g10", "ratio-5-5-s0-g11"])
def test_unit_engine_equals_the_cocotb_record(case):
    """The golden frame, and the cocotb bench's cycle count, per-line log and frame as recorded
    (``tests/zbm_cocotb/unit_records.json``; held equal to cocotb's runs by the slow
    test_zbm_unit_records.py). Was a cocotb run beside each engine run. The two ``ratio-5-5``
    cases are the runs of test_zbm_cocotb.py's test_unit_verilator_ratios[ratio0] (random gaps,
    back-pressure 80) and test_unit_no_gaps_full_rate[verilator] (no back-pressure), now slow:
    the same scene, seeds and clocks (half periods 5 : 5, the merge clock 1 ns behind)."""
    R.check_engine(case)


def test_unit_engine_backpressure_costs_cycles():
    free = R.check_engine("eq-s0-3")
    slow = R.check_engine("eq-s120-3")
    assert slow["cycles"] > free["cycles"]


@pytest.mark.slow
@pytest.mark.parametrize("schedule", ["overlap", "paper"])
def test_two_units_engine_equals_cocotb_bench(schedule):
    """Chains (the report's chain and skew rows run on the plain bench): the same words, cycles and
    per-line log as the cocotb bench, in both schedules."""
    _compare(2, 40, 5, seed=4, schedule=schedule)


def test_unit_engine_rejects_bad_stall():
    with pytest.raises(RasterhwError, match="stall"):
        run_scene([G.edge_pairs(random_triangles(np.random.default_rng(1), 3, W, H))], width=W, height=H,
                  interleave=2, stall=300)


def test_stimulus_depth_shared_by_runs_of_different_sizes():
    assert stimulus_depth(10) == 1024 and stimulus_depth(5000) == 8192
    assert stimulus_depth(10, 16384) == stimulus_depth(9000, 16384) == 16384
    with pytest.raises(RasterhwError, match="does not hold"):
        stimulus_depth(9000, 4096)


def test_watchdog_covers_heavy_backpressure_and_a_slow_merge_clock():
    """Soak seed 20261203 round 1100: stall 254 (ready high 2 clocks in 256) with the merge clock
    1.4 x slower than the segment clock (half periods 5 : 7) outran the cocotb bench's watchdog,
    which had no term for either (the plain bench's had one for the stall only; the engine run uses it). Here a small frame
    with a merge clock 3.5 x slower (2 : 7): it finishes, every word golden, past the old budget
    and inside the shared watchdog. The run is the engine's at the cocotb bench's clocks, equal to
    cocotb's recorded run of it (case ``ratio-2-7-s254``: cycles, per-line log, frame), which the
    slow test_zbm_unit_records.py runs on the cocotb bench again (was a cocotb run here)."""
    eps, gold = R.scene("ratio-2-7-s254")
    total = len(eps[0]) * 9 + 1
    r = R.check_engine("ratio-2-7-s254")   # the golden frame, cocotb's recorded cycles and per-line log
    old = 200 * (total + 64) + 40 * H * (W + 64)          # the cocotb bench's watchdog before
    assert old < r["cycles"] < unit_watchdog(total, width=W, height=H, stall=254, ratio=(2, 7))
    assert unit_watchdog(total, width=W, height=H) == old   # unchanged for free-running runs
    fast = run_scene(eps, width=W, height=H, interleave=2, stall=255, seed=3, build={"speed": True, "opt": "-O1"})
    assert np.array_equal(fast["s0"], gold[0])
