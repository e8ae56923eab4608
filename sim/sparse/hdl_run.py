"""Run the HDL video processors of a p x q matrix on screen triangles in Amaranth pysim.

Each processor is simulated on the same broadcast stream (the broadcast of the paper: every
processor sees every triangle) and its local memory is read back through the video-controller
port; the frame is the interleaved read-out. Returned with every processor's busy cycles per
stage (coverage tests, τ = one cycle each) and its total cycles.
"""

from __future__ import annotations

import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import TRI_BITS, parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave

__all__ = ["run_processor", "run_matrix"]


def run_processor(recs: list[dict], *, n: int, p: int, q: int, a: int, b: int, z_bits: int = 24,
                  readback: bool = True, max_cycles: int = 10_000_000) -> dict:
    """One video processor in pysim: returns ``tri`` and ``zq`` local memories (N x N, -1 /
    -1 where empty), ``tests`` per level, ``stalls``, ``writes``, ``cycles`` (until idle)."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.sparse.vp import VideoProcessor
    from rasterhw.sim.engines.harness import stream_put

    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse HDL: processor ({a}, {b}) is outside a {p}x{q} matrix")
    dut = VideoProcessor(n=n, p=p, q=q, z_bits=z_bits)
    N = 1 << n
    res: dict = {}

    async def bench(ctx):
        ctx.set(dut.a, a)
        ctx.set(dut.b, b)
        cycles = 0
        for r in recs:
            await stream_put(ctx, dut.i, r)
        await ctx.tick()
        while ctx.get(dut.busy):
            await ctx.tick()
            cycles += 1
            if cycles > max_cycles:
                raise RasterhwError(f"sparse HDL: processor ({a}, {b}) still busy after {max_cycles} cycles")
        res["tests"] = [int(ctx.get(getattr(dut, f"tests_{i}"))) for i in range(1, n + 1)]
        res["stalls"] = [int(ctx.get(getattr(dut, f"stalls_{i}"))) for i in range(1, n + 1)]
        res["writes"] = int(ctx.get(dut.writes))
        tri = np.full(N * N, -1, dtype=np.int64)
        zq = np.full(N * N, -1, dtype=np.int64)
        if readback:
            for addr in range(N * N):
                ctx.set(dut.rd_addr, addr)
                await ctx.tick()
                t, z = int(ctx.get(dut.rd_tri)), int(ctx.get(dut.rd_z))
                if t != (1 << TRI_BITS) - 1:
                    tri[addr], zq[addr] = t, z
        res["tri"], res["zq"] = tri.reshape(N, N), zq.reshape(N, N)

    cyc = {"n": 0}

    async def counter(ctx):
        async for _ in ctx.tick():
            cyc["n"] += 1

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.add_testbench(counter, background=True)
    t0 = time.perf_counter()
    sim.run()
    res["wall_s"] = time.perf_counter() - t0
    res["cycles"] = cyc["n"]
    return res


def run_matrix(tris: ScreenTriangles, matrix="2x2", *, processors=None, z_bits: int | None = None) -> dict:
    """Every processor (or the listed ``(a, b)``) of the matrix on ``tris``; the interleaved frame
    (``tri``, ``zq``, -1 where empty) when all ran, per-processor tests per level and cycles."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    recs = broadcast_records(tris)
    z_bits = tris.z_bits if z_bits is None else z_bits
    procs = [(a, b) for b in range(q) for a in range(p)] if processors is None else list(processors)
    N = 1 << n
    loc_t = np.full((q, p, N, N), -1, dtype=np.int64)
    loc_z = np.full((q, p, N, N), -1, dtype=np.int64)
    per = {}
    for a, b in procs:
        r = run_processor(recs, n=n, p=p, q=q, a=a, b=b, z_bits=z_bits)
        loc_t[b, a], loc_z[b, a] = r["tri"], r["zq"]
        per[(a, b)] = r
    out = {"p": p, "q": q, "n": n, "per_processor": per, "local_tri": loc_t, "local_zq": loc_z}
    if processors is None:
        out["tri"], out["zq"] = interleave(loc_t), interleave(loc_z)
    return out
