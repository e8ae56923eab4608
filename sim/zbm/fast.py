"""ZB/M on plain Verilator: no cocotb, no ``--timing``.

``run_unit_fast`` is the scene-run path of ``rasterhw sim zbm --engine verilator`` (and of the
bench and the soak): the chained units of :func:`rasterhw.sim.zbm.run_unit_bench` inside
``cocotb_tests/zbm/fast/tb_zbm_unit_fast.v``, both clock domains on the main's one ``clk``
(what the cocotb bench does with equal, in-phase clocks), the same stimulus files, sinks,
seeded back-pressure and frame dump. ``tests/zbm/test_zbm_unit_fast.py`` holds it bit- and
cycle-exact with the cocotb bench.

``chip_speed_fast`` runs the same workload as :func:`rasterhw.sim.zbm.chip_speed` (chip 0,
``scene``'s golden segments, empty upstream, no gaps or back-pressure, played ``repeat``
times) on the generated ``zbm-chip`` Verilog inside ``cocotb_tests/zbm/fast/tb_zbm_fast.v``
(both clock domains on one ``clk`` input port), driven by a small C++ main
(``cocotb_tests/plain_main.cpp``, shared by every timing-free bench) that toggles the clock until ``done`` and times that
loop. The last repetition's output is compared bit for bit with ``chip_stimulus``'s expected
words. Builds go to ``build/zbm-fast-<hash>/`` (hash of the Verilog, parameters and bench
sources), so the second call with the same parameters only runs.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    REPO_ROOT,
    build_plain_verilator,
    plain_build_dir,
    run_plain_verilator,
)
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.workdirs import build_lock, release, temp_run_folder
from rasterhw.sim.workdirs import keep as keep_run_folder
from rasterhw.sim.zbm.chip_bench import chip_stimulus
from rasterhw.sim.zbm.stimfiles import (
    GAP_BITS,
    memory_depth,
    read_hex_words,
    stimulus_depth,
    write_hex,
    write_unit_stimulus,
)
from rasterhw.sim.zbm.unit_bench import run_unit_bench, unit_watchdog
from rasterhw.sim.zbm.unit_verilog import chain_verilog, chip_verilog

__all__ = ["FAST_DIR", "PGO_OPT", "PLAIN_BUILD", "SPEED_BUILD", "build_fast", "build_unit_fast", "chip_speed_fast",
           "compare_builds", "run_chip_fast", "run_unit_fast", "unit_profile"]

FAST_DIR = REPO_ROOT / "cocotb_tests" / "zbm" / "fast"
TOP = "tb_zbm_fast"


def build_fast(*, interleave: int, width: int, lines: int, chip: int, nseg: int, nup: int,
               opt: str = "-O2") -> tuple[Path, float]:
    """Build (once per parameter set) the timing-free chip bench; returns (binary, build seconds,
    0 if reused). ``opt``: g++ optimisation of the model (-O2 for speed runs; the small test uses
    -O0, which compiles several times faster)."""
    src = chip_verilog(interleave=interleave, chip=chip, width=width)
    params = {"I": interleave, "CHIP": chip, "W": width, "L": lines, "GW": GAP_BITS,
              "SDEPTH": memory_depth(nseg), "MDEPTH": memory_depth(nup)}
    # the chip's counter and line count come back in the main's JSON line
    return build_plain_verilator("zbm-fast", TOP, [src, HARNESS_V, FAST_DIR / "tb_zbm_fast.v"], params=params,
                                 opt=opt, defines={"RASTERHW_CYCLES": 1, "RASTERHW_LINES": 1})


def run_chip_fast(seg_words: list[int], up_words: list[int], *, lines: int, chip: int, interleave: int,
                  width: int, repeat: int = 1, opt: str = "-O2", keep: bool = False) -> dict:
    """Play ``chip_stimulus`` words through the timing-free bench; returns ``{"s0", "s1":
    (lines, npx) uint64 of the last repetition, "cycles" (the chip's counter when done, as the
    cocotb chip bench reports it), "sim_cycles" (rising edges simulated), "lines", "run_s"
    (the C++ clock loop only), "build_s"}``."""
    exe, build_s = build_fast(interleave=interleave, width=width, lines=lines, chip=chip,
                              nseg=len(seg_words), nup=len(up_words), opt=opt)
    npx = -(-(width - chip) // interleave)
    run_dir = temp_run_folder(exe.parent.parent)
    zero = np.zeros(len(seg_words) + len(up_words), np.int64)
    write_hex(run_dir / "seg.hex", seg_words, zero[:len(seg_words)], F.LOOP_BITS)
    write_hex(run_dir / "up.hex", up_words, zero[len(seg_words):], F.PIXEL2.width)
    out = run_dir / "out.hex"
    maxcyc = repeat * (40 * len(seg_words) + 40 * lines * (npx + 16)) + 1000
    meta = run_plain_verilator(exe, [f"+seg={run_dir / 'seg.hex'}", f"+up={run_dir / 'up.hex'}", f"+out={out}",
                                     f"+nseg={len(seg_words)}", f"+nup={len(up_words)}", f"+repeat={repeat}"],
                               run_dir=run_dir, maxcyc=maxcyc)
    s0, s1 = read_hex_words(out)
    if s0.size != lines * npx:
        raise RasterhwError(f"{out}: {s0.size} words, expected {lines * npx}")
    res = {"s0": s0.reshape(lines, npx), "s1": s1.reshape(lines, npx), **meta, "build_s": build_s,
           "run_dir": run_dir if keep else None}
    if keep or os.environ.get("ZBM_KEEP") == "1":
        keep_run_folder(run_dir)
    else:
        for f in run_dir.iterdir():
            f.unlink()
        run_dir.rmdir()
    return res


#: the build of ``rasterhw sim zbm --engine verilator`` (and the soak, the bench's "after" row):
#: each unit's identical modules merged, the pixel processor kept out of line
#: (``sim/zbm/unit_verilog.py``); with a gcc profile of the design (cached: ``pgo="auto"``, or
#: trained first: ``pgo=True``, see :func:`unit_profile`) g++ -O2 and profile-guided optimisation,
#: else g++ -O1 as before, so the test suite's cold builds (which never train) cost no more
SPEED_BUILD = {"merge": True, "opt": None}
#: g++ level of the profiled builds (and of the instrumented build that trains them)
PGO_OPT = "-O2"
#: the build before issue 31 (the bench's "before" row): one module per instance, g++ -O1
PLAIN_BUILD = {"merge": False, "opt": "-O1", "pgo": False}
#: the scene a unit's profile is trained on (the scenes it is checked on, c300 and the tests'
#: random triangles, are others)
TRAIN_SCENE = "c50"


def build_unit_fast(*, interleave: int, width: int, height: int, units: int, nwords: int,
                    capacity: int = F.AEP_CAPACITY, schedule: str = "overlap", opt: str = "-O1",
                    sdepth: int | None = None, merge: bool = False,
                    pgo: str | Path | None = None) -> tuple[Path, float]:
    """Build (once per parameter set and source content) the timing-free unit-chain bench;
    returns (binary, build seconds, 0 if reused). ``opt``: g++ optimisation of the per-cycle code;
    ``merge``: identical modules merged (:data:`SPEED_BUILD`); ``pgo``: ``"generate"`` or a
    profile folder (``rasterhw.sim.engines.runner.build_plain_verilator``)."""
    name, top, srcs, params = _unit_build(interleave=interleave, width=width, height=height, units=units,
                                          nwords=nwords, capacity=capacity, schedule=schedule, sdepth=sdepth,
                                          merge=merge)
    return build_plain_verilator(name, top, srcs, params=params, opt=opt, defines={"RASTERHW_CYCLES": 1}, pgo=pgo)


def _unit_build(*, interleave, width, height, units, nwords, capacity, schedule, sdepth, merge):
    srcs = chain_verilog(interleave=interleave, width=width, height=height, units=units, capacity=capacity,
                         schedule=schedule, merge=merge)
    params = {"I": interleave, "U": units, "W": width, "H": height, "GW": GAP_BITS,
              "SDEPTH": stimulus_depth(nwords, sdepth)}
    return ("zbm-unit-fast", "tb_zbm_unit_fast",
            [*srcs, HARNESS_V, FAST_DIR.parent / "tb_zbm_unit_core.v", FAST_DIR / "tb_zbm_unit_fast.v"], params)


def _profile_dir(gen_exe: Path) -> Path:
    """Where the profile of the instrumented build ``gen_exe`` is kept: named by that build's
    folder, whose name digests the Verilog, the bench, the parameters and the flags."""
    return BUILD_ROOT / "pgo" / gen_exe.parent.parent.name


def unit_profile(*, interleave: int, width: int, height: int, units: int, sdepth: int,
                 capacity: int = F.AEP_CAPACITY, schedule: str = "overlap", opt: str = PGO_OPT,
                 train: bool = True, scene: str = TRAIN_SCENE) -> Path | None:
    """The gcc profile of the merged unit-chain bench with these parameters: the instrumented
    build (``-fprofile-generate``) run once on ``scene`` (:data:`TRAIN_SCENE`; its triangles dealt to the
    units round-robin, as ``sim zbm`` does), kept in ``build/pgo/<that build>/``. Paid once per
    design: a cached profile is returned as it is; ``train=False`` returns None instead of
    training. A training run's frame is checked against the golden model (a wrong profile run is
    an error, not a profile)."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.zbm.words import doublez_words

    kw = {"interleave": interleave, "width": width, "height": height, "units": units, "capacity": capacity,
          "schedule": schedule, "opt": opt, "sdepth": sdepth, "merge": True}
    # named by the instrumented build's folder (its key), known without building it
    name, top, srcs, params = _unit_build(nwords=1, **{k: v for k, v in kw.items() if k != "opt"})
    prof = BUILD_ROOT / "pgo" / plain_build_dir(name, top, srcs, params=params, opt=opt,
                                                 defines={"RASTERHW_CYCLES": 1}, pgo="generate").name
    if (prof / "trained.json").exists():
        return prof
    if not train:
        return None
    exe, _ = build_unit_fast(nwords=1, pgo="generate", **kw)
    prof = _profile_dir(exe)
    with build_lock(prof, what="zbm profile"):
        if (prof / "trained.json").exists():
            return prof
        shutil.rmtree(prof, ignore_errors=True)
        prof.mkdir(parents=True)
        tris = run_geometry(build_scene(scene), width, height)
        eps = G.edge_pairs(tris)
        per = [eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)]
        r = _run_unit_exe(exe, per, width=width, height=height, stall=0, seed=1, gap_seed=None, line_log=False,
                          keep=False, profile=prof)
        gold = doublez_words(G.render_zbm(tris, interleave=interleave, units=units, capacity=capacity).pixels)
        if not (np.array_equal(r["s0"], gold[0]) and np.array_equal(r["s1"], gold[1])):
            shutil.rmtree(prof, ignore_errors=True)
            raise RasterhwError(f"zbm profile: the instrumented build's {scene} frame is not the golden one")
        (prof / "trained.json").write_text(json.dumps({"scene": scene, "cycles": r["cycles"],
                                                       "files": sorted(f.name for f in prof.glob("*.gcda"))}) + "\n")
    return prof


def run_unit_fast(eps_per_unit: list, *, width: int, height: int, interleave: int,
                  capacity: int = F.AEP_CAPACITY, schedule: str = "overlap", stall: int = 0, seed: int = 1,
                  gap_seed: int | None = None, line_log: bool = False, opt: str | None = SPEED_BUILD["opt"],
                  keep: bool = False, sdepth: int | None = None, merge: bool = SPEED_BUILD["merge"],
                  pgo: bool | str = "auto") -> dict:
    """Run a chain of units (unit k gets ``eps_per_unit[k]``) on plain Verilator.

    The build: :data:`SPEED_BUILD` by default (``merge``; ``opt`` None: -O2 with a profile, -O1
    without; a given level is used either way); ``pgo``: ``"auto"`` uses the
    design's cached profile when there is one (never trains: the test suite's builds stay
    plain), ``True`` trains it first if needed (:func:`unit_profile`; ``rasterhw bench`` and
    ``RASTERHW_PGO=1``), ``False`` never (the environment's ``RASTERHW_PGO=0`` turns ``"auto"``
    off as well). Every build gives the same words and cycles (``tests/zbm/test_zbm_build_speed.py``).

    Same arguments and result keys as :func:`rasterhw.sim.zbm.run_unit_bench` run with equal,
    in-phase clocks (``ratio=(5, 5)``, ``phase=0``) and ``speed_run=True``: ``{"s0", "s1": (H, W)
    uint64, "cycles", "overflow", "frames_ok", "proto_errors", "build_s", "run_s" (the C++ clock
    loop only), "sim_cycles", ["line_cycles"]}``."""
    from rasterhw.golden_model.zbm.words import edge_pair_words

    if not 0 <= stall <= 255:
        raise RasterhwError(f"stall must be in 0..255, not {stall!r}")
    env_pgo = os.environ.get("RASTERHW_PGO", "")
    if pgo == "auto" and env_pgo in ("0", "1"):
        pgo = env_pgo == "1"
    words = [edge_pair_words(e) for e in eps_per_unit]
    total = sum(len(w) for w in words)
    kw = {"interleave": interleave, "width": width, "height": height, "units": len(words), "capacity": capacity,
          "schedule": schedule}
    sdepth = stimulus_depth(total, sdepth)
    prof = None
    if pgo and merge:
        prof = unit_profile(**kw, sdepth=sdepth, opt=opt or PGO_OPT, train=pgo is True)
    opt = opt or (PGO_OPT if prof is not None else "-O1")
    exe, build_s = build_unit_fast(nwords=total, sdepth=sdepth, pgo=prof, merge=merge, opt=opt, **kw)
    res = _run_unit_exe(exe, eps_per_unit, width=width, height=height, stall=stall, seed=seed, gap_seed=gap_seed,
                        line_log=line_log, keep=keep)
    return {**res, "build_s": build_s, "build": {"merge": merge, "opt": opt, "pgo": prof is not None}}


def _run_unit_exe(exe: Path, eps_per_unit: list, *, width: int, height: int, stall: int, seed: int,
                  gap_seed: int | None, line_log: bool, keep: bool, profile: Path | None = None) -> dict:
    """One run of a unit-chain bench binary (see :func:`run_unit_fast`)."""
    from rasterhw.golden_model.zbm.words import edge_pair_words

    words = [edge_pair_words(e) for e in eps_per_unit]
    total = sum(len(w) for w in words)
    run_dir = temp_run_folder(exe.parent.parent)
    try:
        write_unit_stimulus(run_dir, words, gap_seed)
        out = run_dir / "frame.hex"
        plus = [f"+stim={run_dir / 'stim.hex'}", f"+index={run_dir / 'index.hex'}", f"+out={out}",
                f"+meta={run_dir / 'meta.json'}", f"+stall={stall}", f"+seed={seed}",
                *([f"+lines={run_dir / 'lines.hex'}"] if line_log else [])]
        maxcyc = unit_watchdog(total, width=width, height=height, stall=stall)   # the cocotb bench's
        meta = run_plain_verilator(exe, plus, run_dir=run_dir, maxcyc=maxcyc, profile=profile)
        meta.update(json.loads((run_dir / "meta.json").read_text()))
        s0, s1 = read_hex_words(out)
        if s0.size != width * height:
            raise RasterhwError(f"{out}: {s0.size} words, expected {width * height}")
        res = {"s0": s0.reshape(height, width), "s1": s1.reshape(height, width), **meta,
               "run_dir": run_dir if keep else None}
        if line_log:
            res["line_cycles"] = [int(v, 16) for v in (run_dir / "lines.hex").read_text().split()
                                  if not v.startswith("//")]
    finally:
        if keep or os.environ.get("ZBM_KEEP") == "1":
            keep_run_folder(run_dir)
        else:
            release(run_dir)
    return res


def run_units_equal_clocks(per_unit: list, *, width: int, height: int, interleave: int, engine: str,
                           schedule: str, line_log: bool = False) -> dict:
    """A chain of units with equal, in-phase clocks (the Table 1, skew and chain runs): on
    Verilator the plain bench (:func:`run_unit_fast`, held word-, cycle- and line-log-exact with
    the cocotb bench by ``tests/zbm/test_zbm_unit_fast.py``; it builds and runs several times
    faster), on Icarus the cocotb bench. ``-O0``: these frames are small, the build is what costs."""
    if engine == "verilator":
        return run_unit_fast(per_unit, width=width, height=height, interleave=interleave, schedule=schedule,
                             line_log=line_log, opt="-O0")
    return run_unit_bench(per_unit, width=width, height=height, interleave=interleave, sim=engine, phase=0,
                          speed_run=True, schedule=schedule, line_log=line_log, opt="-O0")


def compare_builds(tris, *, width: int, height: int, interleave: int, units: int = 1,
                   builds: dict[str, dict] | None = None, rounds: int = 3, base=None) -> dict[str, dict]:
    """The same frame through several builds of the unit bench, alternating (round 1: every
    build, round 2: every build, ...; the machine's load changes across a minute, so the builds
    are compared in the same minutes), each frame compared with the golden one. ``builds``:
    ``{label: run_unit_fast build arguments}`` (default: :data:`PLAIN_BUILD` as ``"plain"``,
    :data:`SPEED_BUILD` with PGO as ``"speed"``). Every build is made (and trained) by a first run
    that is not counted. Returns per label ``{"cycles_per_s"`` (median of the rounds' clock-loop
    rates: wall clock, so it moves with the machine's load), ``"rates"``, ``"cycles"``,
    ``"mismatches"`` (pixels, worst round), ``"build_s"`` (cold build seconds of the first run),
    ``"build"``, ``"cpu_s"`` (the binary's CPU seconds per round: load, clock loop and dump)``}``.
    ``base`` (triangles of a smaller scene): also run it, on the same build, every round, and give
    ``"cpu_cycles_per_s"`` = the cycles ``tris`` has more than ``base`` over the CPU seconds it
    takes more (medians): the clock loop's rate in CPU time, which the load moves much less."""
    import resource

    from rasterhw.golden_model.zbm.words import doublez_words

    builds = builds if builds is not None else {"plain": PLAIN_BUILD, "speed": {**SPEED_BUILD, "pgo": True}}

    def frame(t):
        eps = G.edge_pairs(t)
        return ([eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)],
                doublez_words(G.render_zbm(t, interleave=interleave, units=units).pixels))

    from rasterhw.golden_model.zbm.words import edge_pair_words

    frames = {"main": frame(tris), **({"base": frame(base)} if base is not None else {})}
    sdepth = stimulus_depth(sum(len(edge_pair_words(e)) for e in frames["main"][0]))   # one build for both
    out: dict[str, dict] = {k: {"rates": [], "cycles": set(), "mismatches": 0, "cpu_s": [], "base_cpu_s": []}
                            for k in builds}

    def one(label, which):
        per, (g0, g1) = frames[which]
        c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        r = run_unit_fast(per, width=width, height=height, interleave=interleave, sdepth=sdepth, **builds[label])
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


def chip_speed_fast(*, interleave: int = 8, width: int = 512, height: int = 512, scene: str = "c300",
                    repeat: int = 8) -> dict:
    """Segment-clock cycles per second of one chip (chip 0) on the stimulus of
    :func:`rasterhw.sim.zbm.chip_speed`, on plain Verilator; the last repetition is checked
    bit for bit. Returns ``{"cycles", "run_s", "cycles_per_s", "mismatches", "build_s", ...}``."""
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.pipeline import run_geometry

    tris = run_geometry(load_scene(scene), width, height)
    segs = G.segment_generator(G.edge_pairs(tris), height, width=width)
    npx = -(-width // interleave)
    up = G.DoubleZ.empty((height, npx))
    seg_w, up_w, exp = chip_stimulus(segs, height, up, chip=0, interleave=interleave, width=width)
    r = run_chip_fast(seg_w, up_w, lines=height, chip=0, interleave=interleave, width=width, repeat=repeat)
    bad = int(np.count_nonzero((r["s0"] != exp[0]) | (r["s1"] != exp[1])))
    return {"block": "zbm-chip", "engine": "verilator-notiming", "interleave": interleave, "width": width,
            "height": height, "scene": scene, "repeat": repeat, "cycles": r["cycles"],
            "sim_cycles": r["sim_cycles"], "run_s": r["run_s"], "cycles_per_s": r["cycles"] / r["run_s"],
            "mismatches": bad, "lines": r["lines"], "build_s": r["build_s"]}


if __name__ == "__main__":  # python -m rasterhw.sim.zbm.fast [repeat]
    import sys

    print(json.dumps(chip_speed_fast(repeat=int(sys.argv[1]) if len(sys.argv) > 1 else 8)))
