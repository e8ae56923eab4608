"""Benchmark (not a test): shadow polygons through vz2 against the VP200's table 5.

``rasterhw bench vzbuf`` / ``python -m rasterhw.sim.vzbuf.bench``: every scene with shadow
polygons at 512x512 through the paper-faithful algorithm 2 (``vz2``) and through the labelled
whole-array variant (:mod:`rasterhw.golden_model.vzbuf.wholearray`); fragments = real + shadow
pixels Z-tested (table 1's two pixel rows), per wall second, against the VP200's
843,730 px/s and 2059 ms on c300; peak traced memory of one run.
"""

from __future__ import annotations

import statistics
import sys
import time
import tracemalloc

from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.paper import (
    COLS,
    T1,
    T5,
    VP200_T5_C300_FRAGMENTS_PER_S,
    VP200_T5_C300_MS,
)
from rasterhw.golden_model.vzbuf.render import render_frame
from rasterhw.golden_model.vzbuf.wholearray import render_whole
from rasterhw.golden_model.vzbuf.workload import table1_light


def _time(fn, repeat):
    ts = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), min(ts), out


def _peak(fn) -> float:
    tracemalloc.start()
    tracemalloc.reset_peak()
    base, _ = tracemalloc.get_traced_memory()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return (peak - base) / 2**20


def bench(*, repeat: int = 3, hdl: bool = False, progress: bool = False, scenes=COLS) -> list[dict]:
    res = []
    for n in scenes:
        sc = table1_light(build_scene(n))
        vp_ms = T5["VP200"]["total"][n]
        vp_rate = (T1["pixels processed"][n] + T1["shadow pixels processed"][n]) / (vp_ms / 1e3) if vp_ms else None
        for label, fn in (("vz2", lambda sc=sc: render_frame(sc, 512, 512, alg=2, shadows="polygons")),
                          ("whole-array", lambda sc=sc: render_whole(sc, 512, 512, shadows="polygons"))):
            fn()  # warm
            s, best, out = _time(fn, repeat)
            if label == "vz2":
                frags = out.stats["pixels_real"] + out.stats["pixels_shadow"]
            else:
                frags = out["fragments_real"] + out["fragments_shadow"]
            rate = frags / s
            note = f"{n}, shadow polygons, 512x512, median of {repeat} wall runs (best {best * 1e3:.0f} ms)"
            res.append({"name": f"{n} {label} raw time", "value": s * 1e3, "unit": "ms",
                        "note": note + (f"; VP200 {vp_ms} ms (ratio {vp_ms / (s * 1e3):.2f}x)" if vp_ms else "; VP200 cell lost")})
            res.append({"name": f"{n} {label} fragments per second", "value": rate, "unit": "fragments/s",
                        "note": f"{frags:,} real + shadow fragments, median run (best run {frags / best:,.0f}/s)"
                                + (f"; VP200 {vp_rate:,.0f}/s, ours / VP200 = {rate / vp_rate:.1f}x" if vp_rate else "")})
            if n == "c300":
                res.append({"name": f"c300 {label} throughput / VP200", "value": rate / VP200_T5_C300_FRAGMENTS_PER_S,
                             "unit": "x", "note": f"against table 5's {VP200_T5_C300_FRAGMENTS_PER_S:,} px/s "
                                                  f"({VP200_T5_C300_MS} ms)"})
                res.append({"name": f"c300 {label} peak memory", "value": _peak(fn), "unit": "MiB",
                            "note": "tracemalloc peak of one run"})
            if progress:
                print(f"vzbuf bench: {res[-1]['name']}: {res[-1]['value']:.4g} {res[-1]['unit']}", file=sys.stderr)
    return res


if __name__ == "__main__":  # pragma: no cover
    for r in bench(repeat=3, progress=False):
        print(f"{r['name']:<45} {r['value']:>14,.2f} {r['unit']:<12} {r['note']}")
