"""Run the HDL stack processor (``hdl/sparse/stack_vp.py``) of one matrix place in Amaranth pysim,
records waiting at its input from cycle 0, and hold it to ``golden_model/sparse/stack.py`` bit and
cycle for cycle: local memories, the cycle each record is taken, busy cycles, tests per level,
the stack's depth and the pixel writes."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import TRI_BITS, parse_matrix, sparse_geometry

__all__ = ["compare_stack", "run_stack_pysim"]


def run_stack_pysim(tris: ScreenTriangles, matrix, a: int, b: int, *, colour: bool = False, kp: int = 0,
                    max_cycles: int = 2_000_000) -> dict:
    """Processor ``(a, b)`` of the ``p x q`` matrix as the HDL stack processor in pysim. Returns
    ``tri``, ``zq`` (-1 where empty), ``accept`` (cycle each record was taken), ``busy``
    (the ``busy_cycles`` counter), ``tests`` per level, ``max_stack``, ``writes``, ``records``."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.sparse.stack_vp import StackProcessor

    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse stack HDL: processor ({a}, {b}) is outside a {p}x{q} matrix")
    if colour:
        from rasterhw.golden_model.sparse.stack import broadcast_records_rgb

        recs = broadcast_records_rgb(tris)
    else:
        recs = broadcast_records(tris)
    dut = StackProcessor(n=n, p=p, q=q, z_bits=tris.z_bits, colour=colour, kp=kp)
    N = 1 << n
    res: dict = {"accept": []}

    async def bench(ctx):
        ctx.set(dut.a, a)
        ctx.set(dut.b, b)
        cyc = 0
        for r in recs:
            ctx.set(dut.i.payload, r)
            ctx.set(dut.i.valid, 1)
            while True:
                ready = ctx.get(dut.i.ready)
                await ctx.tick()
                if ready:
                    res["accept"].append(cyc)
                    cyc += 1
                    break
                cyc += 1
                if cyc > max_cycles:
                    raise RasterhwError(f"sparse stack HDL: no record taken in {max_cycles} cycles")
        ctx.set(dut.i.valid, 0)
        while ctx.get(dut.busy):
            await ctx.tick()
            cyc += 1
            if cyc > max_cycles:
                raise RasterhwError(f"sparse stack HDL: still busy after {max_cycles} cycles")
        res["cycles"] = cyc
        res["tests"] = np.array([int(ctx.get(getattr(dut, f"tests_{i}"))) for i in range(1, n + 1)], dtype=np.int64)
        for k in ("busy_cycles", "records", "max_stack", "writes"):
            res[k] = int(ctx.get(getattr(dut, k)))
        tri = np.full(N * N, -1, dtype=np.int64)
        zq = np.full(N * N, -1, dtype=np.int64)
        rgb = np.zeros((N * N, 3), dtype=np.int64)
        for adr in range(N * N):
            ctx.set(dut.rd_addr, adr)
            await ctx.tick()
            t, z = int(ctx.get(dut.rd_tri)), int(ctx.get(dut.rd_z))
            if t != (1 << TRI_BITS) - 1:
                tri[adr], zq[adr] = t, z
                if colour:
                    c = int(ctx.get(dut.rd_rgb))
                    rgb[adr] = (c & 255, (c >> 8) & 255, c >> 16)
        res["tri"], res["zq"] = tri.reshape(N, N), zq.reshape(N, N)
        res["rgb"] = rgb.reshape(N, N, 3) if colour else None

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    res["accept"] = np.array(res["accept"], dtype=np.int64)
    res["busy"] = res.pop("busy_cycles")
    return res


def compare_stack(hdl: dict, gold: dict) -> dict:
    """Differences between an HDL run and ``stack_processor``'s: ``mismatches`` (pixels whose
    triangle, depth or colour differ) and ``cycle_mismatches`` (of: every record's take cycle, busy cycles,
    tests per level, the stack's depth, pixel writes)."""
    bad = (hdl["tri"] != gold["tri"]) | (hdl["zq"] != gold["zq"])
    if hdl.get("rgb") is not None or gold.get("rgb") is not None:
        bad |= (hdl["rgb"] != gold["rgb"]).any(axis=-1)
    mism = int(np.count_nonzero(bad))
    cyc = int(np.count_nonzero(hdl["accept"] != gold["accept"])) if hdl["accept"].shape == gold["accept"].shape \
        else max(len(hdl["accept"]), len(gold["accept"]))
    cyc += int(np.count_nonzero(hdl["tests"] != gold["tests"]))
    cyc += sum(int(hdl[k] != gold[k]) for k in ("busy", "max_stack", "writes"))
    return {"mismatches": mism, "cycle_mismatches": cyc}
