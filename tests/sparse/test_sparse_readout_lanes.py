# amaranth: UnusedElaboratable=no
"""The frame bench's wide read-out (``Matrix(wide_read=True)``, ``hdl/sparse/benchread.py``; ours,
not the paper's video controller): ``lanes`` sparse addresses a clock from every processor, so the
bench's clocks after the frame are ``ceil(2**(2n) / lanes)`` plus its counter words and a few
clocks of hand-over -- issue 51 item 2 (``rasterhw sim sparse``'s ``sim_cycles`` within 1.5x the
frame's). The block as the hardware flow takes it has no such port."""

from __future__ import annotations

import math

import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.sim.engines import run
from rasterhw.sim.sparse.testbench import READ_LANES, MatrixFrameBench
from rasterhw.sim.testbench import compare

#: bench clocks besides the frame, the raster's words and the counter words: the config word's
#: clock and the hand-over from the frame to the read-out (one clock of read latency)
HANDOVER = 4


def bound(params: dict, frame: int, lanes: int) -> int:
    """The most bench clocks a frame of ``frame`` cycles may take with ``lanes`` read lanes."""
    from rasterhw.hdl.sparse.cell import cell_stats

    counters = 2 + params["p"] * params["q"] * len(cell_stats(params["n"]))
    return frame + math.ceil((1 << (2 * params["n"])) / lanes) + counters + HANDOVER


def test_wide_readout_costs_the_raster_over_the_lanes_and_the_one_lane_one_does_not_fit():
    """pysim, 2x2 processors of 8x8 sparse pixels (64 sparse addresses): the same frame read out
    at ``READ_LANES`` and at one lane (the read-out as first built): both bit-exact against the
    golden model and the coupled cycle model, the same frame cycles; the ``READ_LANES`` run within
    :func:`bound`, the one-lane run beyond it (so the bound can fail), the difference exactly the
    read-out's clocks saved."""
    tris = random_triangles(16, 16, 12, mean_area=16.0, seed=5)
    got = {}
    for lanes in (READ_LANES, 1):
        tb = MatrixFrameBench("inline", lanes=lanes)
        p = tb.params(n=3, p=2, q=2, in_depth=4)
        stim = tb.frame(tris, p, 2)
        exp = tb.expect(p, stim)
        r = run(tb, p, stim, engine="pysim", expect_words={"o": len(exp.words["o"])})
        assert compare(exp, r)["mismatches"] == 0
        got[lanes] = (r.cycles, tb.decode(p, r.words["o"])["cycles"])
    (wide, frame), (one, frame1) = got[READ_LANES], got[1]
    assert READ_LANES > 1 and frame == frame1 > 12
    assert wide <= bound(p, frame, READ_LANES) < one
    assert one - wide == 64 - 64 // READ_LANES
    assert one <= bound(p, frame, 1)


def test_lanes_are_checked_and_the_flow_block_has_no_bench_port():
    from rasterhw.hdl.sparse.benchread import check_lanes
    from rasterhw.hdl.sparse.cell import MatrixCell
    from rasterhw.hdl.sparse.matrix import Matrix

    for bad in (3, -1, True, 1.0, 128):
        with pytest.raises(ValueError, match="read_lanes"):
            check_lanes(7, bad)
    with pytest.raises(ValueError, match="read_lanes"):
        check_lanes(1, 8)                        # more lanes than the 4 sparse addresses
    assert [check_lanes(3, k) for k in (0, 1, 2, 64)] == [0, 0, 1, 6]
    with pytest.raises(ValueError, match="lanes"):
        MatrixFrameBench(lanes=3)
    with pytest.raises(ValueError, match="lanes"):
        MatrixFrameBench(lanes=16).pixel_words({"n": 1, "p": 2, "q": 2})
    flow = Matrix(n=3, in_depth=4, cells="instance")
    assert not {"rd_addr", "rd_words", "rdw_addr", "rdw_data"} & set(flow.signature.members)
    cell = MatrixCell(n=3, p=2, q=2, in_depth=4)
    cell._MustUse__silence = cell._vp._MustUse__silence = True    # only its ports are looked at
    assert not {"rdw_addr", "rdw_data"} & set(cell.signature.members)
    bench = Matrix(n=3, in_depth=4, wide_read=True, read_lanes=4, cells="instance")
    assert len(bench.rd_addr) == 6 - 2 and len(bench.rd_words) == 4 * 4 * bench.lane_bits
    with pytest.raises(ValueError, match="read_lanes"):
        Matrix(n=3, wide_read=True, read_lanes=0)


def test_verilator_sim_cycles_within_the_bound():
    """On Verilator (the design the matrix and colour tests build: 2x2, colour, k_p = 4), the scene
    run's ``sim_cycles`` within :func:`bound` of its frame at ``READ_LANES`` lanes, 0 mismatches."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    tris = random_triangles(32, 32, 40, mean_area=40.0, seed=7)
    r = simulate_coupled(tris, "2x2", fifo_depth=64, colour=True, kp=4)
    assert r["mismatches"] == 0 and r["colour_mismatches"] == 0 and r["cycle_mismatches"] == 0
    p = {"n": r["n"], "p": 2, "q": 2}
    assert r["frame_cycles"] < r["sim_cycles"] <= bound(p, r["frame_cycles"], READ_LANES) < bound(p, r["frame_cycles"], 1)
