"""``rasterhw bench`` rows of the ZB/M machine (a benchmark: it prints, it asserts nothing). Every
Verilator row runs a ZB/M testbench on the generic engine (``sim/engines/``)."""

from __future__ import annotations

import resource

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm.words import doublez_words, edge_pair_words
from rasterhw.sim.engines import run
from rasterhw.sim.testbench import compare, find_testbench
from rasterhw.sim.zbm.scene import PLAIN_BUILD, SPEED_BUILD, run_scene, simulate
from rasterhw.sim.zbm.testbench import deal

__all__ = ["bench", "chip_rate", "compare_builds"]


def compare_builds(tris, *, width: int, height: int, interleave: int, units: int = 1,
                   builds: dict[str, dict] | None = None, rounds: int = 3, base=None) -> dict[str, dict]:
    """The same frame through several Verilator builds of the ``zbm-unit`` testbench, alternating
    (round 1: every build, round 2: every build, ...; the machine's load changes across a minute, so
    the builds are compared in the same minutes), each frame compared with the golden one.
    ``builds``: ``{label: engine build settings}`` (default: :data:`PLAIN_BUILD` as ``"plain"``,
    :data:`SPEED_BUILD` with its profile trained as ``"speed"``). Every build is made (and trained)
    by a first run that is not counted. Returns per label ``{"cycles_per_s"`` (median of the
    rounds' clock-loop rates: wall clock, so it moves with the machine's load), ``"rates"``,
    ``"cycles"``, ``"mismatches"`` (pixels, worst round), ``"build_s"`` (cold build seconds of the
    first run), ``"build"``, ``"cpu_s"`` (the binary's CPU seconds per round: load, clock loop and
    dump)``}``. ``base`` (triangles of a smaller scene): also run it, on the same build (one input
    memory depth for both), every round, and give ``"cpu_cycles_per_s"`` = the cycles ``tris`` has
    more than ``base`` over the CPU seconds it takes more (medians): the clock loop's rate in CPU
    time, which the load moves much less."""
    builds = builds if builds is not None else {"plain": PLAIN_BUILD, "speed": {**SPEED_BUILD, "pgo": True}}

    def frame(t):
        eps = G.edge_pairs(t)
        return deal(eps, units), doublez_words(G.render_zbm(t, interleave=interleave, units=units).pixels)

    frames = {"main": frame(tris), **({"base": frame(base)} if base is not None else {})}
    depth = max(len(edge_pair_words(e)) for e in frames["main"][0]) + 2   # one build for both frames
    out: dict[str, dict] = {k: {"rates": [], "cycles": set(), "mismatches": 0, "cpu_s": [], "base_cpu_s": []}
                            for k in builds}

    def one(label, which):
        per, (g0, g1) = frames[which]
        c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        r = run_scene(per, width=width, height=height, interleave=interleave,
                      build={**builds[label], "depth": depth})
        c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        bad = int(np.count_nonzero((r["s0"] != g0) | (r["s1"] != g1)))
        return r, c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime, bad

    for label in builds:   # build (and train) first, not counted
        r, _, bad = one(label, "main")
        out[label].update(build_s=r["build_s"], build=r["build"], mismatches=bad)
    for _ in range(rounds):
        for label in builds:
            o = out[label]
            r, cpu, bad = one(label, "main")
            o["rates"].append(r["cycles"] / r["run_s"])
            o["cycles"].add(int(r["cycles"]))
            o["cpu_s"].append(cpu)
            o["mismatches"] = max(o["mismatches"], bad)
            if base is not None:
                rb, cpu_b, bad_b = one(label, "base")
                o["base_cpu_s"].append(cpu_b)
                o["base_cycles"] = int(rb["cycles"])
                o["mismatches"] = max(o["mismatches"], bad_b)
    for o in out.values():
        o["cycles_per_s"] = float(np.median(o["rates"]))
        o["cycles"] = sorted(o["cycles"])
        if base is not None:
            extra = float(np.median(o["cpu_s"]) - np.median(o["base_cpu_s"]))
            o["cpu_cycles_per_s"] = (o["cycles"][-1] - o["base_cycles"]) / extra if extra > 0 else float("nan")
    return out


def chip_rate(*, interleave: int = 8, width: int = 512, height: int = 512, scene: str = "c300",
              engine: str = "verilator") -> dict:
    """Segment-clock cycles per second of one chip (chip 0, the ``zbm-chip`` testbench on the generic
    ``engine``: plain Verilator at g++ -O2, or ``cocotb-verilator``) on ``scene``'s golden segments with an empty upstream, no gaps or
    back-pressure; every output word checked. Returns ``{"cycles", "run_s", "cycles_per_s",
    "mismatches", "build_s", ...}``."""
    tb = find_testbench("zbm-chip")
    p = tb.params(interleave=interleave, chip=0, width=width)
    segs = G.segment_generator(G.edge_pairs(run_geometry(build_scene(scene), width, height)), height, width=width)
    npx = -(-width // interleave)
    stim = tb.scene_stimulus(p, segs, [G.DoubleZ.empty((npx,)) for _ in range(height)], what=f"scene {scene}")
    exp = tb.expect(p, stim)
    got = run(tb, p, stim, engine=engine, expect_words={k: len(v) for k, v in exp.words.items()},
              build={"opt": "-O2"} if engine == "verilator" else None)
    c = compare(exp, got)
    return {"block": "zbm-chip", "engine": engine, "interleave": interleave, "width": width,
            "height": height, "scene": scene, "cycles": got.cycles, "run_s": got.run_s,
            "cycles_per_s": got.cycles / got.run_s, "mismatches": c["mismatches"] + got.protocol_errors,
            "build_s": got.build_s}


def bench(*, repeat: int = 11, hdl: bool = True, progress: bool = False) -> list[dict]:
    """ZB/M rows: c300 through a unit on Verilator (the build before issue 31 and the speed build,
    side by side), the chip rate with and without cocotb, pysim."""
    if not hdl:
        return []
    # before and after, in the same minutes: the build before issue 31 and the speed build (its
    # gcc profile trained on c50 here first if this design has none; sim zbm then uses it too)
    builds = compare_builds(run_geometry(build_scene("c300"), 512, 512), width=512, height=512, interleave=8,
                            rounds=5, base=run_geometry(build_scene("c50"), 512, 512))
    res = simulate(build_scene("c300"), 512, 512, interleave=8, engine="verilator")
    chip = chip_rate(interleave=8, engine="cocotb-verilator")
    fast = chip_rate(interleave=8)
    small = simulate(build_scene("c50"), 64, 64, interleave=8, engine="pysim")
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
                                     f"{res['run_s']:.2f} s of clock loop"},
        {"name": "ZB/M chip, preloaded c300 segments, Verilator + C++ main", "value": fast["cycles_per_s"],
         "unit": "cycles/s", "note": f"target >= 1e6; clock loop only, one pass of the frame (the zbm-chip "
                                     f"testbench); {fast['mismatches']} mismatches"},
        {"name": "ZB/M chip, same stimulus, Verilator under cocotb (the generic cocotb engine)",
         "value": chip["cycles_per_s"], "unit": "cycles/s",
         "note": f"the cocotb test's run time; {chip['mismatches']} mismatches"},
        {"name": "ZB/M unit, c50 64x64, interleave 8, Amaranth pysim rate", "value": small["cycles_per_s"],
         "unit": "cycles/s", "note": f"for comparison; {small['mismatches']} mismatches"},
    ]
