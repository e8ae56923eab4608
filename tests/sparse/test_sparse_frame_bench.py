"""The frame testbenches of ``rasterhw sim sparse`` on the generic engines (sim/sparse/testbench.py:
``MatrixFrameBench``, the whole matrix; ``ProcessorBench``, one processor): in pysim, every output word
-- the image and every counter -- equal to the golden search and the golden cycle models, with
the run-time settings (the input FIFOs' limit, the processor's place) in a config word."""

from __future__ import annotations

from dataclasses import replace

import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.sim.engines import run
from rasterhw.sim.sparse.testbench import READ_LANES, MatrixFrameBench, ProcessorBench
from rasterhw.sim.testbench import compare


@pytest.mark.parametrize(("vp", "colour", "kp", "limit", "readout"),
                         [("pipeline", False, 0, 1, "wide"), ("stack", True, 4, 2, "wide"),
                          ("pipeline", False, 0, 1, "port"), ("stack", True, 4, 2, "port")])
def test_frame_bench_words_and_counters_equal_golden(vp, colour, kp, limit, readout):
    tb = MatrixFrameBench("inline", readout=readout)
    p = tb.params(n=2, p=2, q=2, in_depth=4, vp=vp, colour=colour, kp=kp)
    tris = random_triangles(8, 8, 10, mean_area=10.0, seed=4)
    stim = tb.frame(tris, p, limit)
    exp = tb.expect(p, stim)
    want = {"o": len(exp.words["o"])}
    got = run(tb, p, stim, engine="pysim", expect_words=want)
    c = compare(exp, got)
    # the raster: 64 pixels through the port, or 16 sparse addresses of 4 processors each, READ_LANES a word
    wide = 16 // READ_LANES
    assert READ_LANES > 1 and c["mismatches"] == 0
    assert c["ports"]["o"]["words"] == (64 if readout == "port" else wide) + 2 + 4 * 8
    h = tb.decode(p, got.words["o"])
    assert h["stall_cycles"] > 0 and h["stats"]["fifo_peak"].max() == limit
    assert (h["rgb"] is not None) == colour and (h["tri"] >= 0).sum() > 10
    # the counters are compared: the golden model of another limit differs
    other = tb.expect(p, replace(stim, source={**stim.source, "limit": 4}))
    assert compare(other, got)["mismatches"] > 0
    if readout == "wide":   # the same frame through the port: the same raster, 64 - 16 / READ_LANES clocks more
        tp = MatrixFrameBench("inline", readout="port")
        gp = run(tp, p, stim, engine="pysim", expect_words={"o": 64 + 2 + 4 * 8})
        hp = tp.decode(p, gp.words["o"])
        assert (hp["tri"] == h["tri"]).all() and (hp["zq"] == h["zq"]).all() and hp["cycles"] == h["cycles"]
        assert gp.cycles - got.cycles == 64 - wide


def test_processor_bench_words_cycles_and_place_equal_golden():
    tb = ProcessorBench()
    p = tb.params(n=3, p=2, q=2)
    tris = random_triangles(16, 16, 12, mean_area=20.0, seed=6)
    for a, b in ((0, 0), (1, 1)):
        stim = tb.frame(tris, p, a, b)
        exp = tb.expect(p, stim)
        got = run(tb, p, stim, engine="pysim", expect_words={"o": len(exp.words["o"])})
        assert compare(exp, got)["mismatches"] == 0
        h = tb.decode(p, got.words["o"])
        assert h["cycles"] > 12 and sum(h["tests"]) > 0 and h["writes"] > 0
    # another processor's golden words differ from this run's: the place is taken from the config word
    assert compare(tb.expect(p, tb.frame(tris, p, 0, 1)), got)["mismatches"] > 0
