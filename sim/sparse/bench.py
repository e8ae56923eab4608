"""``rasterhw bench``: the sparse-raster golden search's speed on c300 (it asserts nothing)."""

from __future__ import annotations

import statistics
import time


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
    return rows
