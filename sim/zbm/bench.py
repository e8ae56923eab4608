"""``rasterhw bench`` rows of the ZB/M machine (a benchmark: it prints, it asserts nothing)."""

from __future__ import annotations


def bench(*, repeat: int = 11, hdl: bool = True, progress: bool = False) -> list[dict]:
    """ZB/M rows: c300 through a unit on Verilator (the build before issue 31 and the speed build,
    side by side), the chip rate with and without cocotb, pysim."""
    if not hdl:
        return []
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.zbm.chip_bench import chip_speed
    from rasterhw.sim.zbm.fast import chip_speed_fast, compare_builds
    from rasterhw.sim.zbm.scene_run import simulate_zbm

    # before and after, in the same minutes: the build before issue 31 and the speed build (its
    # gcc profile trained on c50 here first if this design has none; sim zbm then uses it too)
    builds = compare_builds(run_geometry(build_scene("c300"), 512, 512), width=512, height=512, interleave=8,
                            rounds=5, base=run_geometry(build_scene("c50"), 512, 512))
    res = simulate_zbm(build_scene("c300"), 512, 512, interleave=8, engine="verilator")
    chip = chip_speed(interleave=8, repeat=8)
    fast = chip_speed_fast(interleave=8, repeat=32)
    small = simulate_zbm(build_scene("c50"), 64, 64, interleave=8, engine="pysim")
    plain, speed = builds["plain"], builds["speed"]
    return [
        {"name": "ZB/M unit, c300 512x512, interleave 8, plain Verilator, build before issue 31 (one module per "
                 "instance, g++ -O1), simulation rate", "value": plain["cycles_per_s"], "unit": "cycles/s",
         "note": f"median of 5 rounds alternating with the row below; cycles {plain['cycles']}; "
                 f"{plain['mismatches']} mismatches"},
        {"name": "ZB/M unit, same frame, speed build (identical modules merged, pixel processor out of line, "
                 "g++ -O2 -march=native, link-time optimised, gcc PGO trained on c50), simulation rate", "value": speed["cycles_per_s"],
         "unit": "cycles/s",
         "note": f"target >= 3e5 (issue 31); {speed['cycles_per_s'] / plain['cycles_per_s']:.2f}x the row above; "
                 f"cycles {speed['cycles']}; {speed['mismatches']} mismatches"},
        {"name": "ZB/M unit, c300 512x512, build before issue 31, clock loop in CPU time", "unit": "cycles/s",
         "value": plain["cpu_cycles_per_s"],
         "note": "(cycles c300 - c50) / (CPU s c300 - c50), medians of 5 rounds: the binary's CPU time, which "
                 "the machine's load moves much less than the wall-clock rate above"},
        {"name": "ZB/M unit, c300 512x512, speed build, clock loop in CPU time", "unit": "cycles/s",
         "value": speed["cpu_cycles_per_s"],
         "note": f"target >= 3e5; {speed['cpu_cycles_per_s'] / plain['cpu_cycles_per_s']:.2f}x the row above"},
        {"name": "ZB/M unit, c300 512x512, interleave 8, Verilator, wall", "value": res["wall_s"], "unit": "s",
         "note": f"target < 5 s warm; build {res.get('build_s', 0):.0f} s of it; {res['mismatches']} mismatches"},
        {"name": "ZB/M unit, plain Verilator + C++ main (sim zbm's build), simulation rate",
         "value": res["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; {res['cycles']} segment clocks of 8 chips + generator in "
                                     f"{res['sim_s']:.2f} s of clock loop"},
        {"name": "ZB/M chip, preloaded c300 segments, Verilator + C++ main", "value": fast["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; clock loop only; {fast['mismatches']} mismatches"},
        {"name": "ZB/M chip, same stimulus, Verilator under cocotb", "value": chip["cycles_per_s"],
         "unit": "cycles/s", "note": f"start-up included; {chip['mismatches']} mismatches"},
        {"name": "ZB/M unit, c50 64x64, interleave 8, Amaranth pysim rate", "value": small["cycles_per_s"],
         "unit": "cycles/s", "note": f"for comparison; {small['mismatches']} mismatches"},
    ]
