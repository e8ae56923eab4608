"""The whole matrix (``hdl/sparse/matrix.py``: broadcast, every processor's input FIFO, the slowest
holding the broadcast back, interleaved read-out) in Amaranth pysim against the golden model: the
image bit for bit, and frame cycles, broadcast stalls, FIFO peaks, per-processor busy cycles and
per-level tests against the coupled matrix's cycle model (``golden_model/sparse/vpcycles.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.vpcycles import coupled_matrix_vp
from rasterhw.hdl.sparse.cell import cell_stats


def run_matrix_pysim(tris, *, p, q, limit, in_depth=8, fifo_depth=8, gaps=None):
    """The matrix in pysim with a source that offers a record on every cycle from the first
    (``gaps``: a per-cycle offer pattern instead); returns the read-out and every counter."""
    from amaranth.sim import Simulator
    from rasterhw.golden_model.sparse.fixed import broadcast_records
    from rasterhw.golden_model.sparse.formats import sparse_geometry
    from rasterhw.hdl.sparse.matrix import Matrix

    n = sparse_geometry(tris.width, tris.height, p, q)
    dut = Matrix(n=n, p=p, q=q, z_bits=tris.z_bits, fifo_depth=fifo_depth, in_depth=in_depth)
    recs = broadcast_records(tris)
    W, H = tris.width, tris.height
    res = {"tri": np.full((H, W), -1, dtype=np.int64), "zq": np.full((H, W), -1, dtype=np.int64)}
    names = cell_stats(n)

    async def bench(ctx):
        ctx.set(dut.limit, limit)
        idx, c = 0, 0
        while idx < len(recs):
            v = True if gaps is None else bool(gaps[c])
            ctx.set(dut.i.payload, recs[idx])
            ctx.set(dut.i.valid, v)
            if v and ctx.get(dut.i.ready):
                idx += 1
            await ctx.tick()
            c += 1
        ctx.set(dut.i.valid, 0)
        while ctx.get(dut.busy):
            await ctx.tick()
        res["cycles"], res["stall_cycles"] = ctx.get(dut.cycles), ctx.get(dut.stall_cycles)
        st = np.zeros((p * q, len(names)), dtype=np.int64)
        for k in range(p * q):
            ctx.set(dut.stat_cell, k)
            for j in range(len(names)):
                ctx.set(dut.stat_sel, j)
                st[k, j] = ctx.get(dut.stat)
        res["stats"] = {name: st[:, j] for j, name in enumerate(names)}
        for y in range(H):
            for x in range(W):
                ctx.set(dut.rd_x, x)
                ctx.set(dut.rd_y, y)
                await ctx.tick()
                t, z = ctx.get(dut.rd_tri), ctx.get(dut.rd_z)
                if t != 0xFFFF:
                    res["tri"][y, x], res["zq"][y, x] = t, z

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return res


@pytest.mark.parametrize(("size", "matrix", "limit", "ntri", "area"), [
    ((16, 16), (2, 2), 1, 12, 16.0),    # shallowest input FIFO: the broadcast waits
    ((16, 16), (2, 2), 8, 12, 16.0),
    ((32, 16), (4, 2), 2, 16, 20.0),    # a non-square matrix
])
def test_matrix_cycle_exact_against_coupled_model(size, matrix, limit, ntri, area):
    p, q = matrix
    tris = random_triangles(*size, ntri, mean_area=area, seed=ntri + limit)
    f = sparse_render(tris, matrix, depth="fixed", trace=True)
    gz = np.where(f.tri_id >= 0, np.rint(f.depth * (1 << tris.z_bits)), -1).astype(np.int64)
    h = run_matrix_pysim(tris, p=p, q=q, limit=limit)
    assert np.array_equal(h["tri"], f.tri_id)
    assert np.array_equal(h["zq"], gz)
    g = coupled_matrix_vp(f, limit)
    assert h["cycles"] == g["frame_cycles"]
    assert h["stall_cycles"] == g["stall_cycles"]
    assert h["stats"]["fifo_peak"].tolist() == g["fifo_peak"]
    assert max(g["fifo_peak"]) <= limit
    assert h["stats"]["busy_cycles"].tolist() == g["busy"]
    assert h["stats"]["records"].tolist() == [ntri] * (p * q)
    n = len(g["tests"][0])
    tests = np.stack([h["stats"][f"tests_{i}"] for i in range(1, n + 1)], axis=1)
    assert np.array_equal(tests, np.array(g["tests"]))
    assert np.array_equal(tests, f.tests_per_proc[:, 1:])


def test_depth_one_stalls_the_broadcast():
    tris = random_triangles(16, 16, 12, mean_area=16.0, seed=3)
    h1 = run_matrix_pysim(tris, p=2, q=2, limit=1)
    assert h1["stall_cycles"] > 0
    assert h1["stats"]["fifo_peak"].max() == 1
