"""The whole matrix (``hdl/sparse/matrix.py``) on one frame, in Verilator or pysim: broadcast,
every processor's input FIFO, back-pressure from the fullest, and the interleaved read-out, in one
simulation.

Verilator: the cell (input FIFO + video processor) is generated once as the Verilog module
``sparse_cell`` and the matrix instantiates it ``p*q`` times by name, so the Verilog holds one
processor module whatever the matrix size. The bench ``sim/sparse/verilator/tb_sparse_matrix.v``
offers a record on every cycle from the first, drains, reads every counter and sweeps the full
raster. The input FIFOs are built ``in_depth`` entries deep; ``limit`` (the run's FIFO depth) is
a plusarg, so a depth sweep reuses one build. With ``colour`` the records are ``BROADCAST_RGB``
(``stack.broadcast_records_rgb``) and the bench writes the interleaved colour memories as well
(``+rgb=``; the generated ``tb_sparse_matrix_cfg.vh`` defines ``RASTERHW_RGB``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.engines.runner import build_plain_verilator, run_plain_verilator
from rasterhw.sim.sparse.verilator_run import SHARED_VH, pack_records
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["IN_DEPTH", "build_matrix", "run_matrix", "run_matrix_pysim", "run_matrix_verilator"]

BENCH = Path(__file__).resolve().parent / "verilator" / "tb_sparse_matrix.v"
TOP = "tb_sparse_matrix"
MAXT = 16384
#: the input FIFOs as built: the deepest run-time limit a run can ask for
IN_DEPTH = 64


def _check(recs, limit: int, in_depth: int) -> None:
    if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= in_depth:
        raise RasterhwError(f"sparse matrix: FIFO depth must be an integer in 1..{in_depth}, not {limit!r}")
    if len(recs) > MAXT:
        raise RasterhwError(f"sparse matrix bench holds at most {MAXT} triangles, not {len(recs)}")


def build_matrix(*, n: int, p: int, q: int, z_bits: int = 24, fifo_depth: int = 8,
                 in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False, kp: int = 0,
                 ke: int = 3) -> tuple[Path, float, dict]:
    """Build once per parameter set; returns ``(binary, build seconds or 0, Verilog sizes)``.
    ``vp="stack"``: every cell's processor the stack-based one; ``colour``, ``kp``, ``ke``: the
    processors' surface parameters and their cost."""
    from rasterhw.hdl.sparse.cell import MatrixCell, cell_stats
    from rasterhw.hdl.sparse.layouts import layouts
    from rasterhw.hdl.sparse.matrix import CELL_MODULE, Matrix
    from rasterhw.sim.engines.verilog_cache import convert_cached

    kw = dict(n=n, p=p, q=q, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth)
    # the default design's cache keys stay as they were
    kw.update({k: v for k, v in (("vp", vp), ("colour", colour), ("kp", kp), ("ke", ke))
               if v != {"vp": "pipeline", "colour": False, "kp": 0, "ke": 3}[k]})
    cell = convert_cached("sparse-matrix", lambda: MatrixCell(**kw), params=kw,
                          module=CELL_MODULE)
    top = convert_cached("sparse-matrix", lambda: Matrix(**kw, cells="instance"), params={**kw, "cells": "instance"},
                         module="sparse_matrix")
    ns = len(cell_stats(n))
    lp, lq = p.bit_length() - 1, q.bit_length() - 1
    params = {"N": n, "LP": lp, "LQ": lq, "BW": layouts(colour)[0].size, "MAXT": MAXT, "ZW": z_bits + 1, "TW": TRI_BITS,
              "NS": ns, "LIMW": in_depth.bit_length(), "CW": max(1, (max(p * q, 2) - 1).bit_length()),
              "SW": max(1, (ns - 1).bit_length())}
    exe, secs = build_plain_verilator("sparse-matrix", TOP, [BENCH], params=params, defines={"RASTERHW_CYCLES": 1},
                                      generated={"sparse_cell.v": cell, "sparse_matrix.v": top,
                                                 "tb_sparse_matrix_cfg.vh": "`define RASTERHW_RGB\n" if colour else "",
                                                 **{f: (BENCH.parent / f).read_text() for f in SHARED_VH}})
    return exe, secs, {"verilog_bytes_cell": len(cell), "verilog_bytes_matrix": len(top)}


def _rgb_planes(words: np.ndarray) -> np.ndarray:
    """``(..., 3)`` R, G, B of ``R | G << 8 | B << 16`` words."""
    return np.stack([(words >> (8 * ch)) & 255 for ch in range(3)], axis=-1)


def run_matrix_verilator(recs: list[dict], *, n: int, p: int, q: int, limit: int, z_bits: int = 24,
                         fifo_depth: int = 8, in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False,
                         kp: int = 0, ke: int = 3) -> dict:
    """The matrix on Verilator: ``tri`` / ``zq`` (full raster, -1 where empty), ``rgb`` (``(H, W, 3)``,
    with ``colour``; else ``None``), ``cycles`` (the matrix's frame counter), ``stall_cycles``,
    ``stats`` (counter name -> (p*q,) array), ``run_s``, ``build_s``, ``sim_cycles`` (bench clocks,
    read-out included), Verilog sizes. ``recs``: ``BROADCAST_RGB`` records with ``colour``."""
    from rasterhw.hdl.sparse.cell import cell_stats

    _check(recs, limit, in_depth)
    exe, build_s, sizes = build_matrix(n=n, p=p, q=q, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth, vp=vp,
                                       colour=colour, kp=kp, ke=ke)
    run_dir = temp_run_folder(exe.parent.parent)
    (run_dir / "in.bin").write_bytes(pack_records(recs, colour=colour))
    W, H = p << n, q << n
    names = cell_stats(n)
    maxcyc = 400 * (len(recs) + 10) * (1 + n) * (1 + 64 // limit) + 4 * W * H + 10_000_000
    meta = run_plain_verilator(exe, [f"+in={run_dir / 'in.bin'}", f"+out={run_dir / 'out.hex'}",
                                     f"+stats={run_dir / 'stats.hex'}", f"+ntri={len(recs)}", f"+limit={limit}",
                                     f"+rgb={run_dir / 'rgb.hex'}"],
                               run_dir=run_dir, maxcyc=maxcyc)
    t0 = time.perf_counter()
    b_out = read_memh(run_dir / "out.hex", W * H)
    st = read_memh(run_dir / "stats.hex", 2 + p * q * len(names))
    rgb = None
    if colour:
        c = read_memh(run_dir / "rgb.hex", W * H)
        rgb = _rgb_planes(memh_uint64(c, 0, c.shape[1]).astype(np.int64)).reshape(H, W, 3)
    release(run_dir)
    st = memh_uint64(st, 0, st.shape[1]).astype(np.int64)
    words = memh_uint64(b_out, 0, b_out.shape[1]).astype(np.int64)
    tri = words >> (z_bits + 1)
    zq = words & ((1 << (z_bits + 1)) - 1)
    empty = tri == (1 << TRI_BITS) - 1
    tri[empty], zq[empty] = -1, -1
    per = st[2:].reshape(p * q, len(names))
    return {"tri": tri.reshape(H, W), "zq": zq.reshape(H, W), "rgb": rgb, "cycles": int(st[0]), "stall_cycles": int(st[1]),
            "stats": {name: per[:, j] for j, name in enumerate(names)}, "run_s": meta["run_s"],
            "sim_cycles": meta["sim_cycles"], "build_s": build_s, "read_s": time.perf_counter() - t0, **sizes}


def run_matrix(tris, *, n: int, p: int, q: int, limit: int, z_bits: int = 24, fifo_depth: int = 8,
               in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False, kp: int = 0, ke: int = 3,
               engine: str = "verilator") -> dict:
    """The matrix on one frame of ``tris`` on a generic engine (``sim/engines/``; the testbench
    :class:`~rasterhw.sim.sparse.testbench.FrameBench`: the records offered back to back, the
    limit in a config word, the raster and every counter streamed out). The keys of
    :func:`run_matrix_verilator`; ``sim_cycles`` are the bench's clocks (read-out included).
    ``engine="verilator"`` instantiates one cell module by name; ``"pysim"`` elaborates every cell."""
    from rasterhw.hdl.sparse.cell import cell_stats
    from rasterhw.sim.engines import run as run_engine
    from rasterhw.sim.sparse.testbench import FrameBench

    tb = FrameBench("instance" if engine == "verilator" else "inline")
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
    build = {"depth": MAXT + 2} if engine == "verilator" else None
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
    Same keys as :func:`run_matrix_verilator` (``sim_cycles`` and ``run_s`` of the whole run).
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
