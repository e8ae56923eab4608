"""``rasterhw sim sparse --scene SCENE --matrix PxQ --engine ...``: every video processor of the
matrix in HDL on the scene, its interleaved local memories compared with the bit-accurate golden
model pixel by pixel (triangle index and quantised depth)."""

from __future__ import annotations

import itertools
import os
import sys
import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.sparse.cycles import KE_EDGES
from rasterhw.golden_model.sparse.fixed import broadcast_records, colour_rgb8
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave, sparse_render
from rasterhw.golden_model.sparse.stack import broadcast_records_rgb, coupled_stack_matrix
from rasterhw.golden_model.sparse.vpcycles import HDL_FIFO_DEPTH

__all__ = ["simulate", "simulate_coupled", "simulate_tris"]

#: ``hierarchical=None``: Verilator's hierarchical build from this many processors up (measured at
#: 1024² c300 4x4, docs/sparse.md: flat 1,173-2,229 s to build; hierarchical ~20 s, the clock loop slower)
HIER_FROM_CELLS = 16


def simulate_tris(tris, matrix="4x4", *, engine: str = "verilator", progress: bool = False, idle: int = 0,
                  seed: int = 1, workers: int = 2) -> dict:
    """Run every processor on ``tris``; returns the ``rasterhw sim`` keys plus per-level tests.
    ``idle``, ``seed``: random idle clocks on every processor's input (see
    :func:`rasterhw.sim.sparse.verilator_run.run_processor_verilator`; processor ``(a, b)`` uses
    seed ``seed + 64 * b + a``). ``workers``: Verilator processors run at once (at most the
    machine's cores)."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    from rasterhw.sim.sparse.verilator_run import run_processor_verilator

    if engine not in ("pysim", "verilator"):
        raise RasterhwError(f"sparse sim: engine must be 'pysim' or 'verilator', not {engine!r}")
    g = sparse_render(tris, (p, q), depth="fixed")
    gz = g.depth_words(tris.z_bits)
    recs = broadcast_records(tris)
    N = 1 << n
    loc_t = np.full((q, p, N, N), -1, dtype=np.int64)
    loc_z = np.full((q, p, N, N), -1, dtype=np.int64)
    t0 = time.perf_counter()
    per = []
    run_s = 0.0
    sim_cycles = 0
    procs = [(a, b) for b in range(q) for a in range(p)]
    def one(a, b):   # ProcessorBench on the generic engine
        return run_processor_verilator(tris, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, idle=idle,
                                       seed=seed + 64 * b + a, engine=engine)

    if engine == "verilator":
        # the processors are independent simulator processes: the first alone (it builds the bench
        # once), then two at a time on this machine's cores; results are taken in processor order
        from concurrent.futures import ThreadPoolExecutor

        first = one(*procs[0])
        pool = ThreadPoolExecutor(max_workers=max(1, min(int(workers), os.cpu_count() or 1)))
        futures = [pool.submit(one, a, b) for a, b in procs[1:]]
        results = itertools.chain([first], (f.result() for f in futures))
    else:
        pool = None
        results = (one(a, b) for a, b in procs)
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


def simulate_coupled(tris, matrix="4x4", *, engine: str = "verilator", fifo_depth: int = 64,
                     vp_fifo_depth: int | None = None, progress: bool = False, vp: str = "pipeline",
                     colour: bool = False, kp: int = 0, hierarchical: bool | None = None) -> dict:
    """The whole matrix in one simulation (``hdl/sparse/matrix.py``): the image against the golden
    model pixel by pixel, and the frame's cycles, broadcast stalls, FIFO peaks and every processor's
    busy cycles and per-level tests against the coupled matrix's golden cycle model
    (``golden_model/sparse/vpcycles.py``, ``coupled_matrix_vp``): ``cycle_mismatches`` counts
    the counters that differ. ``fifo_depth``: the input FIFOs' run-time limit (built
    :data:`~rasterhw.sim.sparse.matrix_run.IN_DEPTH` deep); ``vp_fifo_depth``: the FIFOs between
    the processor's levels (a build parameter): ``None`` is :data:`HDL_FIFO_DEPTH` (8, as the one-processor runs
    build it: a queue of windows inside the processor) or down to 2 (the paper gives no size; both
    ours; ``"vp_buffers"`` in the JSON says which). ``vp="stack"``: every
    processor the stack-based one (``hdl/sparse/stack_vp.py``), against the golden coupled model on
    the stack processors' service times (``stack.coupled_stack_matrix``); ``busy`` is then the processor's
    own count of the cycles it holds a record. ``colour``: the vertex colours broadcast as three
    more linear functions and written with the Z test, the HDL's colour memories against
    ``fixed.colour_rgb8`` (``colour_mismatches``; the frame image is then the HDL's colour); ``kp``:
    formula (5)'s cost of ``kp`` parameter additions per surviving window on ``k_e`` = 3 edge
    adders, in cycles, in the HDL and in both golden cycle models. ``hierarchical`` (Verilator):
    the cell verilated and compiled once (same results; a much shorter build, a slower clock loop);
    ``None`` (the default): hierarchical from :data:`HIER_FROM_CELLS` processors up (a flat 4x4 at
    1024² took 20-37 min to build, hierarchical 20 s), flat below."""
    from rasterhw.golden_model.sparse.vpcycles import coupled_matrix_vp
    from rasterhw.sim.sparse.matrix_run import IN_DEPTH, run_matrix

    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    if engine not in ("pysim", "verilator"):
        raise RasterhwError(f"sparse sim: engine must be 'pysim' or 'verilator', not {engine!r}")
    if vp == "stack" and vp_fifo_depth is not None:
        raise RasterhwError("sparse sim: --vp-fifo-depth is the pipeline processor's; the stack processor has no "
                            "inner FIFOs")
    if vp_fifo_depth is None:
        vp_fifo_depth = HDL_FIFO_DEPTH
    if isinstance(vp_fifo_depth, bool) or not isinstance(vp_fifo_depth, int) or not 2 <= vp_fifo_depth <= 64:
        raise RasterhwError(f"sparse sim: --vp-fifo-depth must be an integer in 2..64, not {vp_fifo_depth!r}")
    if vp not in ("pipeline", "stack"):
        raise RasterhwError(f"sparse sim: --vp must be 'pipeline' or 'stack', not {vp!r}")
    if not isinstance(colour, bool):
        raise RasterhwError(f"sparse sim: --colour is a flag, not {colour!r}")
    if isinstance(kp, bool) or not isinstance(kp, int) or not 0 <= kp <= 15:
        raise RasterhwError(f"sparse sim: --kp must be an integer in 0..15, not {kp!r}")
    if hierarchical is None:
        hierarchical = engine == "verilator" and p * q >= HIER_FROM_CELLS
    if not isinstance(hierarchical, bool) or (hierarchical and engine != "verilator"):
        raise RasterhwError("sparse sim: --hierarchical is a flag of the Verilator build")
    in_depth = IN_DEPTH  # one build for every run-time depth
    t0 = time.perf_counter()
    recs = broadcast_records_rgb(tris) if colour else broadcast_records(tris)
    kw = dict(n=n, p=p, q=q, limit=fifo_depth, z_bits=tris.z_bits, fifo_depth=vp_fifo_depth, in_depth=in_depth, vp=vp,
              colour=colour, kp=kp, ke=KE_EDGES)
    # the generic engine's testbench (MatrixFrameBench) on either engine
    h = run_matrix(tris, **kw, hierarchical=hierarchical, engine=engine)
    hdl_s = time.perf_counter() - t0
    t1 = time.perf_counter()
    g = sparse_render(tris, (p, q), depth="fixed", trace=True)
    gz = g.depth_words(tris.z_bits)
    if vp == "stack":
        gc = coupled_stack_matrix(tris, p, q, fifo_depth, kp=kp)
    else:
        gc = coupled_matrix_vp(g, fifo_depth, fifo_depth=vp_fifo_depth, kp=kp, ke=KE_EDGES)
    grgb = colour_rgb8(tris, g.tri_id, p, q) if colour else None
    golden_s = time.perf_counter() - t1
    mism = int(np.count_nonzero((h["tri"] != g.tri_id) | (h["zq"] != gz)))
    col = {}
    if colour:
        col = {"colour_mismatches": int(np.count_nonzero((h["rgb"] != grgb).any(axis=-1))),
               "colour_pixels_compared": int(h["tri"].size)}
    st = h["stats"]
    tests = np.stack([st[f"tests_{i}"] for i in range(1, n + 1)], axis=1)
    pairs = [(h["cycles"], gc["frame_cycles"]), (h["stall_cycles"], gc["stall_cycles"])]
    pairs += list(zip(st["fifo_peak"].tolist(), gc["fifo_peak"], strict=True))
    pairs += list(zip(st["busy_cycles"].tolist(), gc["busy"], strict=True))
    pairs += list(zip(tests.ravel().tolist(), np.asarray(gc["tests"]).ravel().tolist(), strict=True))
    cyc_mism = sum(int(a != b) for a, b in pairs)
    frame = h["cycles"]
    busy = st["busy_cycles"]
    if progress:
        print(f"coupled {p}x{q}: {frame} cycles (golden {gc['frame_cycles']}), stalls {h['stall_cycles']}, "
              f"FIFO peak {int(st['fifo_peak'].max())}", file=sys.stderr, flush=True)
    if colour:
        image = {"frame_rgb": h["rgb"].astype(np.uint8),
                 "frame_note": "the HDL's colour memories (R, G, B as linear functions), read out interleaved"}
    else:
        image = {"frame_rgb": depth_image(h["zq"], tris.z_bits),
                 "frame_note": "the HDL's video memory holds depth only: the image is its depth buffer (near = bright)"}
    return {"engine": engine, "coupled": True, "vp": vp, "cycles": frame, "clock_hz": None,
            "pixels_compared": int(h["tri"].size), "mismatches": mism, "cycle_mismatches": cyc_mism,
            "colour": colour, **col, "kp": kp, "ke": KE_EDGES,
            "cycles_compared": len(pairs), "matrix": f"{p}x{q}", "n": n, "triangles": len(recs),
            "fifo_depth": fifo_depth, "fifo_depth_built": in_depth, "vp_fifo_depth": vp_fifo_depth,
            "vp_buffers": ("none (stack processor)" if vp == "stack" else
                           f"ours ({vp_fifo_depth}-entry FIFOs between the levels)"),
            "hierarchical": hierarchical, "gp_issue_interval": 1,
            "frame_cycles": frame, "frame_cycles_golden": gc["frame_cycles"],
            "stall_cycles": h["stall_cycles"], "stall_cycles_golden": gc["stall_cycles"],
            "fifo_peak": st["fifo_peak"].tolist(), "fifo_peak_golden": gc["fifo_peak"],
            "fifo_peak_max": int(st["fifo_peak"].max()), "fifo_peak_max_golden": gc["fifo_peak_max"],
            "busy": busy.tolist(), "busy_golden": gc["busy"],
            "idle": (frame - busy).tolist(), "idle_golden": gc["idle"],
            "tests_per_level_hdl": tests.sum(axis=0).tolist(),
            "tests_match_golden": bool(np.array_equal(tests, g.tests_per_proc[:, 1:])),
            "writes": int(st["writes"].sum()), "pixels_written_golden": int(g.pixels_written),
            "readout_cycles": int(h["tri"].size),
            "sim_cycles": int(h["sim_cycles"]), "run_s": round(h["run_s"], 4), "build_s": round(h["build_s"], 2),
            "cycles_per_s": round(h["sim_cycles"] / h["run_s"], 1) if h["run_s"] > 0 else None,
            "hdl_wall_s": round(hdl_s, 3), "golden_wall_s": round(golden_s, 3),
            "wall_s": round(time.perf_counter() - t0, 3),
            **{k: h[k] for k in ("verilog_bytes_cell", "verilog_bytes_matrix") if k in h}, **image}


def depth_image(zq: np.ndarray, z_bits: int) -> np.ndarray:
    """(H, W, 3) uint8 grey image of a read-out depth buffer (-1 empty -> black; near -> bright)."""
    z = zq.astype(np.float64)
    grey = np.where(zq >= 0, 255.0 - 200.0 * z / float((1 << z_bits) - 1), 0.0)
    g = np.clip(np.rint(grey), 0, 255).astype(np.uint8)
    return np.repeat(g[..., None], 3, axis=2)


def simulate(scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False,
             matrix: str = "4x4", coupled: bool = True, fifo_depth: int = 64, vp_fifo_depth: int | None = None,
             vp: str = "pipeline", colour: bool = False, kp: int = 0, hierarchical: bool | None = None) -> dict:
    """The registry's sim-block contract (``scene`` a Scene or a built-in name). ``coupled``: the
    whole matrix in one simulation (:func:`simulate_coupled`); otherwise every processor alone on
    the full stream, one simulation each (:func:`simulate_tris`, ``"coupled": false``; its
    processors are built with eight-entry inner FIFOs, ours). ``vp_fifo_depth`` ``None``: the
    coupled matrix's default (:data:`HDL_FIFO_DEPTH`, ours)."""
    if isinstance(scene, str):
        from rasterhw.golden_model.scenes import build_scene

        scene = build_scene(scene)
    p, q = parse_matrix(matrix)
    sparse_geometry(width, height, p, q)
    tris = run_geometry(scene, width, height)
    if coupled:
        return simulate_coupled(tris, (p, q), engine=engine, fifo_depth=fifo_depth, vp_fifo_depth=vp_fifo_depth,
                                progress=progress, vp=vp, colour=colour, kp=kp, hierarchical=hierarchical)
    if fifo_depth != 64 or vp_fifo_depth is not None or vp != "pipeline" or colour or kp or hierarchical:
        raise RasterhwError("sparse sim: --fifo-depth, --vp-fifo-depth, --vp, --colour, --kp and --hierarchical are "
                            "options of the coupled matrix (drop --no-coupled)")
    return {**simulate_tris(tris, (p, q), engine=engine, progress=progress), "coupled": False}
