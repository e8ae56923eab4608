"""EXPERTS bench: the golden model's speed on experts-1000 (no HDL block yet)."""

from __future__ import annotations

import time


def bench(*, repeat: int = 3, hdl: bool = False, progress: bool = False) -> list[dict]:
    from rasterhw.golden_model.experts.model import render_frame
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene

    tris = run_geometry(build_scene("experts-tilt-1000"), 512, 512, z_bits=16)
    out = []
    for model in ("float", "bit"):
        best = float("inf")
        for _ in range(max(repeat, 1)):
            t = time.perf_counter()
            render_frame(tris, model=model, aj="c")
            best = min(best, time.perf_counter() - t)
        out.append({"name": f"experts golden {model} model, experts-tilt-1000 frame (A.J. c)", "value": round(best, 4),
                    "unit": "s", "note": f"best of {max(repeat, 1)}; whole 512x512 frame, every SLP/PXP stage"})
    return out
