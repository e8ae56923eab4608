"""``rasterhw bench`` rows of the SNU machine (a benchmark: it prints, it asserts nothing)."""

from __future__ import annotations


def bench(*, repeat: int = 11, hdl: bool = True, progress: bool = False) -> list[dict]:
    """Pixel-bus rows: snu-100px through the HDL on Verilator (only with ``hdl``)."""
    if not hdl:
        return []
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
