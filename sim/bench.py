"""``rasterhw bench``: speed and memory figures. A benchmark prints; it asserts nothing.

Targets from the issues are printed beside each figure so a reader sees the gap at once.
"""

from __future__ import annotations

import statistics
import time
import tracemalloc

from tqdm import tqdm


def _median_time(fn, repeat: int) -> tuple[float, float]:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def _peak_mb(fn) -> float:
    tracemalloc.start()
    try:
        fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak / 2**20


def run_bench(*, repeat: int = 11, hdl: bool = True, progress: bool = True) -> list[dict]:
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import rasterise
    from rasterhw.golden_model.scenes import build_scene

    rows: list[dict] = []
    from rasterhw.sim.registry import load, machines

    benches = [(m.name, load(m.bench)) for m in machines().values() if m.bench]
    steps = ["c300 geometry", "c300 raster 512", "sp27 raster 512", "memory 1280x1024"] + [n for n, _ in benches]
    bar = tqdm(steps, desc="bench", disable=not progress, leave=False)

    def step(name):
        bar.set_postfix_str(name)
        bar.update(1)

    c300 = build_scene("c300")
    step("c300 geometry")
    med, _ = _median_time(lambda: run_geometry(c300, 512, 512), repeat)
    rows.append({"name": "geometry pipeline, c300, 512x512 (median)", "value": med * 1e3, "unit": "ms"})
    tris = run_geometry(c300, 512, 512)
    step("c300 raster 512")
    med, best = _median_time(lambda: rasterise(tris), repeat)
    rows.append({"name": "reference rasteriser, c300, 512x512 (median)", "value": med * 1e3, "unit": "ms",
                 "note": "target < 20 ms; paper's VP200 algorithm 2: 293 ms (paper's figure)"})
    rows.append({"name": "reference rasteriser, c300, 512x512 (best)", "value": best * 1e3, "unit": "ms"})
    step("sp27 raster 512")
    sp27 = run_geometry(build_scene("sp27"), 512, 512)
    med, _ = _median_time(lambda: rasterise(sp27), repeat)
    rows.append({"name": "reference rasteriser, sp27, 512x512 (median)", "value": med * 1e3, "unit": "ms"})
    step("memory 1280x1024")
    big = run_geometry(c300, 1280, 1024)
    peak = _peak_mb(lambda: rasterise(big))
    rows.append({"name": "reference rasteriser, c300, 1280x1024, peak traced memory", "value": peak,
                 "unit": "MB", "note": "target < 500 MB"})
    for name, fn in benches:
        step(name)
        rows += fn(repeat=repeat, hdl=hdl, progress=progress)
    bar.close()
    return rows
