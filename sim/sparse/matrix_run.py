"""The whole matrix (``hdl/sparse/matrix.py``) on one frame, on any generic engine (``sim/engines/``:
pysim, Verilator): broadcast, every processor's input FIFO, back-pressure from the fullest, and the
interleaved read-out, in one simulation.

The engine runs the testbench
:class:`~rasterhw.sim.sparse.testbench.MatrixFrameBench`: the cell (input FIFO + video processor) is
generated once as the Verilog module ``sparse_cell`` and the matrix instantiates it ``p*q`` times
by name, so the Verilog holds one processor module whatever the matrix size; the run's input FIFO
limit rides in a config word before the records (one build serves every depth); the records are
offered on every clock from the first; the full raster (every processor's memory read in
parallel: one word per processor per clock, ``MatrixFrameBench(readout="wide")``), the frame and
stall counters and every cell's counters stream out. On pysim every cell is elaborated (``MatrixFrameBench("inline")``).
"""

from __future__ import annotations

import time

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.sparse.verilator_run import MAXT

__all__ = ["IN_DEPTH", "run_matrix"]

#: the input FIFOs as built: the deepest run-time limit a run can ask for
IN_DEPTH = 64


def run_matrix(tris, *, n: int, p: int, q: int, limit: int, z_bits: int = 24, fifo_depth: int = 8,
               in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False, kp: int = 0, ke: int = 3,
               engine: str = "verilator", hierarchical: bool = False) -> dict:
    """The matrix on one frame of ``tris`` on a generic engine (``sim/engines/``; the testbench
    :class:`~rasterhw.sim.sparse.testbench.MatrixFrameBench`: the records offered back to back, the
    limit in a config word, the raster and every counter streamed out): ``tri`` / ``zq`` (full
    raster, -1 where empty), ``rgb`` (``(H, W, 3)`` with ``colour``, else None), ``cycles`` (the
    matrix's frame counter), ``stall_cycles``, ``stats`` (counter name -> (p*q,) array),
    ``run_s``, ``build_s``, ``sim_cycles`` (the bench's clocks, read-out included: the frame, then
    ``2**(2n)`` clocks of parallel read-out and one clock per counter).
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
    want = tb.pixel_words(params) + 2 + p * q * len(cell_stats(n))
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
