"""``rasterhw bench`` rows of the ZB/M machine (a benchmark: it prints, it asserts nothing)."""

from __future__ import annotations


def bench(*, repeat: int = 11, hdl: bool = True, progress: bool = False) -> list[dict]:
    """ZB/M rows: c300 through a unit on Verilator, the chip rate with and without cocotb, pysim."""
    if not hdl:
        return []
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.zbm.chip_bench import chip_speed
    from rasterhw.sim.zbm.fast import chip_speed_fast
    from rasterhw.sim.zbm.scene_run import simulate_zbm

    res = simulate_zbm(build_scene("c300"), 512, 512, interleave=8, engine="verilator")
    chip = chip_speed(interleave=8, repeat=8)
    fast = chip_speed_fast(interleave=8, repeat=32)
    small = simulate_zbm(build_scene("c50"), 64, 64, interleave=8, engine="pysim")
    return [
        {"name": "ZB/M unit, c300 512x512, interleave 8, Verilator, wall", "value": res["wall_s"], "unit": "s",
         "note": f"target < 5 s warm; build {res.get('build_s', 0):.0f} s of it; {res['mismatches']} mismatches"},
        {"name": "ZB/M unit, plain Verilator + C++ main, simulation rate", "value": res["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; {res['cycles']} segment clocks of 8 chips + generator in "
                                     f"{res['sim_s']:.2f} s of clock loop"},
        {"name": "ZB/M chip, preloaded c300 segments, Verilator + C++ main", "value": fast["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; clock loop only; {fast['mismatches']} mismatches"},
        {"name": "ZB/M chip, same stimulus, Verilator under cocotb", "value": chip["cycles_per_s"],
         "unit": "cycles/s", "note": f"start-up included; {chip['mismatches']} mismatches"},
        {"name": "ZB/M unit, c50 64x64, interleave 8, Amaranth pysim rate", "value": small["cycles_per_s"],
         "unit": "cycles/s", "note": f"for comparison; {small['mismatches']} mismatches"},
    ]
