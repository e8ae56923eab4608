"""The cocotb unit bench (``tests/zbm_cocotb/tb_zbm_unit.v``), a cross-check of the generic engines
(a test, not a user path: it is not in the package): a chain of ``zbm-unit``\\s on the
generated Verilog (``unit_verilog.py``), Verilog-side clocks with any ratio and phase,
edge pairs preloaded from a hex file and played out, merge words collected into a frame memory
and dumped, run under cocotb (``sim/engines/runner.py``) on Verilator or Icarus. With the golden
frame the cocotb test compares every line itself and can run the Python stream checkers
(``tests/zbm/test_zbm_cocotb.py``)."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.words import edge_pair_words
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    build_dir_for,
    get_sim,
    run_cocotb,
    verilator_make_flags,
)
from rasterhw.sim.workdirs import keep as keep_run_folder
from rasterhw.sim.workdirs import temp_run_folder
from rasterhw.sim.zbm.testbench import bench_clocks, unit_watchdog

from zbm_cocotb.stimfiles import GAP_BITS, read_hex_words, stimulus_depth, write_unit_stimulus
from zbm_cocotb.unit_verilog import chain_verilog

__all__ = ["BENCH_DIR", "SIM_ENV", "TEST_MODULE", "VERILATOR_ARGS", "bench_clocks", "expect_env", "plusargs",
           "run_unit_bench", "unit_watchdog"]

BENCH_DIR = Path(__file__).resolve().parent
TEST_MODULE = "zbm_cocotb.cocotb_zbm"
# Verilator: cocotb's runner passes --public-flat-rw, which makes every signal of the ~0.4 MB
# (chip) / 3 MB (unit, I = 8) generated Verilog public: Verilator then keeps every alias wire
# as a member, optimises nothing across them and writes megabytes of run-once constructor code
# (the 357 s first build and 5.5 k cycles/s of the c300 unit run). The benches read only the
# wrappers' own signals: zbm_public.vlt makes those (read-only) public and nothing else.
VERILATOR_ARGS = ("--no-public-flat-rw", str(BENCH_DIR / "zbm_public.vlt"))
#: the unit bench's Verilog beside the generated units: its top and the harness
UNIT_BENCH = (HARNESS_V, BENCH_DIR / "tb_zbm_unit.v")
# The cocotb test module imports NumPy inside the simulator process: one BLAS thread, so that
# idle OpenBLAS workers do not compete with the simulation for this machine's 2 cores.
SIM_ENV = {"OPENBLAS_NUM_THREADS": "1"}


def plusargs(ratio: tuple[int, int], stall: int, seed: int, maxcyc: int, phase: int = 1) -> list[str]:
    """Bench plusargs. ``phase`` (ns) delays the merge clock against the segment clock: 1 (the
    tests) puts every merge edge in its own simulator time slot; 0 (speed runs, equal clocks)
    lets both clocks tick in the same slots, half as many evaluations per cycle."""
    bench_clocks(ratio, phase)   # the ratio and phase checks (the engine's clocks of this bench)
    sh, mh = ratio
    if not 0 <= stall <= 255:
        raise RasterhwError(f"stall must be in 0..255, not {stall!r}")
    return [f"+sync_half={sh}", f"+merge_half={mh}", f"+merge_phase={phase}", f"+stall={stall}", f"+seed={seed}",
            f"+maxcyc={maxcyc}"]


def expect_env(expect, speed_run: bool) -> dict:
    """A bench run compares with the golden frame inside cocotb; without one it must be an
    explicit speed run whose caller compares the dump itself (simulate_zbm, chip_speed)."""
    if expect is None and not speed_run:
        raise RasterhwError("ZB/M bench: give the golden frame (expect=) or say speed_run=True")
    return {"ZBM_SPEED_RUN": "1"} if expect is None else {}


def run_unit_bench(eps_per_unit: list[G.EdgePairs], *, width: int, height: int, interleave: int,
                   sim: str | None = None, capacity: int = F.AEP_CAPACITY, ratio: tuple[int, int] = (5, 5),
                   stall: int = 0, seed: int = 1, gap_seed: int | None = None,
                   expect: tuple[np.ndarray, np.ndarray] | None = None, speed_run: bool = False,
                   check_protocol: bool = False,
                   keep: bool = False, phase: int = 1, schedule: str = "overlap", line_log: bool = False,
                   opt: str = "-O1", sdepth: int | None = None) -> dict:
    """Run a chain of units (unit k gets ``eps_per_unit[k]``) on the generated Verilog.

    ``ratio`` = (segment, merge) clock half periods in ns; ``stall`` = back-pressure level
    (0..255, ready low when a seeded 8-bit random number is below it); ``gap_seed`` = seed of
    the random idle gaps before input words (None: none); ``phase`` = merge clock delay in ns
    (1, or 0 for speed runs: see :func:`plusargs`).  With ``expect`` = (s0, s1) (H, W)
    golden words the cocotb test itself compares every scan line and (``check_protocol``)
    runs the Python stream checkers and in-order scoreboards. Without ``expect`` the caller must say
    ``speed_run=True`` (it compares the returned dump itself); else RasterhwError.
    ``opt``: C++ optimisation of the per-cycle code (``-O0`` for the small timing benches, whose
    build dominates). ``line_log``: also return ``line_cycles`` (H,): unit 0's segment-clock count in the merge
    cycle in which the last chip slot finished each merge output line. ``sdepth``: the bench's
    stimulus memory depth (a build parameter; default the smallest that holds the words): runs of
    different sizes that pass the same depth share one build.
    Returns ``{"s0", "s1": (H, W) uint64, "cycles", "proto_errors", "build_s", "run_s", ...}``.
    """
    exp_env = expect_env(expect, speed_run)   # before any work
    sim = get_sim(sim)
    units = len(eps_per_unit)
    t0 = time.perf_counter()
    srcs = chain_verilog(interleave=interleave, width=width, height=height, units=units, capacity=capacity,
                         schedule=schedule)
    words = [edge_pair_words(e) for e in eps_per_unit]
    total = sum(len(w) for w in words)
    sdepth = stimulus_depth(total, sdepth)
    params = {"I": interleave, "U": units, "W": width, "H": height, "GW": GAP_BITS, "SDEPTH": sdepth}
    # the .vlt is a build input too: a change to it must give a fresh build
    bdir = build_dir_for("zbm-unit", sim, sources=[*srcs, *UNIT_BENCH, BENCH_DIR / "zbm_public.vlt"], **params)
    bdir.mkdir(parents=True, exist_ok=True)
    run_dir = temp_run_folder(bdir)
    flat, index = write_unit_stimulus(run_dir, words, gap_seed)
    out_path = run_dir / "frame.hex"
    env = {"ZBM_BENCH": "unit", "ZBM_OUT": str(out_path), "ZBM_CHECK_PROTOCOL": "1" if check_protocol else "0",
           **exp_env, **SIM_ENV}
    if expect is not None:
        exp_path = run_dir / "expect.npz"
        np.savez(exp_path, s0=expect[0], s1=expect[1], interleave=interleave, units=units,
                 stim=np.array([f"{x:x}" for x in flat]), index=np.array(index, np.int64))
        env["ZBM_EXPECT"] = str(exp_path)
    maxcyc = unit_watchdog(total, width=width, height=height, stall=stall, ratio=ratio)
    t1 = time.perf_counter()
    timings: dict = {}
    with verilator_make_flags(opt, coroutines=True):
        run_cocotb(sources=[*srcs, *UNIT_BENCH], toplevel="tb_zbm_unit",
                   test_module=TEST_MODULE, testcase="zbm_unit_frame", build_dir=bdir, test_dir=run_dir, sim=sim,
                   parameters=params,
                   plusargs=[f"+stim={run_dir / 'stim.hex'}", f"+index={run_dir / 'index.hex'}", f"+out={out_path}",
                             *plusargs(ratio, stall, seed, maxcyc, phase),
                             *([f"+lines={run_dir / 'lines.hex'}"] if line_log else [])],
                   extra_env=env, timings=timings, verilator_args=VERILATOR_ARGS)
    t2 = time.perf_counter()
    meta = json.loads((run_dir / "result.json").read_text())
    s0, s1 = read_hex_words(out_path)
    if s0.size != width * height:
        raise RasterhwError(f"{out_path}: {s0.size} words, expected {width * height}")
    res = {"s0": s0.reshape(height, width), "s1": s1.reshape(height, width), **meta,
           "prepare_s": t1 - t0, "build_s": timings["build_s"], "run_s": timings["test_s"],
           "total_s": t2 - t0, "run_dir": run_dir if keep else None}
    if line_log:
        res["line_cycles"] = [int(v, 16) for v in (run_dir / "lines.hex").read_text().split()
                              if not v.startswith("//")]
    if keep or os.environ.get("ZBM_KEEP") == "1":
        keep_run_folder(run_dir)
    else:
        shutil.rmtree(run_dir, ignore_errors=True)
    return res
