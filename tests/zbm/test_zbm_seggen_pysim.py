"""Pysim tests of the ZB/M segment generator against golden_model.zbm.segment_generator."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import edge_pair_words, segment_words
from rasterhw.hdl.zbm.seggen import ZbmSegmentGenerator
from rasterhw.sim.engines.harness import random_gap, stream_protocol_checker, stream_put

pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


def run_seggen(dut, words, n_out, *, idle_p=0.0, stall_p=0.0, seed=0, cycles=200_000):
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    rng = np.random.default_rng(seed)
    got = []

    async def src(ctx):
        for w in words:
            await stream_put(ctx, dut.i, w, gap=random_gap(rng, idle_p))

    async def sink(ctx):
        held = None
        for _ in range(cycles):      # a hang fails instead of running forever
            if len(got) >= n_out:
                break
            ready = rng.random() >= stall_p
            ctx.set(dut.o.ready, ready)
            _, _, valid, payload = await ctx.tick().sample(dut.o.valid, dut.o.payload)
            if held is not None:     # valid held and payload stable until accepted
                assert valid and payload == held
            held = payload if (valid and not ready) else None
            if valid and ready:
                got.append(payload)

    sim.add_testbench(src, background=True)
    sim.add_testbench(stream_protocol_checker(dut.o, "o"), background=True)
    sim.add_testbench(sink)
    sim.run()
    assert len(got) == n_out, f"timeout: {len(got)} of {n_out} words"
    return got


def _capacity(eps, which):
    need, _ = G.max_active_edge_pairs(eps)
    return {"big": 256, "exact": need}[which]


@pytest.mark.parametrize("mode,capacity,idle_p,stall_p", [
    (F.MODE_COLOUR, "big", 0.0, 0.0), (F.MODE_MAPPING, "big", 0.3, 0.3), (F.MODE_COLOUR, "exact", 0.1, 0.5)])
def test_seggen_matches_golden(mode, capacity, idle_p, stall_p):
    w, h = 48, 24
    rng = np.random.default_rng(mode + len(capacity))
    tris = random_triangles(rng, 10, w, h)
    eps = G.edge_pairs(tris, mode=mode)
    cap = _capacity(eps, capacity)
    segs = G.segment_generator(eps, h, width=w, capacity=cap)
    assert segs.stats["segments"] > 20 and segs.stats["aep_max"] <= cap
    exp = [wd for y in range(h) for wd in segment_words(segs, y)]
    dut = ZbmSegmentGenerator(width=w, height=h, capacity=cap)
    got = run_seggen(dut, edge_pair_words(eps), len(exp), idle_p=idle_p, stall_p=stall_p, seed=mode)
    assert got == exp


def test_seggen_overflow_stalls_without_loss():
    """One pair more than the memory holds: every line before the overflow line comes out
    exactly, then nothing (no incomplete line), ``overflow`` is set and the FIFO fills."""
    w, h = 48, 24
    rng = np.random.default_rng(5)
    eps = G.edge_pairs(random_triangles(rng, 10, w, h))
    need, line = G.max_active_edge_pairs(eps)
    with pytest.raises(RasterhwError, match=f"line {line} needs {need}"):
        G.segment_generator(eps, h, width=w, capacity=need - 1)
    segs = G.segment_generator(eps, h, width=w)
    exp = [wd for y in range(line) for wd in segment_words(segs, y)]
    dut = ZbmSegmentGenerator(width=w, height=h, capacity=need - 1)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got, state = [], {}

    async def src(ctx):
        for wd in edge_pair_words(eps):
            await stream_put(ctx, dut.i, wd)

    async def sink(ctx):
        ctx.set(dut.o.ready, 1)
        for _ in range(3000):
            _, _, valid, payload, ovf = await ctx.tick().sample(dut.o.valid, dut.o.payload, dut.overflow)
            if valid:
                got.append(payload)
            if ovf and "at" not in state:
                state["at"] = len(got)
        state["ready"] = ctx.get(dut.i.ready)
        state["ovf"] = ctx.get(dut.overflow)
        state["line"] = ctx.get(dut.line)

    sim.add_testbench(src, background=True)
    sim.add_testbench(stream_protocol_checker(dut.o, "o"), background=True)
    sim.add_testbench(sink)
    sim.run()
    assert state["ovf"] == 1 and state["line"] == line
    assert got == exp and state["at"] == len(exp)
    assert state["ready"] == 0                           # back-pressure: the loader holds its FIFO


def test_seggen_bad_parameters():
    with pytest.raises(ValueError, match="height must be 1..512, not 0"):
        ZbmSegmentGenerator(height=0)
    with pytest.raises(ValueError, match="capacity"):
        ZbmSegmentGenerator(capacity=0)
