"""Soak round of the sparse-raster video processors (``rasterhw soak --block sparse``;
sim/flow/soak.py runs it).

A round (4 x 4 matrix, 256 x 256) draws random screen triangles (count, size; random idle clocks
on every processor's input in most of these rounds) or a random cube scene through the whole matrix in one simulation (a random input FIFO depth; its
counters against the golden coupled cycle model too); every processor's local memory (triangle
index and depth) and per-level test counts are compared. Round 0 instead
runs one random processor through the cocotb bench with random idle clocks on its input.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.sparse.sim import simulate, simulate_tris
from rasterhw.sim.sparse.vp_cocotb import run_cocotb_bench

__all__ = ["sparse_round"]

SP_W, SP_H = 256, 256


def _sparse_cocotb_round(rng: np.random.Generator) -> dict:
    """One random processor of the 4 x 4 matrix through its cocotb bench: random idle clocks on
    the broadcast input, a stream checker, the local memory and per-level tests read back."""
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


def sparse_round(rng: np.random.Generator, k: int) -> dict:
    """Round ``k``: the cocotb bench for round 0, the whole matrix on plain Verilator after it."""
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
        name = str(rng.choice(["c50", "c100", "sp8"]))
        seed = int(rng.integers(0, 1 << 30))
        depth = int(rng.choice([1, 2, 8, 64]))
        r = simulate(build_scene(name, seed=seed), SP_W, SP_H, engine="verilator", matrix="4x4", fifo_depth=depth)
        what = f"scene {name} seed={seed}, whole matrix, input FIFO depth {depth}"
    bad = r["mismatches"] + int(not r["tests_match_golden"]) + int(r["writes"] != r["pixels_written_golden"])
    bad += r.get("cycle_mismatches", 0)  # the whole matrix: every counter against the coupled cycle model
    return {"pixels": r["pixels_compared"], "mismatches": bad, "run_s": r.get("run_s", 0.0), "settings": what}
