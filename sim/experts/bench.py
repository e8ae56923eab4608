"""EXPERTS bench: the golden model's speed, and (``hdl``) the experts-1000 frame through the PXP HDL
(the span PXP, the default of ``rasterhw sim pxp``) and through SLP + PXP HDL (``rasterhw sim experts``)
on Verilator."""

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
    if hdl:
        from rasterhw.sim.experts.scene import simulate_scene
        r = simulate_scene(build_scene("experts-1000"), 512, 512, engine="verilator", sn=8, pn=8, aj="c")
        note = (f"{r['pixels_compared']} pixels, {r['mismatches']} mismatches, {r['cycle_mismatches']} cycle "
                f"mismatches; {r['pxp_cycles_per_line_mean']} PXP cycles per scan line (8 x 8)")
        out += [{"name": "experts-1000 frame through the PXP HDL with A.J. (c) (Verilator), wall", "value": r["wall_s"], "unit": "s",
                 "note": note + f"; build {r['build_s']} s (0 when warm)"},
                {"name": "PXP HDL simulation rate (Verilator)", "value": r["cycles_per_s"], "unit": "cycles/s",
                 "note": f"{r['cycles']} cycles in {r['run_s']} s (clock loop only)"},
                {"name": "PXP cycles per scan line, experts-1000, 8 x 8", "value": r["pxp_cycles_per_line_mean"],
                 "unit": "cycles", "note": f"mean over the 4096 PXP lines ({r['pxp']} PXP)"}]
        from rasterhw.sim.experts.scene import simulate_frame
        f = simulate_frame(build_scene("experts-1000"), 512, 512, engine="verilator", sn=8, pn=8, aj="c")
        out.append({"name": "experts-1000 whole frame through SLP + span PXP HDL (Verilator), wall",
                    "value": f["wall_s"], "unit": "s",
                    "note": (f"{f['pixels_compared']} pixels, {f['mismatches']} mismatches, SLP "
                             f"{f['slp_cycle_mismatches']} / PXP {f['pxp_cycle_mismatches']} cycle mismatches; "
                             f"SLP {f['slp_clock_for_30fps_hz']} Hz, PXP {f['pxp_clock_for_30fps_hz']} Hz for "
                             "30 frames/s; target < 60 s warm")})
    return out
