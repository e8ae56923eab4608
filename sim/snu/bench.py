"""``rasterhw bench`` rows of the SNU machine (a benchmark: it prints, it asserts nothing)."""

from __future__ import annotations


def bench(*, repeat: int = 11, hdl: bool = True, progress: bool = False) -> list[dict]:
    """Pixel-bus rows: the snu-100px frame as ``rasterhw sim pixelbus --engine verilator`` runs it
    (plain Verilator, clear + both pipelines' streams + swap, ``sim/snu/scene.py``; only with ``hdl``)."""
    if not hdl:
        return []
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.snu.scene import frame_run

    res = frame_run(build_scene("snu-100px"), 1280, 1024)
    return [
        {"name": "pixel bus, snu-100px 1280x1024 frame on plain Verilator, wall", "value": res["wall_s"],
         "unit": "s", "note": f"target < 5 s warm; build {res['build_s']:.0f} s of it; {res['pixels_compared']} "
                              f"pixels compared, {res['mismatches']} mismatches"},
        {"name": "pixel bus, plain Verilator simulation rate", "value": res["cycles_per_s"], "unit": "cycles/s",
         "note": f"target >= 1e6; {res['cycles']} bus cycles of the frame (clear, pixels, swap), clock loop only"},
    ]
