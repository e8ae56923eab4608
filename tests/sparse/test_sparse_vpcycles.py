"""The video processor's cycle model (golden_model/sparse/vpcycles.py) against the HDL processor in
Amaranth pysim, cycle by cycle: the cycle each record is taken, the stage counters, the last busy cycle."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.vpcycles import VPCycleModel, vp_standalone, vp_streams


def _pysim_bench(tris, *, n, p, q, a, b, fifo_depth, offer):
    """The Verilator bench's protocol in pysim: ``valid`` on the cycles ``offer`` allows while records
    remain, one more cycle after the last is taken, then until ``busy`` is low (that cycle counted)."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.sparse.vp import VideoProcessor

    recs = broadcast_records(tris)
    dut = VideoProcessor(n=n, p=p, q=q, z_bits=tris.z_bits, fifo_depth=fifo_depth)
    res = {}

    async def bench(ctx):
        ctx.set(dut.a, a)
        ctx.set(dut.b, b)
        acc, c, idx = [], 0, 0
        while idx < len(recs):
            v = bool(offer(c))
            ctx.set(dut.i.payload, recs[idx])
            ctx.set(dut.i.valid, v)
            if v and ctx.get(dut.i.ready):
                acc.append(c)
                idx += 1
            await ctx.tick()
            c += 1
        ctx.set(dut.i.valid, 0)
        await ctx.tick()
        c += 1
        while ctx.get(dut.busy):
            await ctx.tick()
            c += 1
        res.update(cycles=c + 1, accept=acc, tests=[int(ctx.get(getattr(dut, f"tests_{i}"))) for i in range(1, n + 1)],
                   stalls=[int(ctx.get(getattr(dut, f"stalls_{i}"))) for i in range(1, n + 1)])

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return res


def _model(tris, *, p, q, a, b, fifo_depth, offer):
    f = sparse_render(tris, (p, q), depth="fixed", trace=True)
    vp = VPCycleModel(*vp_streams(f, b * p + a), fifo_depth=fifo_depth)
    acc, c, idx = [], 0, 0
    while idx < f.triangles:
        if vp.step(bool(offer(c))):
            acc.append(c)
            idx += 1
        c += 1
    vp.step(False)
    c += 1
    while vp.busy:
        vp.step(False)
        c += 1
    return {"cycles": c + 1, "accept": acc, "tests": vp.tests, "stalls": vp.stalls}


@pytest.mark.parametrize(("size", "matrix", "proc", "fifo_depth", "ntri", "area", "gaps"), [
    (32, (2, 2), (1, 0), 8, 14, 60.0, False),   # big triangles: the pixel level's FIFO fills
    (32, (2, 2), (0, 1), 2, 14, 60.0, True),    # shallowest FIFO, random idle input clocks
    (64, (4, 4), (3, 2), 3, 25, 8.0, False),    # small triangles on a 4x4 matrix
])
def test_model_equals_pysim_cycle_by_cycle(size, matrix, proc, fifo_depth, ntri, area, gaps):
    tris = random_triangles(size, size, ntri, mean_area=area, seed=size + ntri)
    rng = np.random.default_rng(5)
    pattern = rng.random(100_000) < 0.7 if gaps else np.ones(100_000, dtype=bool)
    kw = dict(p=matrix[0], q=matrix[1], a=proc[0], b=proc[1], fifo_depth=fifo_depth, offer=lambda c: pattern[c])
    n = (size // matrix[0]).bit_length() - 1
    got = _pysim_bench(tris, n=n, **kw)
    want = _model(tris, **kw)
    assert want["accept"] == got["accept"]
    assert want["tests"] == got["tests"] and want["stalls"] == got["stalls"]
    assert want["cycles"] == got["cycles"]
    if fifo_depth == 8 and not gaps:
        assert sum(got["stalls"]) > 0  # the case exercises back-pressure


def test_standalone_counts_tests_as_the_golden_search():
    tris = random_triangles(64, 64, 30, mean_area=20.0, seed=11)
    f = sparse_render(tris, "2x2", depth="fixed", trace=True)
    for k in range(4):
        r = vp_standalone(*vp_streams(f, k), f.triangles)
        assert r["tests"] == f.tests_per_proc[k, 1:].tolist()
        assert r["cycles"] > max(r["tests"]) and len(r["accept"]) == f.triangles


def test_bad_input_is_rejected():
    tris = random_triangles(32, 32, 5, seed=2)
    with pytest.raises(RasterhwError, match="trace=True"):
        vp_streams(sparse_render(tris, "2x2"), 0)
    f = sparse_render(tris, "2x2", trace=True)
    with pytest.raises(RasterhwError, match="processor index"):
        vp_streams(f, 4)
    with pytest.raises(RasterhwError, match="fifo_depth"):
        VPCycleModel(*vp_streams(f, 0), fifo_depth=1)


def test_model_equals_the_verilator_bench_per_processor():
    """Every processor of the 4 x 4, n = 6 Verilog (the build tests/sparse/test_sparse_vp_verilator.py
    and the soak use: the generic engine's ProcessorBench, one build for every processor): the
    bench's cycle count equals the model's, processor by processor."""
    from rasterhw.sim.sparse.scene import run_processor

    tris = random_triangles(256, 256, 40, mean_area=1280.0, seed=8)
    f = sparse_render(tris, "4x4", depth="fixed", trace=True)
    got, want = [], []
    for b in range(4):
        for a in range(4):
            r = run_processor(tris, n=6, p=4, q=4, a=a, b=b, z_bits=tris.z_bits)
            m = vp_standalone(*vp_streams(f, b * 4 + a), f.triangles)
            got.append((r["cycles"], list(r["tests"]), list(r["stalls"])))
            want.append((m["cycles"], m["tests"], m["stalls"]))
    assert got == want
    assert len({c for c, _, _ in got}) > 1  # the processors differ: the check is per processor


def test_setup_fifo_depth_is_fifo_zero_only():
    """``setup_fifo_depth`` sizes only FIFO 0 (set-up into level 1): equal to ``fifo_depth`` it is the
    default processor; a shallower one can only slow the processor; below 2 it is refused."""
    from rasterhw.golden_model.sparse.vpcycles import coupled_matrix_vp

    tris = random_triangles(32, 32, 30, mean_area=30.0, seed=11)
    f = sparse_render(tris, (2, 2), depth="fixed", trace=True)
    base = coupled_matrix_vp(f, 2, fifo_depth=4)
    same = coupled_matrix_vp(f, 2, fifo_depth=4, setup_fifo_depth=4)
    assert base["frame_cycles"] == same["frame_cycles"] and base["busy"] == same["busy"]
    assert np.array_equal(base["accept"], same["accept"])
    small = coupled_matrix_vp(f, 2, fifo_depth=4, setup_fifo_depth=2)
    assert small["frame_cycles"] >= base["frame_cycles"]
    with pytest.raises(RasterhwError):
        coupled_matrix_vp(f, 2, fifo_depth=4, setup_fifo_depth=1)
