"""``rasterhw bench``: the sparse-raster golden search and the HDL video processors on c300 (it
asserts nothing; targets from issue 10 are printed beside the figures)."""

from __future__ import annotations

import statistics
import time

#: the paper gives τ (one coverage test) but no clock: frame times are also shown at this one
ASSUMED_CLOCK_HZ = 100e6


def bench(*, repeat: int = 5, hdl: bool = True, progress: bool = False) -> list[dict]:
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.sparse.search import sparse_render

    tris = run_geometry(build_scene("c300"), 512, 512)
    rows = []
    for m in ("2x2", "4x4", "8x8"):
        times = []
        for _ in range(max(1, repeat)):
            t0 = time.perf_counter()
            f = sparse_render(tris, m)
            times.append(time.perf_counter() - t0)
        med = statistics.median(times)
        rows.append({"name": f"sparse golden search c300 512x512 {m}", "value": round(med * 1e3, 2), "unit": "ms",
                     "note": f"{int(f.tests.sum())} coverage tests, {f.tests.sum() / med / 1e6:.1f} M tests/s "
                             "(NumPy, all processors at once)"})
    if hdl:
        from rasterhw.sim.sparse.scene import simulate_tris

        # one processor at a time: the rate of one simulator process, not of two sharing the cores
        r = simulate_tris(tris, "4x4", engine="verilator", progress=progress, workers=1)
        rows.append({"name": "sparse-vp verilator c300 4x4: simulation speed", "value": r["cycles_per_s"],
                     "unit": "cycles/s", "note": f"target >= 1 M; {r['sim_cycles']} cycles over 16 processors in "
                                                 f"{r['run_s']} s of clock loop, one processor at a time; "
                                                 f"mismatches {r['mismatches']}"})
        par = simulate_tris(tris, "4x4", engine="verilator", progress=progress)
        rows.append({"name": "sparse-vp verilator c300 4x4: scene run, wall", "value": par["wall_s"], "unit": "s",
                     "note": f"two processors at a time (as rasterhw sim sparse); mismatches {par['mismatches']}"})
        # the whole matrix in one simulation at the paper's 1024 x 1024 (issue 28's target: < 60 s warm)
        from rasterhw.sim.sparse.scene import simulate_coupled

        big = run_geometry(build_scene("c300"), 1024, 1024)
        simulate_coupled(big, "4x4", fifo_depth=64, progress=progress)  # build (cold) or reuse
        cp = simulate_coupled(big, "4x4", fifo_depth=64, progress=progress)
        rows.append({"name": "sparse-matrix verilator c300 1024x1024 4x4 coupled: scene run, wall (warm)",
                     "value": cp["wall_s"], "unit": "s",
                     "note": f"target < 60 s; processors: {cp['vp_buffers']}; "
                             f"{'hierarchical' if cp['hierarchical'] else 'flat'} build; "
                             f"clock loop {cp['run_s']} s for {cp['sim_cycles']} cycles (frame "
                             f"{cp['frame_cycles']} + read-out), golden cycle model {cp['golden_wall_s']} s; "
                             f"mismatches {cp['mismatches']}, cycle mismatches {cp['cycle_mismatches']}"})
        rows.append({"name": "sparse-vp c300 4x4: frame time (slowest processor)", "value": r["cycles"],
                     "unit": "cycles", "note": f"{r['cycles'] / ASSUMED_CLOCK_HZ * 1e3:.3f} ms at an assumed "
                                               f"{ASSUMED_CLOCK_HZ / 1e6:g} MHz (τ = 1 cycle; the paper gives no clock)"})
    return rows
