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
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    REPO_ROOT,
    build_plain_verilator,
    run_plain_verilator,
)
from rasterhw.sim.workdirs import keep as keep_run_folder
from rasterhw.sim.workdirs import release, temp_run_folder
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

__all__ = ["FAST_DIR", "build_fast", "run_chip_fast", "chip_speed_fast", "build_unit_fast", "run_unit_fast"]

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


def build_unit_fast(*, interleave: int, width: int, height: int, units: int, nwords: int,
                    capacity: int = F.AEP_CAPACITY, schedule: str = "overlap", opt: str = "-O1",
                    sdepth: int | None = None) -> tuple[Path, float]:
    """Build (once per parameter set and source content) the timing-free unit-chain bench;
    returns (binary, build seconds, 0 if reused). ``-O1`` by default: the I = 8 unit's per-cycle
    code is megabytes, and -O2 doubles its compile time for a few per cent of run speed."""
    srcs = chain_verilog(interleave=interleave, width=width, height=height, units=units, capacity=capacity,
                         schedule=schedule)
    params = {"I": interleave, "U": units, "W": width, "H": height, "GW": GAP_BITS,
              "SDEPTH": stimulus_depth(nwords, sdepth)}
    return build_plain_verilator("zbm-unit-fast", "tb_zbm_unit_fast",
                                 [*srcs, HARNESS_V, FAST_DIR.parent / "tb_zbm_unit_core.v", FAST_DIR / "tb_zbm_unit_fast.v"],
                                 params=params, opt=opt,
                                 defines={"RASTERHW_CYCLES": 1})


def run_unit_fast(eps_per_unit: list, *, width: int, height: int, interleave: int,
                  capacity: int = F.AEP_CAPACITY, schedule: str = "overlap", stall: int = 0, seed: int = 1,
                  gap_seed: int | None = None, line_log: bool = False, opt: str = "-O1",
                  keep: bool = False, sdepth: int | None = None) -> dict:
    """Run a chain of units (unit k gets ``eps_per_unit[k]``) on plain Verilator.

    Same arguments and result keys as :func:`rasterhw.sim.zbm.run_unit_bench` run with equal,
    in-phase clocks (``ratio=(5, 5)``, ``phase=0``) and ``speed_run=True``: ``{"s0", "s1": (H, W)
    uint64, "cycles", "overflow", "frames_ok", "proto_errors", "build_s", "run_s" (the C++ clock
    loop only), "sim_cycles", ["line_cycles"]}``."""
    from rasterhw.golden_model.zbm.words import edge_pair_words

    if not 0 <= stall <= 255:
        raise RasterhwError(f"stall must be in 0..255, not {stall!r}")
    words = [edge_pair_words(e) for e in eps_per_unit]
    total = sum(len(w) for w in words)
    exe, build_s = build_unit_fast(interleave=interleave, width=width, height=height, units=len(words),
                                   nwords=total, capacity=capacity, schedule=schedule, opt=opt, sdepth=sdepth)
    run_dir = temp_run_folder(exe.parent.parent)
    try:
        write_unit_stimulus(run_dir, words, gap_seed)
        out = run_dir / "frame.hex"
        plus = [f"+stim={run_dir / 'stim.hex'}", f"+index={run_dir / 'index.hex'}", f"+out={out}",
                f"+meta={run_dir / 'meta.json'}", f"+stall={stall}", f"+seed={seed}",
                *([f"+lines={run_dir / 'lines.hex'}"] if line_log else [])]
        maxcyc = unit_watchdog(total, width=width, height=height, stall=stall)   # the cocotb bench's
        meta = run_plain_verilator(exe, plus, run_dir=run_dir, maxcyc=maxcyc)
        meta.update(json.loads((run_dir / "meta.json").read_text()))
        s0, s1 = read_hex_words(out)
        if s0.size != width * height:
            raise RasterhwError(f"{out}: {s0.size} words, expected {width * height}")
        res = {"s0": s0.reshape(height, width), "s1": s1.reshape(height, width), **meta, "build_s": build_s,
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
