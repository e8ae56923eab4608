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
    steps = ["c300 geometry", "c300 raster 512", "sp27 raster 512", "memory 1280x1024"]
    if hdl:
        steps += ["pixelbus verilator", "zbm verilator"]
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
    if hdl:
        step("pixelbus verilator")
        rows += _bench_pixelbus()
        step("zbm verilator")
        rows += _bench_zbm()
    bar.close()
    return rows


def _bench_pixelbus() -> list[dict]:
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.snu.gouraud import scan_convert
    from rasterhw.sim.snu.pixelbus import simulate_pixelbus

    tris = run_geometry(build_scene("snu-100px"), 1280, 1024, z_bits=24, z_far_is_zero=True)
    stream = scan_convert(tris)
    res = simulate_pixelbus(stream, engine="verilator", progress=False)
    return [
        {"name": "pixel bus, snu-100px 1280x1024 on Verilator, wall", "value": res["wall_s"], "unit": "s",
         "note": f"target < 60 s; {res['pixels_compared']} pixels compared, {res['mismatches']} mismatches"},
        {"name": "pixel bus, Verilator simulation rate", "value": res["cycles_per_s"], "unit": "cycles/s"},
    ]


def _bench_zbm() -> list[dict]:
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.zbm.driver import chip_speed, simulate_zbm
    from rasterhw.sim.zbm.fast import chip_speed_fast

    res = simulate_zbm(build_scene("c300"), 512, 512, interleave=8, engine="verilator")
    chip = chip_speed(interleave=8, repeat=8)
    fast = chip_speed_fast(interleave=8, repeat=32)
    small = simulate_zbm(build_scene("c50"), 64, 64, interleave=8, engine="pysim")
    return [
        {"name": "ZB/M unit, c300 512x512, interleave 8, Verilator, wall", "value": res["wall_s"], "unit": "s",
         "note": f"target < 60 s; build {res.get('build_s', 0):.0f} s of it; {res['mismatches']} mismatches"},
        {"name": "ZB/M unit, Verilator simulation rate", "value": res["cycles_per_s"], "unit": "cycles/s"},
        {"name": "ZB/M chip, preloaded c300 segments, Verilator + C++ main", "value": fast["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; clock loop only; {fast['mismatches']} mismatches"},
        {"name": "ZB/M chip, same stimulus, Verilator under cocotb", "value": chip["cycles_per_s"],
         "unit": "cycles/s", "note": f"start-up included; {chip['mismatches']} mismatches"},
        {"name": "ZB/M unit, c50 64x64, interleave 8, Amaranth pysim rate", "value": small["cycles_per_s"],
         "unit": "cycles/s", "note": f"for comparison; {small['mismatches']} mismatches"},
    ]
