"""The cocotb chip bench (``tests/zbm_cocotb/tb_zbm_chip.v``): one ``zbm-chip`` on the generated
Verilog, segment words and upstream merge words preloaded and played out (gaps, clock ratios,
back-pressure as the unit bench)."""

from __future__ import annotations

import json
import os
import shutil
import time

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.words import doublez_words, merge_words, segment_words
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    build_dir_for,
    effective_opt,
    get_sim,
    run_cocotb,
    verilator_make_flags,
)
from rasterhw.sim.workdirs import temp_run_folder
from rasterhw.sim.zbm.testbench import random_gaps

from zbm_cocotb.stimfiles import GAP_BITS, memory_depth, read_hex_words, write_hex
from zbm_cocotb.unit_bench import (
    BENCH_DIR,
    SIM_ENV,
    TEST_MODULE,
    VERILATOR_ARGS,
    expect_env,
    plusargs,
)
from zbm_cocotb.unit_verilog import chip_verilog

__all__ = ["chip_stimulus", "run_chip_bench"]


def chip_stimulus(segs: G.Segments, lines: int, upstream: G.DoubleZ, *, chip: int, interleave: int,
                  width: int) -> tuple[list[int], list[int], tuple[np.ndarray, np.ndarray]]:
    """Segment-port words for lines ``0..lines-1`` (segments + end of line), upstream merge
    words (``upstream``: (lines, npx) DoubleZ, chip order) and the expected merge output
    ``merge(upstream, chip_scanline)`` as (s0, s1) (lines, npx) words."""
    seg_words = []
    exp = G.DoubleZ.empty((lines, upstream.z.shape[1]))
    for y in range(lines):
        seg_words += segment_words(segs, y)
        own, _ = G.chip_scanline(segs, y, chip, interleave, width)
        up = G.DoubleZ(upstream.z[y], upstream.a[y], upstream.c[y], upstream.tag[y])
        m = G.merge(up, own)
        exp.z[y], exp.a[y], exp.c[y], exp.tag[y] = m.z, m.a, m.c, m.tag
    return seg_words, merge_words(*doublez_words(upstream)), doublez_words(exp)


def run_chip_bench(seg_words: list[int], up_words: list[int], *, lines: int, chip: int, interleave: int,
                   width: int, sim: str | None = None, ratio: tuple[int, int] = (5, 5), stall: int = 0,
                   seed: int = 1, gap_seed: int | None = None, repeat: int = 1,
                   expect: tuple[np.ndarray, np.ndarray] | None = None, speed_run: bool = False,
                   check_protocol: bool = False,
                   phase: int = 1) -> dict:
    """Run one ``zbm-chip`` on the generated Verilog (see :func:`run_unit_bench` for the knobs);
    ``repeat`` plays the stimulus that many times (speed runs).  Returns ``{"s0", "s1":
    (lines, npx) uint64 of the last repetition, "cycles", "lines", "proto_errors", "run_s", ...}``."""
    exp_env = expect_env(expect, speed_run)   # before any work
    sim = get_sim(sim)
    t0 = time.perf_counter()
    p = {"interleave": interleave, "chip": chip, "width": width}
    src = chip_verilog(**p)
    npx = -(-(width - chip) // interleave)
    params = {"I": interleave, "CHIP": chip, "W": width, "L": lines, "GW": GAP_BITS,
              "SDEPTH": memory_depth(len(seg_words)), "MDEPTH": memory_depth(len(up_words))}
    bdir = build_dir_for("zbm-chip", sim, sources=[src, HARNESS_V, BENCH_DIR / "tb_zbm_chip.v", BENCH_DIR / "zbm_public.vlt"],
                         **params)
    bdir.mkdir(parents=True, exist_ok=True)
    run_dir = temp_run_folder(bdir)
    g = random_gaps(len(seg_words) + len(up_words), gap_seed)
    write_hex(run_dir / "seg.hex", seg_words, g[:len(seg_words)], F.LOOP_BITS)
    write_hex(run_dir / "up.hex", up_words, g[len(seg_words):], F.PIXEL2.width)
    out_path = run_dir / "out.hex"
    env = {"ZBM_BENCH": "chip", "ZBM_OUT": str(out_path), "ZBM_CHECK_PROTOCOL": "1" if check_protocol else "0",
           **exp_env, **SIM_ENV}
    if expect is not None:
        np.savez(run_dir / "expect.npz", s0=expect[0], s1=expect[1], repeat=repeat,
                 seg=np.array([f"{x:x}" for x in seg_words]), up=np.array([f"{x:x}" for x in up_words]))
        env["ZBM_EXPECT"] = str(run_dir / "expect.npz")
    maxcyc = repeat * (40 * len(seg_words) + 40 * lines * (npx + 16)) + 1000
    t1 = time.perf_counter()
    timings: dict = {}
    with verilator_make_flags(effective_opt("-O2"), coroutines=True):   # the level its key names
        run_cocotb(sources=[src, HARNESS_V, BENCH_DIR / "tb_zbm_chip.v"], toplevel="tb_zbm_chip",
                   test_module=TEST_MODULE, testcase="zbm_chip_lines", build_dir=bdir, test_dir=run_dir, sim=sim,
                   parameters=params,
                   plusargs=[f"+seg={run_dir / 'seg.hex'}", f"+up={run_dir / 'up.hex'}", f"+out={out_path}",
                             f"+nseg={len(seg_words)}", f"+nup={len(up_words)}", f"+repeat={repeat}",
                             *plusargs(ratio, stall, seed, maxcyc, phase)],
                   extra_env=env, timings=timings, verilator_args=VERILATOR_ARGS)
    t2 = time.perf_counter()
    meta = json.loads((run_dir / "result.json").read_text())
    s0, s1 = read_hex_words(out_path)
    res = {"s0": s0.reshape(lines, npx), "s1": s1.reshape(lines, npx), **meta, "prepare_s": t1 - t0,
           "build_s": timings["build_s"], "run_s": timings["test_s"], "total_s": t2 - t0}
    if os.environ.get("ZBM_KEEP") != "1":
        shutil.rmtree(run_dir, ignore_errors=True)
    return res
