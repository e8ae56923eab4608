"""One video processor of the matrix on Verilator, through the generic engine (``sim/engines/``).

The testbench is :class:`~rasterhw.sim.sparse.testbench.ProcessorBench`: the processor's place
``(a, b)`` in a config word (so one build serves every processor of the matrix), the broadcast
records back to back (or with random idle clocks), the end word; then the local memory, the
per-level tests and stalls, the pixel writes and the processor's cycle count stream out. The
engine builds the bench once per design (``build/tb-sparse-vp-<hash>/``) and reuses it.
``engine="cocotb-verilator"`` / ``"cocotb-icarus"``: the same bench top under cocotb (the
generic cocotb engine); :func:`check_processor` holds one processor against the golden model
(the checks the processor's own cocotb bench made before the generic engine replaced it).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.sim.engines import run as run_engine
from rasterhw.sim.sparse.testbench import ProcessorBench

__all__ = ["MAXT", "check_processor", "run_processor_verilator"]

#: the most records a frame may have (the bench's input memory: one build for every frame)
MAXT = 16384


def run_processor_verilator(tris, *, n: int, p: int, q: int, a: int, b: int, z_bits: int = 24, idle: int = 0,
                            seed: int = 1, engine: str = "verilator") -> dict:
    """Processor ``(a, b)`` on ``tris`` on ``engine`` (Verilator by default; pysim; the cocotb engines):
    ``tri``, ``zq`` (N x N, -1 where empty), ``tests`` and ``stalls`` per level, ``writes``, ``cycles``
    (the processor's own count: ``ProcessorBench.decode``) plus ``run_s`` (the simulation),
    ``build_s``, ``records`` (the broadcast records played) and ``sim_cycles`` (the bench's clocks, read-out included). ``idle`` (0..255): each
    clock before a record is idle with probability ``idle / 256`` (seeded by ``seed``); the frame
    and the per-level tests do not depend on it, the cycle count does."""
    if isinstance(idle, bool) or not (isinstance(idle, int) and 0 <= idle <= 255):
        raise RasterhwError(f"sparse verilator bench: idle must be an integer in 0..255, not {idle!r}")
    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse HDL: processor ({a}, {b}) is outside a {p}x{q} matrix")
    tb = ProcessorBench()
    params = tb.params(n=n, p=p, q=q, z_bits=z_bits)
    stim = tb.frame(tris, params, a, b)
    N = 1 << n
    ntri = len(stim.words["i"]) - 2
    if ntri > MAXT:
        raise RasterhwError(f"sparse verilator bench holds at most {MAXT} triangles, not {ntri}")
    maxcyc = (200 * (ntri + 10) * (1 + n) + 64 * N * N + 10_000_000) * (1 + idle // 16)
    got = run_engine(tb, params, stim, engine=engine, idle=idle / 256, seed=seed,
                     expect_words={"o": N * N + 2 * n + 2}, max_cycles=maxcyc,
                     build={"depth": MAXT + 2} if engine != "pysim" else None)   # one build per design
    if got.protocol_errors:
        raise RasterhwError(f"sparse processor ({a}, {b}) on {engine}: {got.protocol_errors} clocks broke the "
                            "stream rules")
    return {**tb.decode(params, got.words["o"]), "sim_cycles": got.cycles, "run_s": got.run_s,
            "build_s": got.build_s, "records": ntri}


def check_processor(tris, matrix: str = "4x4", *, a: int = 0, b: int = 0, engine: str = "cocotb-verilator",
                    idle: int = 0, seed: int = 1, expect: dict | None = None) -> dict:
    """Processor ``(a, b)`` of ``matrix`` on screen triangles ``tris`` against the bit-accurate golden
    model: ``mismatches`` counts the local-memory words (triangle and depth) and per-level test
    counts that differ (``expect`` overrides the golden ``tri`` / ``zq`` / ``tests``: a test of the
    check). Also ``records``, ``words_read`` (the local memory's words), ``n``."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    g = sparse_render(tris, (p, q), depth="fixed")
    gz = g.depth_words(tris.z_bits)
    want = {"tri": g.tri_id[b::q, a::p], "zq": gz[b::q, a::p], "tests": g.tests_per_proc[b * p + a, 1:]}
    want.update(expect or {})
    r = run_processor_verilator(tris, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, idle=idle, seed=seed,
                                engine=engine)
    bad = int(np.count_nonzero((r["tri"] != want["tri"]) | (r["zq"] != want["zq"])))
    bad += int(np.count_nonzero(np.asarray(r["tests"]) != np.asarray(want["tests"])))
    return {"records": r["records"], "words_read": int(r["tri"].size), "n": n, "mismatches": bad}
