"""Random differential runs: every HDL block against its golden model, on Verilator.

``rasterhw soak --pixels N --seed S`` runs rounds of random stimulus through each block until
``N`` output pixels of that block have been compared bit for bit with the golden model (the
last round may overshoot). Every round draws its own settings from ``numpy.random`` seeded by
``(S, block, round)``: the same seed gives the same rounds, so a failure printed as
``seed S`` reproduces with ``--seed S --block NAME``.

What a round randomises, per block:

* ``pixelbus`` (SNU pixel bus, 1280 x 1024, Verilog RAM): address pattern (uniform,
  scan-line runs, columns, one bank), one or two pipelines, Z from the full 24 bits or a
  narrow range (ties between the pipelines), idle gaps before writes (none, sparse, dense);
  the banks' own busy time is the back-pressure. The whole frame (RGB and Z, draw buffer)
  and the cycle count are compared.
* ``zbm`` (ZB/M unit, interleave 2): random screen triangles or a random built-in scene
  (seeded), random idle gaps on the edge-pair input, seeded random back-pressure on the
  output (``stall``); every fourth round (0, 4, ...) also a random segment:merge clock ratio
  (half periods 2..7 ns each, the cocotb bench with Verilog-side clocks), the others equal
  clocks on the plain-Verilator bench; both double-Z samples of every pixel are compared.
* ``pxp`` (EXPERTS PXP, 512 x 512, anti-jagging (c)): random EXPERTS / cube scenes (seeded),
  random Sn x Pn and range method (static, i, ii); every PXP pixel is compared, and every
  line's cycle count: equal to the model's in half the rounds (input back to back, output
  always ready), no faster than the model's in the other half (random idle clocks on the
  input, random back-pressure on the output of the plain bench). Round 0 instead runs random
  lines through the cocotb bench with the same kinds of timing (stream checkers, scoreboards).
* ``sparse`` (sparse-raster video processors, 4 x 4 matrix, 256 x 256): random screen
  triangles (count, size; random idle clocks on every processor's input in most of these
  rounds) or a random cube scene; every processor's local memory (triangle index and depth) and
  per-level test counts are compared. Round 0 instead runs one random processor through the cocotb
  bench with random idle clocks on its input.

The vector Z-buffer machine has no HDL, so it has no round here.
"""

from __future__ import annotations

import inspect
import sys
import time
from collections.abc import Callable

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["BLOCKS", "run_soak"]


def _rng(seed: int, block: str, k: int) -> np.random.Generator:
    return np.random.default_rng([seed, sum(block.encode()) * 7919 + len(block), k])


# ---------------------------------------------------------------- SNU pixel bus
PB_W, PB_H = 1280, 1024
#: writes per pipeline kept in 65,534..131,070 so the bench's stimulus memory (a build
#: parameter) is always 2**17 words: one build for every round
PB_PIPE_WRITES = (66_000, 131_000)


def _pixelbus_round(rng: np.random.Generator) -> dict:
    from rasterhw.golden_model.snu import pixelbus as golden
    from rasterhw.golden_model.snu.formats import N_BANKS
    from rasterhw.golden_model.snu.pixelstream import PixelStream
    from rasterhw.sim.snu.pixelbus import run_cocotb_bench

    npix = PB_W * PB_H
    pipes = 1 if rng.random() < 0.25 else 2
    counts = [int(rng.integers(*PB_PIPE_WRITES)) for _ in range(pipes)]
    n = sum(counts)
    pattern = str(rng.choice(["uniform", "scanline", "vertical", "one-bank"]))
    if pattern == "uniform":
        addr = rng.integers(0, npix, n)
    elif pattern == "scanline":  # runs along lines from random starts
        run = int(rng.integers(4, 200))
        starts = rng.integers(0, npix, -(-n // run))
        addr = (starts[:, None] + np.arange(run)).ravel()[:n] % npix
    elif pattern == "vertical":  # runs down columns: one bank after another, W apart
        run = int(rng.integers(4, 200))
        starts = rng.integers(0, npix, -(-n // run))
        addr = (starts[:, None] + PB_W * np.arange(run)).ravel()[:n] % npix
    else:  # one bank: the worst case for the interleave
        bank = int(rng.integers(0, N_BANKS))
        addr = rng.integers(0, npix // N_BANKS, n) * N_BANKS + bank
        addr = np.minimum(addr, npix - 1)
    zmode = str(rng.choice(["full", "narrow"]))
    z = rng.integers(0, 1 << 24, n) if zmode == "full" else rng.integers(0, 16, n)
    pipe = np.repeat(np.arange(pipes), counts)
    order = rng.permutation(n)  # the pipelines' writes interleaved in a random order
    s = PixelStream(PB_W, PB_H, addr[order].astype(np.int64), rng.integers(0, 1 << 24, n),
                    z[order].astype(np.int64), pipe[order].astype(np.int64))
    idle = float(rng.choice([0.0, 0.05, 0.5]))
    gaps = rng.integers(1, 9, n) * (rng.random(n) < idle)
    acc = golden.pixelbus_accept_cycles(s, gaps=gaps)
    rgb, zz = golden.pixelbus_frame(s, accept=acc)
    cycles = int(acc.max()) + golden.MEM_CYCLE
    r = run_cocotb_bench(s, sim="verilator", gaps=gaps, expect={"rgb": rgb, "z": zz, "cycles": cycles})
    bad = int(np.count_nonzero((r["rgb"] != rgb) | (r["z"] != zz))) + int(r["cycles"] != cycles)
    return {"pixels": npix, "mismatches": bad, "run_s": r["run_s"],
            "settings": f"pattern={pattern} pipes={pipes} writes={n} z={zmode} idle={idle}"}


# ---------------------------------------------------------------- ZB/M unit
ZBM_W, ZBM_H, ZBM_I = 256, 256, 2
#: rounds keep at most this many edge pairs (9 loader words each, plus the end marker) and pass
#: one stimulus depth that holds them, so every round runs on one build of each bench
ZBM_MAX_EDGE_PAIRS = 1021
ZBM_SDEPTH = 16384
#: every this many rounds (from round 0) runs two clocks at a random ratio under cocotb; the
#: others run equal clocks on plain Verilator (several times faster per round)
ZBM_RATIO_EVERY = 4


def _first_triangles(tris, k: int):
    """The first ``k`` triangles of ``tris`` (submission order kept)."""
    from dataclasses import replace

    cut = {f: getattr(tris, f)[:k] for f in ("xy", "z", "zq", "colour", "poly_id")}
    if tris.uv is not None:
        cut["uv"] = tris.uv[:k]
    return replace(tris, **cut)


def _zbm_round(rng: np.random.Generator, k: int = 1) -> dict:
    from rasterhw.golden_model import zbm as G
    from rasterhw.golden_model.zbm.stimulus import random_triangles
    from rasterhw.golden_model.zbm.words import doublez_words
    from rasterhw.sim.zbm import driver as Z

    kind = str(rng.choice(["triangles", "scene"]))
    if kind == "triangles":
        n = int(rng.integers(50, 500))
        size = float(rng.uniform(3, 40))
        tris = random_triangles(rng, n, ZBM_W, ZBM_H, size=size)
        what = f"triangles n={n} size={size:.1f}"
    else:
        from rasterhw.golden_model.pipeline import run_geometry
        from rasterhw.golden_model.scenes import build_scene

        name = str(rng.choice(["c50", "c100", "zbm-5x5", "sp27"]))
        seed = int(rng.integers(0, 1 << 30))
        tris = run_geometry(build_scene(name, seed=seed), ZBM_W, ZBM_H)
        what = f"scene {name} seed={seed}"
    eps = G.edge_pairs(tris)
    if len(eps) > ZBM_MAX_EDGE_PAIRS:  # keep the first triangles: one bench build for every round
        keep = max(1, len(tris.xy) * ZBM_MAX_EDGE_PAIRS // len(eps) - 1)
        while len(eps) > ZBM_MAX_EDGE_PAIRS:
            tris = _first_triangles(tris, keep)
            eps = G.edge_pairs(tris)
            keep = max(1, keep * 9 // 10)
        what += f" (first {len(tris.xy)} triangles)"
    try:
        Z.check_edge_pairs(eps, ZBM_W, ZBM_H)
    except RasterhwError:  # more active pairs than the unit holds: not a frame it can draw
        return {"pixels": 0, "mismatches": 0, "run_s": 0.0, "settings": what + " (skipped: over capacity)"}
    gold = G.render_zbm(tris, interleave=ZBM_I)
    exp = doublez_words(gold.pixels)
    ratio = (int(rng.integers(2, 8)), int(rng.integers(2, 8)))
    stall = int(rng.choice([0, int(rng.integers(1, 256))]))
    gap_seed = int(rng.integers(0, 1 << 30)) if rng.random() < 0.7 else None
    seed = int(rng.integers(0, 1 << 30))
    if k % ZBM_RATIO_EVERY == 0:   # two clocks at a random ratio: the cocotb bench (Verilator --timing)
        r = Z.run_unit_bench([eps], width=ZBM_W, height=ZBM_H, interleave=ZBM_I, sim="verilator", ratio=ratio,
                             stall=stall, seed=seed, gap_seed=gap_seed, expect=exp, sdepth=ZBM_SDEPTH)
    else:   # equal clocks: the plain-Verilator bench (held cycle-exact with the cocotb one)
        from rasterhw.sim.zbm.fast import run_unit_fast

        ratio = (5, 5)
        r = run_unit_fast([eps], width=ZBM_W, height=ZBM_H, interleave=ZBM_I, stall=stall, seed=seed,
                          gap_seed=gap_seed, sdepth=ZBM_SDEPTH)
    bad = int(np.count_nonzero((r["s0"] != exp[0]) | (r["s1"] != exp[1])))
    bad += int(r.get("proto_errors", 0)) + int(not r.get("frames_ok", True))
    return {"pixels": ZBM_W * ZBM_H, "mismatches": bad, "run_s": r["run_s"],
            "settings": f"{what} ratio={ratio[0]}:{ratio[1]} stall={stall} gaps={'on' if gap_seed is not None else 'off'}"}


# ---------------------------------------------------------------- EXPERTS PXP
PXP_W, PXP_H = 512, 512


def _pxp_cocotb_round(rng: np.random.Generator) -> dict:
    """Random lines of a random frame through the PXP's cocotb bench: random idle clocks on the
    segment stream, random back-pressure on the pixel stream, stream checkers, scoreboards."""
    from rasterhw.golden_model.experts.model import render_frame
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.experts.pxp_cocotb import run_cocotb_bench
    from rasterhw.sim.experts.pxp_sim import job_list

    name = str(rng.choice(["experts-1000", "experts-tilt-1000", "c100"]))
    seed = int(rng.integers(0, 1 << 30))
    fr = render_frame(run_geometry(build_scene(name, seed=seed), PXP_W, PXP_H, z_bits=16), model="bit", aj="c")
    todo = []
    for y in sorted(rng.choice(PXP_H, 6, replace=False).tolist()):
        lo = int(rng.integers(0, PXP_W // 2))
        todo.append((y, lo, int(rng.integers(lo + 1, PXP_W + 1))))
    idle, stall = float(rng.choice([0.0, 0.2, 0.6])), float(rng.choice([0.0, 0.2, 0.6]))
    jb = job_list(fr, todo)
    what = f"cocotb: scene {name} seed={seed} lines={[t[0] for t in todo]} idle={idle} stall={stall}"
    try:
        run_cocotb_bench(jb, width=PXP_W, sim="verilator", idle=idle, stall=stall, seed=int(rng.integers(1 << 30)))
        bad = 0
    except RasterhwError as e:
        bad, what = 1, f"{what}: {e}"
    return {"pixels": int(jb["pixels"].size), "mismatches": bad, "run_s": 0.0, "settings": what}


def _pxp_round(rng: np.random.Generator, k: int = 1) -> dict:
    if k == 0:  # the first round of every soak: idle and back-pressure through the cocotb bench
        return _pxp_cocotb_round(rng)
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.experts.pxp_sim import simulate_scene

    name = str(rng.choice(["experts-1000", "experts-2000", "experts-tilt-1000", "experts-uneven", "c100", "sp27"]))
    seed = int(rng.integers(0, 1 << 30))
    sn, pn = int(rng.choice([1, 2, 4, 8])), int(rng.choice([1, 2, 4, 8]))
    ranges = str(rng.choice(["static", "i", "ii"]))
    # half the rounds cycle-exact (every line's finish time equal to the model's), half with random
    # input idle clocks and output back-pressure (pixels equal, no line faster than the model)
    idle, stall = (0, 0) if rng.random() < 0.5 else (int(rng.integers(0, 230)), int(rng.integers(0, 230)))
    r = simulate_scene(build_scene(name, seed=seed), PXP_W, PXP_H, engine="verilator", sn=sn, pn=pn, aj="c",
                       ranges=ranges, idle=idle, stall=stall, seed=int(rng.integers(1, 1 << 20)))
    bad = r["mismatches"] + r["cycle_mismatches"]
    return {"pixels": r["pixels_compared"], "mismatches": bad, "run_s": r["run_s"],
            "settings": f"scene {name} seed={seed} sn={sn} pn={pn} ranges={ranges} idle={idle} stall={stall}"}


# ---------------------------------------------------------------- sparse video processors
SP_W, SP_H = 256, 256


def _sparse_cocotb_round(rng: np.random.Generator) -> dict:
    """One random processor of the 4 x 4 matrix through its cocotb bench: random idle clocks on
    the broadcast input, a stream checker, the local memory and per-level tests read back."""
    from rasterhw.golden_model.reference import random_triangles
    from rasterhw.sim.sparse.vp_cocotb import run_cocotb_bench

    n, seed = int(rng.integers(5, 60)), int(rng.integers(0, 1 << 30))
    a, b = int(rng.integers(0, 4)), int(rng.integers(0, 4))
    idle = float(rng.choice([0.0, 0.3, 0.7]))
    tris = random_triangles(SP_W, SP_H, n, mean_area=float(rng.uniform(20, 2000)), seed=seed)
    what = f"cocotb: triangles n={n} seed={seed} processor=({a}, {b}) idle={idle}"
    try:
        r = run_cocotb_bench(tris, "4x4", a=a, b=b, sim="verilator", idle=idle, seed=int(rng.integers(1 << 30)))
        px, bad = r["words_read"], 0
    except RasterhwError as e:
        px, bad, what = (SP_W // 4) * (SP_H // 4), 1, f"{what}: {e}"
    return {"pixels": px, "mismatches": bad, "run_s": 0.0, "settings": what}


def _sparse_round(rng: np.random.Generator, k: int = 1) -> dict:
    from rasterhw.golden_model.reference import random_triangles
    from rasterhw.sim.sparse.sim import simulate, simulate_tris

    if k == 0:  # the first round of every soak: idle input through the cocotb bench
        return _sparse_cocotb_round(rng)

    if rng.random() < 0.6:
        n = int(rng.integers(20, 600))
        area = float(rng.uniform(5, 400))
        seed = int(rng.integers(0, 1 << 30))
        idle = int(rng.choice([0, 0, 40, 128, 220]))
        r = simulate_tris(random_triangles(SP_W, SP_H, n, mean_area=area, seed=seed), "4x4", engine="verilator",
                          idle=idle, seed=int(rng.integers(1, 1 << 20)))
        what = f"triangles n={n} area={area:.0f} seed={seed} idle={idle}"
    else:
        from rasterhw.golden_model.scenes import build_scene

        name = str(rng.choice(["c50", "c100", "sp8"]))
        seed = int(rng.integers(0, 1 << 30))
        r = simulate(build_scene(name, seed=seed), SP_W, SP_H, engine="verilator", matrix="4x4")
        what = f"scene {name} seed={seed}"
    bad = r["mismatches"] + int(not r["tests_match_golden"]) + int(r["writes"] != r["pixels_written_golden"])
    return {"pixels": r["pixels_compared"], "mismatches": bad, "run_s": r.get("run_s", 0.0), "settings": what}


#: block -> one random round (returns pixels compared, mismatches, settings)
BLOCKS: dict[str, Callable[[np.random.Generator], dict]] = {
    "pixelbus": _pixelbus_round,
    "zbm": _zbm_round,
    "pxp": _pxp_round,
    "sparse": _sparse_round,
}


def run_soak(*, pixels: int, seed: int, blocks: list[str] | None = None, progress: bool = True,
             max_rounds: int = 100_000) -> list[dict]:
    """Random rounds per block until ``pixels`` output pixels were compared; one row per block:
    ``block, rounds, pixels_compared, mismatches, wall_s, failures`` (the first few failing
    rounds: round number and settings)."""
    names = list(BLOCKS) if not blocks else blocks
    for b in names:
        if b not in BLOCKS:
            raise RasterhwError(f"no soak for block {b!r}; blocks: {', '.join(BLOCKS)}")
    if not isinstance(pixels, int) or pixels < 1:
        raise RasterhwError(f"--pixels must be a positive integer, not {pixels!r}")
    rows = []
    for b in names:
        t0 = time.perf_counter()
        done = bad = k = 0
        failures = []
        while done < pixels and k < max_rounds:
            fn = BLOCKS[b]
            r = fn(_rng(seed, b, k), k) if "k" in inspect.signature(fn).parameters else fn(_rng(seed, b, k))
            done += r["pixels"]
            bad += r["mismatches"]
            if r["mismatches"] and len(failures) < 5:
                failures.append({"round": k, "mismatches": r["mismatches"], "settings": r["settings"]})
            if progress:
                print(f"soak {b} round {k}: {r['pixels']} pixels, {r['mismatches']} mismatches ({r['settings']})",
                      file=sys.stderr, flush=True)
            k += 1
        rows.append({"block": b, "seed": seed, "rounds": k, "pixels_compared": done, "mismatches": bad,
                     "wall_s": round(time.perf_counter() - t0, 1), "failures": failures})
    return rows
