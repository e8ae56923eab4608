"""Soak round of the sparse-raster video processors (``rasterhw soak --block sparse``;
sim/flow/soak.py runs it).

A round draws random screen triangles (count, size; random idle clocks on every processor's input
in most of these rounds; 4 x 4 matrix, 256 x 256, every processor alone on the broadcast stream)
or a random cube scene through the whole matrix in one simulation (a random input FIFO depth; its
counters against the golden coupled cycle model too); every processor's local memory (triangle
index and depth) and per-level test counts are compared. Round 0 instead runs one random
processor of a 4 x 4 matrix under cocotb (the generic cocotb engine) with random idle clocks on its input.

``sparse_round`` (the registered round, ``make soak``) runs the whole matrix and the cocotb run
at the paper's 4 x 4 and 256 x 256. ``sparse_round_ci`` (the test suite's soak) runs the same
kinds of round on the designs the other sparse tests build: the whole matrix at 2 x 2, 32 x 32
with colour and (5)'s k_p = 4 (``tests/sparse/test_sparse_matrix.py``, ``test_sparse_colour_hdl.py``;
its colour compared too) and the cocotb run's 4 x 4 matrix at 32 x 32
(``tests/sparse/test_sparse_vp_cocotb.py``), so a test run compiles two fewer large models (the
4 x 4 whole matrix at 256 x 256 took 44 s of the 93 s the test took in a fresh run); the
triangle rounds (every processor of the 4 x 4 matrix at 256 x 256, ``ProcessorBench``: the design
``tests/sparse/test_sparse_vp_verilator.py`` builds) are the same in both.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.sparse.scene import check_processor, simulate, simulate_tris

__all__ = ["sparse_round", "sparse_round_ci"]

#: frame of the triangle rounds (every processor of the 4 x 4 matrix alone on the stream)
SP_W, SP_H = 256, 256
#: (width, height, matrix) of the whole-matrix rounds and of round 0's cocotb run
FULL = {"matrix": (256, 256, "4x4"), "cocotb": (256, 256, "4x4")}
CI = {"matrix": (32, 32, "2x2"), "cocotb": (32, 32, "4x4")}
#: the whole matrix's build options per kind of soak (``simulate`` keywords)
MATRIX_OPTIONS = {"full": {}, "ci": {"colour": True, "kp": 4}}


def _sparse_cocotb_round(rng: np.random.Generator, w: int, h: int, matrix: str) -> dict:
    """One random processor of the matrix under cocotb (the generic cocotb engine on Verilator):
    random idle clocks on the broadcast input, stream checkers, the local memory and per-level
    tests read back."""
    n, seed = int(rng.integers(5, 60)), int(rng.integers(0, 1 << 30))
    p, q = (int(v) for v in matrix.split("x"))
    a, b = int(rng.integers(0, p)), int(rng.integers(0, q))
    idle = int(rng.choice([0, 77, 179]))   # of 256: 0, 30 %, 70 %
    tris = random_triangles(w, h, n, mean_area=float(rng.uniform(20, 2000)) * (w * h) / (SP_W * SP_H), seed=seed)
    what = f"cocotb {w}x{h} {matrix}: triangles n={n} seed={seed} processor=({a}, {b}) idle={idle}"
    try:
        r = check_processor(tris, matrix, a=a, b=b, engine="cocotb-verilator", idle=idle,
                            seed=int(rng.integers(1 << 30)))
        px, bad = r["words_read"], r["mismatches"]
    except RasterhwError as e:
        px, bad, what = (w // p) * (h // q), 1, f"{what}: {e}"
    return {"pixels": px, "mismatches": bad, "run_s": 0.0, "settings": what}


def _round(rng: np.random.Generator, k: int, sizes: dict) -> dict:
    if k == 0:  # the first round of every soak: idle input through the cocotb bench
        return _sparse_cocotb_round(rng, *sizes["cocotb"])
    if rng.random() < 0.6:
        n = int(rng.integers(20, 600))
        area = float(rng.uniform(5, 400))
        seed = int(rng.integers(0, 1 << 30))
        idle = int(rng.choice([0, 0, 40, 128, 220]))
        r = simulate_tris(random_triangles(SP_W, SP_H, n, mean_area=area, seed=seed), "4x4", engine="verilator",
                          idle=idle, seed=int(rng.integers(1, 1 << 20)))
        what = f"triangles n={n} area={area:.0f} seed={seed} idle={idle}"
    else:
        w, h, matrix = sizes["matrix"]
        opts = MATRIX_OPTIONS["ci" if sizes is CI else "full"]
        name = str(rng.choice(["c50", "c100", "sp8"]))
        seed = int(rng.integers(0, 1 << 30))
        depth = int(rng.choice([1, 2, 8, 64]))
        r = simulate(build_scene(name, seed=seed), w, h, engine="verilator", matrix=matrix, fifo_depth=depth, **opts)
        what = f"scene {name} seed={seed}, whole {matrix} matrix {w}x{h}, input FIFO depth {depth}" + \
            "".join(f", {k} {v}" for k, v in opts.items())
    bad = r["mismatches"] + int(not r["tests_match_golden"]) + int(r["writes"] != r["pixels_written_golden"])
    bad += r.get("cycle_mismatches", 0)  # the whole matrix: every counter against the coupled cycle model
    bad += r.get("colour_mismatches", 0)
    return {"pixels": r["pixels_compared"], "mismatches": bad, "run_s": r.get("run_s", 0.0), "settings": what}


def sparse_round(rng: np.random.Generator, k: int) -> dict:
    """Round ``k``: the cocotb bench for round 0, random triangles or the whole 4 x 4 matrix at
    256 x 256 on plain Verilator after it."""
    return _round(rng, k, FULL)


def sparse_round_ci(rng: np.random.Generator, k: int) -> dict:
    """:func:`sparse_round` with the whole matrix at 2 x 2, 32 x 32 and the cocotb bench at 4 x 4,
    32 x 32 (the designs the other sparse tests build)."""
    return _round(rng, k, CI)
