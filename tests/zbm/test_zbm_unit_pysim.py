"""Pysim tests of ZB/M units (segment generator + chips), chained by merge ports, against
golden_model.zbm.render_zbm; and the cycles-per-edge-pair measurement of Table 1."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import cycles as C
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import edge_pair_words, pixel2_words
from rasterhw.hdl.zbm.chain import ZbmChain
from rasterhw.hdl.zbm.unit import ZbmUnit
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put
from zbm_unit_cycles import measure_cycles_per_edge_pair, run_unit_cycles

pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


def run_units(units, words_per_unit, n_lines, *, merge_period=1e-8, stall_p=0.0, seed=0,
              max_cycles=200_000):
    top = ZbmChain(units)
    sim = Simulator(top)
    sim.add_clock(1e-8, domain="sync")
    sim.add_clock(merge_period, domain="merge")
    last = units[-1]
    got = {c: [] for c in range(last.interleave)}
    need = {c: last.chip_pixels(c) * n_lines for c in range(last.interleave)}

    def src(u, words):
        async def bench(ctx):
            for w in words:
                await stream_put(ctx, u.i, w)
        return bench

    async def sink(ctx):      # samples at the clock edge, random back-pressure
        rng = np.random.default_rng(seed)
        n = 0
        sigs = []
        for c in got:
            sigs += [last.o_merge[c].valid, last.o_merge[c].payload]
        while any(len(got[c]) < need[c] for c in got):
            rdy = {c: rng.random() >= stall_p for c in got}
            for c in got:
                ctx.set(last.o_merge[c].ready, rdy[c])
            _, _, *vals = await ctx.tick("merge").sample(*sigs)
            n += 1
            assert n < max_cycles, "timeout"
            for i, c in enumerate(got):
                if vals[2 * i] and rdy[c]:
                    got[c].append(vals[2 * i + 1].as_value().value)

    for u, words in zip(units, words_per_unit, strict=True):
        sim.add_testbench(src(u, words), background=True)
    for c in range(last.interleave):
        sim.add_testbench(stream_protocol_checker(last.o_merge[c], f"o_merge[{c}]", domain="merge"), background=True)
    for k, u in enumerate(units):
        sim.add_testbench(stream_protocol_checker(u.i, f"unit{k}.i"), background=True)
    sim.add_testbench(sink)
    sim.run()
    return got


# the last case: the paper schedule with the merge clock at 2/3 of the segment clock's period (the
# 3:2 half periods of test_zbm_cocotb.py::test_unit_paper_schedule_verilator_protocol, now slow)
@pytest.mark.parametrize("interleave,n_units,merge_period,schedule",
                         [(2, 1, 1e-8, "overlap"), (4, 2, 1.9e-8, "overlap"), (2, 1, 1e-8, "paper"),
                          (4, 2, 1.9e-8, "paper"), (2, 1, 2e-8 / 3, "paper")])
def test_units_match_render_zbm(interleave, n_units, merge_period, schedule):
    w, h = 32, 10
    rng = np.random.default_rng(interleave)
    tris = random_triangles(rng, 8, w, h, size=8)
    res = G.render_zbm(tris, interleave=interleave, units=n_units)
    eps = G.edge_pairs(tris)
    units = [ZbmUnit(interleave=interleave, width=w, height=h, head=(k == 0), schedule=schedule)
             for k in range(n_units)]
    words = [edge_pair_words(eps.take(np.flatnonzero(eps.tag % n_units == k))) for k in range(n_units)]
    got = run_units(units, words, h, merge_period=merge_period, stall_p=0.3)
    exp_all = np.array(pixel2_words(res.pixels), dtype=object).reshape(h, w)
    for c in range(interleave):
        exp = [int(v) for v in exp_all[:, c::interleave].ravel()]
        assert got[c] == exp, c
    assert res.stats["z_writes"] > 0


def test_unit_bad_parameters():
    with pytest.raises(ValueError, match="interleave must be 1, 2, 4, 8 or 16, not 5"):
        ZbmUnit(interleave=5)
    with pytest.raises(ValueError, match="schedule must be 'overlap' or 'paper', not 'fast'"):
        ZbmUnit(interleave=2, width=16, schedule="fast")


@pytest.mark.parametrize("interleave,seed,schedule,mode", [
    (1, 0, "overlap", F.MODE_COLOUR), (2, 1, "overlap", F.MODE_COLOUR), (8, 2, "overlap", F.MODE_COLOUR),
    (1, 0, "paper", F.MODE_COLOUR), (2, 1, "paper", F.MODE_MAPPING), (8, 2, "paper", F.MODE_COLOUR)])
def test_cycle_model_is_exact(interleave, seed, schedule, mode):
    """HDL cycles == golden_model.zbm.cycles.hdl_cycles on random small streams (empty and
    clipped segments, several pairs per line, loads on many lines), both schedules."""
    w, h = 8 * interleave if interleave > 1 else 24, 10
    rng = np.random.default_rng(seed)
    eps = G.edge_pairs(random_triangles(rng, 6, w, h, size=10))
    if mode == F.MODE_MAPPING:      # cycles do not depend on the channel values: 6 zero channels
        z = np.zeros((len(eps), len(F.CHANNELS[mode])), np.int64)
        eps = dataclasses.replace(eps, mode=mode, val=z, ddy=z.copy(), ddx=z.copy())
    model = C.hdl_cycles(eps, h, width=w, interleave=interleave, schedule=schedule)
    assert G.max_active_edge_pairs(eps)[0] >= 2 and len(eps) >= 5 and model["generator"]["empty"] > 0
    hdl = run_unit_cycles(eps, h, width=w, interleave=interleave, schedule=schedule)
    assert hdl["overflow"] == 0 and hdl["lines"] == h
    assert hdl["cycles"] == model["cycles"], (hdl, model)


# interleave 8 in the default set runs on Verilator (tests/zbm/test_zbm_cocotb.py::
# test_table1_paper_schedule_verilator[8], the same design and check); its pysim run is slow-only
@pytest.mark.parametrize("interleave", [1, pytest.param(8, marks=pytest.mark.slow),
                                        pytest.param(16, marks=pytest.mark.slow)])
def test_paper_schedule_table1(interleave):
    """Paper schedule: HDL steady state = the paper's 9 + (len_chip + 8) * 5 exactly."""
    a = measure_cycles_per_edge_pair(interleave, n_edge_pairs=2, schedule="paper")
    b = measure_cycles_per_edge_pair(interleave, n_edge_pairs=3, schedule="paper")
    assert a["cycles"] == a["model_cycles"] and b["cycles"] == b["model_cycles"]
    assert b["cycles"] - a["cycles"] == C.formula_cycles_per_edge_pair(interleave) == {1: 74, 8: 54, 16: 54}[interleave]


def test_unit_overflow_flag():
    """Over capacity the unit stops with ``overflow`` instead of finishing the frame."""
    eps = C.paper_workload(3, lines_apart=1, width=16)          # 3 pairs active on line 2
    assert G.max_active_edge_pairs(eps) == (3, 2)
    hdl = run_unit_cycles(eps, 8, width=16, interleave=2, capacity=2, max_cycles=400)
    assert hdl["overflow"] == 1 and hdl["lines"] <= 2
    ok = run_unit_cycles(eps, 8, width=16, interleave=2, capacity=3)
    assert ok["overflow"] == 0 and ok["lines"] == 8
    assert ok["cycles"] == C.hdl_cycles(eps, 8, width=16, interleave=2, capacity=3)["cycles"]


def test_cycles_per_edge_pair_interleave_8():
    """The report's measurement: HDL == model; steady state 4 (len_chip + 8) + 18 (docs/zbm.md)."""
    r = measure_cycles_per_edge_pair(8, n_edge_pairs=3)
    assert r["cycles"] == r["model_cycles"]
    assert r["marginal_cycles_per_edge_pair"] == 4 * (1 + 8) + 18


@pytest.mark.slow
@pytest.mark.parametrize("interleave", F.INTERLEAVES)
def test_cycles_per_edge_pair_sweep(interleave):
    r = measure_cycles_per_edge_pair(interleave)
    print(r)
    assert r["cycles"] == r["model_cycles"]
    lc = -(-5 // interleave)
    assert r["marginal_cycles_per_edge_pair"] == 4 * (lc + 8) + max(lc + 8, 18)


if __name__ == "__main__":    # python tests/zbm/test_zbm_unit_pysim.py -> the Table 1 measurement
    for i in F.INTERLEAVES:
        print(measure_cycles_per_edge_pair(i))


def test_line_log_steady_state_equals_model():
    """measure_table1's one-run steady state (pysim) == the model's marginal, both schedules, I = 2."""
    from rasterhw.sim.zbm.cycles_hdl import measure_table1

    for sched, want in (("paper", 64), ("overlap", 62)):
        r = measure_table1(2, schedule=sched, n_edge_pairs=2)
        assert r["per_edge_pair"] == r["model_marginal"] == want
        # every merge word of the frame compared on pysim too (issue 46): 20 lines x 8 pixels
        assert r["words_compared"] == 20 * 8 and r["mismatches"] == 0


@pytest.mark.parametrize("interleave,width", [(1, 32), (4, 32),
                                             # the report's rows that a fast report leaves unmeasured
                                             pytest.param(8, 128, marks=pytest.mark.slow),
                                             pytest.param(16, 128, marks=pytest.mark.slow)])
def test_pixel_rate_scales_with_interleave(interleave, width):
    """Merge-bound lines: a chip sends its ceil(W / I) pixels per line plus 2 cycles of swap and
    reader start, so the unit's output rate is W / (W / I + 2) pixels per clock."""
    from rasterhw.sim.zbm.scaling import pixel_rate

    r = pixel_rate(interleave, width=width, height=10)
    assert r["cycles_per_line"] == -(-width // interleave) + 2
    assert r["pixels_per_cycle"] == pytest.approx(width / (-(-width // interleave) + 2))
