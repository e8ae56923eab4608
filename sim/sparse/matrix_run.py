"""The whole matrix (``hdl/sparse/matrix.py``) on one frame, in Verilator or pysim: broadcast,
every processor's input FIFO, back-pressure from the fullest, and the interleaved read-out, in one
simulation.

Verilator: the generic engine (``sim/engines/``) runs the testbench
:class:`~rasterhw.sim.sparse.testbench.MatrixFrameBench`: the cell (input FIFO + video processor) is
generated once as the Verilog module ``sparse_cell`` and the matrix instantiates it ``p*q`` times
by name, so the Verilog holds one processor module whatever the matrix size; the run's input FIFO
limit rides in a config word before the records (one build serves every depth); the records are
offered on every clock from the first; the full raster, the frame and stall counters and every
cell's counters stream out. pysim: :func:`run_matrix_pysim`, every cell elaborated, the same
protocol driven from Python (a per-cycle offer pattern possible).
"""

from __future__ import annotations

import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.sim.sparse.verilator_run import MAXT

__all__ = ["IN_DEPTH", "run_matrix", "run_matrix_pysim"]

#: the input FIFOs as built: the deepest run-time limit a run can ask for
IN_DEPTH = 64


def _rgb_planes(words: np.ndarray) -> np.ndarray:
    """``(..., 3)`` R, G, B of ``R | G << 8 | B << 16`` words."""
    return np.stack([(words >> (8 * ch)) & 255 for ch in range(3)], axis=-1)


def _check(recs, limit: int, in_depth: int) -> None:
    if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= in_depth:
        raise RasterhwError(f"sparse matrix: FIFO depth must be an integer in 1..{in_depth}, not {limit!r}")
    if len(recs) > MAXT:
        raise RasterhwError(f"sparse matrix bench holds at most {MAXT} triangles, not {len(recs)}")


def run_matrix(tris, *, n: int, p: int, q: int, limit: int, z_bits: int = 24, fifo_depth: int = 8,
               in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False, kp: int = 0, ke: int = 3,
               engine: str = "verilator", hierarchical: bool = False) -> dict:
    """The matrix on one frame of ``tris`` on a generic engine (``sim/engines/``; the testbench
    :class:`~rasterhw.sim.sparse.testbench.MatrixFrameBench`: the records offered back to back, the
    limit in a config word, the raster and every counter streamed out): ``tri`` / ``zq`` (full
    raster, -1 where empty), ``rgb`` (``(H, W, 3)`` with ``colour``, else None), ``cycles`` (the
    matrix's frame counter), ``stall_cycles``, ``stats`` (counter name -> (p*q,) array),
    ``run_s``, ``build_s``, ``sim_cycles`` (the bench's clocks, read-out included).
    ``engine="verilator"`` instantiates one cell module by name; ``"pysim"`` elaborates every cell.
    ``hierarchical`` (Verilator): the cell verilated and compiled once (``build={"hier": True}``):
    the same model, a much shorter build, a slower clock loop (``docs/sparse.md``)."""
    from rasterhw.hdl.sparse.cell import cell_stats
    from rasterhw.sim.engines import run as run_engine
    from rasterhw.sim.sparse.testbench import MatrixFrameBench

    tb = MatrixFrameBench("instance" if engine == "verilator" else "inline")
    params = tb.params(n=n, p=p, q=q, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth, vp=vp, colour=colour,
                       kp=kp, ke=ke)
    try:
        stim = tb.frame(tris, params, limit)
    except ValueError as e:
        raise RasterhwError(str(e)) from None
    ntri = len(stim.words["i"]) - 2
    if ntri > MAXT:
        raise RasterhwError(f"sparse matrix bench holds at most {MAXT} triangles, not {ntri}")
    W, H = p << n, q << n
    want = W * H + 2 + p * q * len(cell_stats(n))
    maxcyc = 400 * (ntri + 10) * (1 + n) * (1 + 64 // limit) + 4 * W * H + 10_000_000
    # the input memory sized for MAXT records whatever the frame: one build per design
    build = {"depth": MAXT + 2, **({"hier": True} if hierarchical else {})} if engine == "verilator" else None
    if hierarchical and engine != "verilator":
        raise RasterhwError("sparse matrix: --hierarchical is a Verilator build")
    got = run_engine(tb, params, stim, engine=engine, expect_words={"o": want}, max_cycles=maxcyc, build=build)
    t0 = time.perf_counter()
    res = tb.decode(params, got.words["o"])
    return {**res, "run_s": got.run_s if engine == "verilator" else got.wall_s, "sim_cycles": got.cycles,
            "build_s": got.build_s, "read_s": time.perf_counter() - t0, "protocol_errors": got.protocol_errors}


def run_matrix_pysim(recs: list[dict], *, n: int, p: int, q: int, limit: int, z_bits: int = 24,
                     fifo_depth: int = 8, in_depth: int = 8, gaps=None, vp: str = "pipeline", colour: bool = False,
                     kp: int = 0, ke: int = 3) -> dict:
    """The matrix in Amaranth pysim, every cell elaborated, with the Verilator bench's protocol (a
    record offered on every cycle from the first; ``gaps``: a per-cycle offer pattern instead).
    Same keys as :func:`run_matrix` (``sim_cycles`` and ``run_s`` of the whole run).
    ``vp="stack"``: every processor the stack-based one; ``colour``, ``kp``, ``ke`` as there."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.sparse.cell import cell_stats
    from rasterhw.hdl.sparse.matrix import Matrix

    _check(recs, limit, in_depth)
    dut = Matrix(n=n, p=p, q=q, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth, vp=vp, colour=colour,
                 kp=kp, ke=ke)
    W, H = p << n, q << n
    res = {"tri": np.full((H, W), -1, dtype=np.int64), "zq": np.full((H, W), -1, dtype=np.int64),
           "rgb": np.zeros((H, W, 3), dtype=np.int64) if colour else None}
    names = cell_stats(n)
    clk = {"n": 0}

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
            c += 1
        res["cycles"], res["stall_cycles"] = int(ctx.get(dut.cycles)), int(ctx.get(dut.stall_cycles))
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
                c += 1
                t, z = ctx.get(dut.rd_tri), ctx.get(dut.rd_z)
                if t != (1 << TRI_BITS) - 1:
                    res["tri"][y, x], res["zq"][y, x] = t, z
                if colour:
                    res["rgb"][y, x] = _rgb_planes(np.int64(ctx.get(dut.rd_rgb)))
        clk["n"] = c

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    t0 = time.perf_counter()
    sim.run()
    res.update(run_s=time.perf_counter() - t0, sim_cycles=clk["n"], build_s=0.0)
    return res
