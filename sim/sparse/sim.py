"""``rasterhw sim sparse --scene SCENE --matrix PxQ --engine ...``: every video processor of the
matrix in HDL on the scene, its interleaved local memories compared with the bit-accurate golden
model pixel by pixel (triangle index and quantised depth)."""

from __future__ import annotations

import os
import sys
import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave, sparse_render

__all__ = ["simulate", "simulate_tris"]


def simulate_tris(tris, matrix="4x4", *, engine: str = "verilator", progress: bool = False, idle: int = 0,
                  seed: int = 1, workers: int = 2) -> dict:
    """Run every processor on ``tris``; returns the ``rasterhw sim`` keys plus per-level tests.
    ``idle``, ``seed`` (Verilator only): random idle clocks on every processor's input (see
    :func:`rasterhw.sim.sparse.verilator_run.run_processor_verilator`; processor ``(a, b)`` uses
    seed ``seed + 64 * b + a``). ``workers``: Verilator processors run at once (at most the
    machine's cores)."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    if engine == "pysim":
        from rasterhw.sim.sparse.hdl_run import run_processor as run
    elif engine == "verilator":
        from functools import partial

        from rasterhw.sim.sparse.verilator_run import pack_records, run_processor_verilator
    else:
        raise RasterhwError(f"sparse sim: engine must be 'pysim' or 'verilator', not {engine!r}")
    if idle and engine != "verilator":
        raise RasterhwError("sparse sim: idle input clocks are a Verilator bench setting")
    g = sparse_render(tris, (p, q), depth="fixed")
    gz = np.where(g.tri_id >= 0, np.rint(g.depth * (1 << tris.z_bits)), -1).astype(np.int64)
    recs = broadcast_records(tris)
    if engine == "verilator":
        run = partial(run_processor_verilator, packed=pack_records(recs), idle=idle)
    N = 1 << n
    loc_t = np.full((q, p, N, N), -1, dtype=np.int64)
    loc_z = np.full((q, p, N, N), -1, dtype=np.int64)
    t0 = time.perf_counter()
    per = []
    run_s = 0.0
    sim_cycles = 0
    procs = [(a, b) for b in range(q) for a in range(p)]
    if engine == "verilator":
        # the processors are independent simulator processes: two at a time on this machine's
        # cores (the build first, once); results are taken in processor order
        from concurrent.futures import ThreadPoolExecutor

        from rasterhw.sim.sparse.verilator_run import build

        build(n=n, p=p, q=q, z_bits=tris.z_bits)
        pool = ThreadPoolExecutor(max_workers=max(1, min(int(workers), os.cpu_count() or 1)))
        futures = [pool.submit(run, recs, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, seed=seed + 64 * b + a)
                   for a, b in procs]
        results = (f.result() for f in futures)
    else:
        pool = None
        results = (run(recs, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits) for a, b in procs)
    try:
        for (a, b), r in zip(procs, results, strict=True):
            loc_t[b, a], loc_z[b, a] = r["tri"], r["zq"]
            per.append(r)
            run_s += r.get("run_s", r.get("wall_s", 0.0))
            sim_cycles += r.get("sim_cycles", r["cycles"])
            if progress:
                print(f"processor ({a}, {b}): {r['cycles']} cycles, tests per level {r['tests']}", file=sys.stderr, flush=True)
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    wall = time.perf_counter() - t0
    ht, hz = interleave(loc_t), interleave(loc_z)
    mism = int(np.count_nonzero((ht != g.tri_id) | (hz != gz)))
    tests = np.array([r["tests"] for r in per])  # (P, n)
    golden_tests = g.tests_per_proc[:, 1:]
    return {"engine": engine, "cycles": int(max(r["cycles"] for r in per)), "clock_hz": None,
            "pixels_compared": int(ht.size), "mismatches": mism, "wall_s": round(wall, 3),
            "cycles_per_s": round(sim_cycles / run_s, 1) if run_s > 0 else None,
            "matrix": f"{p}x{q}", "n": n, "triangles": len(recs),
            "tests_per_level_hdl": tests.sum(axis=0).tolist(),
            "tests_match_golden": bool(np.array_equal(tests, golden_tests)),
            "max_stage_tests_per_processor": int(tests.max()), "writes": int(sum(r["writes"] for r in per)),
            "pixels_written_golden": int(g.pixels_written), "sim_cycles": int(sim_cycles),
            "run_s": round(run_s, 4)}


def simulate(scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False,
             matrix: str = "4x4") -> dict:
    """The registry's sim-block contract (``scene`` a Scene or a built-in name)."""
    if isinstance(scene, str):
        from rasterhw.golden_model.scenes import build_scene

        scene = build_scene(scene)
    p, q = parse_matrix(matrix)
    sparse_geometry(width, height, p, q)
    tris = run_geometry(scene, width, height)
    return simulate_tris(tris, (p, q), engine=engine, progress=progress)
