"""Surface parameters in the pipeline video processor (hdl/sparse/vp.py) and in the coupled matrix
with either processor: colour (R, G, B as linear functions broadcast with the edges) bit for bit
against ``fixed.colour_rgb8``, and formula (5)'s k_p/k_e cost in cycles, against the golden cycle
models (golden_model/sparse/vpcycles.py, cycles.py)."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.cycles import stage_cycles
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.vpcycles import VPCycleModel, vp_streams


@pytest.mark.parametrize("kp", [0, 1, 4, 7])
def test_pipeline_stage_cycles_are_formula_5(kp):
    """Each stage of the processor as built (the cycle model, held to the HDL below) is busy
    ``4 w_(i-1) + [w_i > 0] + ceil(w_i k_p / k_e)`` cycles per record (cycles.stage_cycles) plus
    the cycles a survivor waited."""
    tris = random_triangles(32, 32, 20, mean_area=60.0, seed=4)
    f = sparse_render(tris, "2x2", depth="fixed", trace=True, per_record=True)
    want = stage_cycles(f.stats["windows_per_record"], kp=kp).sum(axis=1)  # (P, n)
    for k in range(4):
        vp = VPCycleModel(*vp_streams(f, k), fifo_depth=64, kp=kp)
        taken = 0
        while taken < f.triangles or vp.busy:
            taken += vp.step(taken < f.triangles)
        assert [b - s for b, s in zip(vp.stage_busy, vp.stalls, strict=True)] == want[k].tolist()
    if kp:
        assert (want > stage_cycles(f.stats["windows_per_record"]).sum(axis=1)).any()


def _vp_pysim(tris, *, p, q, a, b, colour, kp, fifo_depth=8):
    """Processor (a, b) alone in pysim, records offered back to back: the cycle each is taken, the
    stage counters, the cycle it goes idle, its local memories (colour too)."""
    from amaranth.sim import Simulator
    from rasterhw.golden_model.sparse.fixed import broadcast_records
    from rasterhw.golden_model.sparse.formats import TRI_BITS, sparse_geometry
    from rasterhw.golden_model.sparse.stack import broadcast_records_rgb
    from rasterhw.hdl.sparse.vp import VideoProcessor

    n = sparse_geometry(tris.width, tris.height, p, q)
    recs = broadcast_records_rgb(tris) if colour else broadcast_records(tris)
    dut = VideoProcessor(n=n, p=p, q=q, z_bits=tris.z_bits, fifo_depth=fifo_depth, colour=colour, kp=kp)
    N = 1 << n
    res = {"tri": np.full(N * N, -1), "rgb": np.zeros((N * N, 3), dtype=np.int64)}

    async def bench(ctx):
        ctx.set(dut.a, a)
        ctx.set(dut.b, b)
        acc, c, idx = [], 0, 0
        while idx < len(recs) or ctx.get(dut.busy):
            ctx.set(dut.i.valid, idx < len(recs))
            if idx < len(recs):
                ctx.set(dut.i.payload, recs[idx])
                if ctx.get(dut.i.ready):
                    acc.append(c)
                    idx += 1
            await ctx.tick()
            c += 1
        res.update(cycles=c, accept=acc, tests=[int(ctx.get(getattr(dut, f"tests_{i}"))) for i in range(1, n + 1)],
                   stalls=[int(ctx.get(getattr(dut, f"stalls_{i}"))) for i in range(1, n + 1)])
        for adr in range(N * N):
            ctx.set(dut.rd_addr, adr)
            await ctx.tick()
            if ctx.get(dut.rd_tri) != (1 << TRI_BITS) - 1:
                res["tri"][adr] = ctx.get(dut.rd_tri)
            if colour:
                v = int(ctx.get(dut.rd_rgb))
                res["rgb"][adr] = (v & 255, (v >> 8) & 255, v >> 16)

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    res["tri"], res["rgb"] = res["tri"].reshape(N, N), res["rgb"].reshape(N, N, 3)
    return res


@pytest.mark.parametrize(("matrix", "proc", "kp", "fifo_depth"), [
    ((2, 2), (1, 0), 4, 8),     # depth + RGB priced as (5)
    ((2, 2), (0, 1), 5, 2),     # shallowest inner FIFOs: parameter waits and back-pressure together
    ((4, 2), (3, 1), 0, 8),     # colour alone costs no cycle
])
def test_pipeline_vp_colour_bit_exact_and_cycles_as_the_model(matrix, proc, kp, fifo_depth):
    from rasterhw.golden_model.sparse.fixed import colour_rgb8

    p, q = matrix
    a, b = proc
    tris = random_triangles(16 * p, 16 * q, 10, mean_area=40.0, seed=3 + kp)
    f = sparse_render(tris, matrix, depth="fixed", trace=True)
    h = _vp_pysim(tris, p=p, q=q, a=a, b=b, colour=True, kp=kp, fifo_depth=fifo_depth)
    assert np.array_equal(h["tri"], f.tri_id[b::q, a::p])
    full = colour_rgb8(tris, f.tri_id, p, q).astype(np.int64)
    assert np.array_equal(h["rgb"], full[b::q, a::p])                  # colour: bit for bit
    assert (h["rgb"][h["tri"] >= 0] > 0).any() and (h["tri"] >= 0).sum() > 20
    vp = VPCycleModel(*vp_streams(f, b * p + a), fifo_depth=fifo_depth, kp=kp)
    acc, c = [], 0
    while len(acc) < f.triangles or vp.busy:
        if vp.step(len(acc) < f.triangles):
            acc.append(c)
        c += 1
    assert h["accept"] == acc and h["cycles"] == c
    assert h["tests"] == vp.tests and h["stalls"] == vp.stalls
    assert h["tests"] == f.tests_per_proc[b * p + a, 1:].tolist()
    if kp:
        plain = VPCycleModel(*vp_streams(f, b * p + a), fifo_depth=fifo_depth)
        taken = c0 = 0
        while taken < f.triangles or plain.busy:
            taken += plain.step(taken < f.triangles)
            c0 += 1
        assert c > c0   # the parameter additions cost cycles


@pytest.mark.parametrize(("vp", "limit", "kp"), [("pipeline", 1, 4), ("pipeline", 8, 0), ("stack", 1, 4),
                                                 ("stack", 8, 0)])
def test_coupled_matrix_with_colour_bit_and_cycle_exact(vp, limit, kp):
    """The whole matrix with surface parameters, either processor: image and colour against the
    golden model, frame, stalls, FIFO peaks, busy cycles and tests against its coupled cycle model."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    tris = random_triangles(16, 16, 12, mean_area=16.0, seed=9)
    r = simulate_coupled(tris, "2x2", engine="pysim", fifo_depth=limit, vp=vp, colour=True, kp=kp)
    assert r["colour"] and r["kp"] == kp and r["ke"] == 3
    assert r["mismatches"] == 0 and r["colour_mismatches"] == 0 and r["colour_pixels_compared"] == 256
    assert r["cycle_mismatches"] == 0 and r["cycles_compared"] == 2 + 2 * 4 + 4 * 3
    assert r["frame_rgb"].shape == (16, 16, 3) and r["frame_rgb"].max() > 0
    plain = simulate_coupled(tris, "2x2", engine="pysim", fifo_depth=limit, vp=vp)
    assert "colour_mismatches" not in plain
    # unset, the pipeline has eight-entry inner FIFOs (ours, HDL_FIFO_DEPTH); pysim is never hierarchical
    assert plain["vp_fifo_depth"] == 8 and plain["hierarchical"] is False
    assert plain["vp_buffers"].startswith("ours (8-entry" if vp == "pipeline" else "none")
    if kp:
        assert r["frame_cycles"] > plain["frame_cycles"] and all(x > y for x, y in zip(r["busy"], plain["busy"], strict=True))
    else:
        assert r["frame_cycles"] == plain["frame_cycles"] and r["busy"] == plain["busy"]


def test_colour_options_are_checked():
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.hdl.sparse.vp import VideoProcessor
    from rasterhw.sim.sparse.scene import simulate, simulate_coupled

    tris = random_triangles(16, 16, 4, mean_area=10.0, seed=1)
    for kw in ({"kp": -1}, {"kp": 16}, {"kp": True}, {"colour": 1}):
        with pytest.raises(RasterhwError):
            simulate_coupled(tris, "2x2", engine="pysim", **kw)
    with pytest.raises(RasterhwError, match="drop --no-coupled"):
        simulate("c50", 32, 32, engine="pysim", matrix="2x2", coupled=False, colour=True)
    for kw in ({"kp": -1}, {"ke": 0}, {"colour": 1}, {"kp": 16}):
        with pytest.raises(ValueError):
            VideoProcessor(n=3, **kw)


def test_verilator_coupled_matrix_colour_and_kp():
    """One small frame on Verilator: the 2x2 matrix of pipeline processors with colour and (5)'s
    k_p = 4: image, colour and every counter equal to the golden model's."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    tris = random_triangles(32, 32, 30, mean_area=40.0, seed=11)
    r = simulate_coupled(tris, "2x2", fifo_depth=2, colour=True, kp=4)
    assert r["engine"] == "verilator" and r["pixels_compared"] == 32 * 32
    assert r["mismatches"] == 0 and r["colour_mismatches"] == 0
    assert r["cycle_mismatches"] == 0 and r["cycles_compared"] == 2 + 2 * 4 + 4 * 4
    assert r["frame_rgb"].max() > 0 and r["stall_cycles"] > 0


@pytest.mark.cocotb
def test_hierarchical_build_is_the_same_model():
    """``--hierarchical`` (the cell verilated once, Verilator's hierarchical verilation) runs the
    frame of the test above to the same image, colour, counters and cycles as the flat build
    (which that test builds); it is a build of its own (``tb-sparse-matrix-hier-*``)."""
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.sparse.scene import simulate_coupled

    tris = random_triangles(32, 32, 30, mean_area=40.0, seed=11)
    flat = simulate_coupled(tris, "2x2", fifo_depth=2, colour=True, kp=4)
    hier = simulate_coupled(tris, "2x2", fifo_depth=2, colour=True, kp=4, hierarchical=True)
    assert hier["mismatches"] == 0 and hier["colour_mismatches"] == 0 and hier["cycle_mismatches"] == 0
    assert (flat["hierarchical"], hier["hierarchical"]) == (False, True)   # 2x2: flat unless asked
    for k in flat:
        if k.endswith("_s") or k in ("cycles_per_s", "hierarchical"):   # timings; the build
            continue
        a, b = flat[k], hier[k]
        same = np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b
        assert same, k
    with pytest.raises(RasterhwError, match="Verilator build"):
        simulate_coupled(tris, "2x2", engine="pysim", hierarchical=True)
