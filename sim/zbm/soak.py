"""Soak round of the ZB/M unit (``rasterhw soak --block zbm``; sim/flow/soak.py runs it).

A round (interleave 2, 256 x 256) draws random screen triangles or a random built-in scene
(seeded), random idle gaps on the edge-pair input, seeded random back-pressure on the output
(``stall``); every fourth round (0, 4, ...) also a random segment:merge clock ratio (half
periods 2..7 ns each, the merge clock 1 ns behind, as the cocotb bench's Verilog-side clocks), the
others equal clocks in phase; every round on the generic Verilator engine with separate clocks
(one build for every ratio); both double-Z samples of every pixel are compared.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm.stimulus import first_triangles, random_triangles
from rasterhw.golden_model.zbm.words import doublez_words
from rasterhw.sim.zbm.edge_check import check_edge_pairs
from rasterhw.sim.zbm.scene import SPEED_BUILD, run_scene
from rasterhw.sim.zbm.testbench import bench_clocks

__all__ = ["zbm_round"]

ZBM_W, ZBM_H, ZBM_I = 256, 256, 2
#: rounds keep at most this many edge pairs (9 loader words each, plus the end marker) and pass
#: one stimulus depth that holds them, so every round runs on one build of each bench
ZBM_MAX_EDGE_PAIRS = 1021
ZBM_SDEPTH = 16384
#: every this many rounds (from round 0) runs two clocks at a random ratio; the others equal clocks
ZBM_RATIO_EVERY = 4


def zbm_round(rng: np.random.Generator, k: int) -> dict:
    """Round ``k``: two clocks at a random ratio when ``k % ZBM_RATIO_EVERY == 0``, else equal clocks."""
    kind = str(rng.choice(["triangles", "scene"]))
    if kind == "triangles":
        n = int(rng.integers(50, 500))
        size = float(rng.uniform(3, 40))
        tris = random_triangles(rng, n, ZBM_W, ZBM_H, size=size)
        what = f"triangles n={n} size={size:.1f}"
    else:
        name = str(rng.choice(["c50", "c100", "zbm-5x5", "sp27"]))
        seed = int(rng.integers(0, 1 << 30))
        tris = run_geometry(build_scene(name, seed=seed), ZBM_W, ZBM_H)
        what = f"scene {name} seed={seed}"
    eps = G.edge_pairs(tris)
    if len(eps) > ZBM_MAX_EDGE_PAIRS:  # keep the first triangles: one bench build for every round
        keep = max(1, len(tris.xy) * ZBM_MAX_EDGE_PAIRS // len(eps) - 1)
        while len(eps) > ZBM_MAX_EDGE_PAIRS:
            tris = first_triangles(tris, keep)
            eps = G.edge_pairs(tris)
            keep = max(1, keep * 9 // 10)
        what += f" (first {len(tris.xy)} triangles)"
    try:
        check_edge_pairs(eps, ZBM_W, ZBM_H)
    except RasterhwError:  # more active pairs than the unit holds: not a frame it can draw
        return {"pixels": 0, "mismatches": 0, "run_s": 0.0, "settings": what + " (skipped: over capacity)"}
    gold = G.render_zbm(tris, interleave=ZBM_I)
    exp = doublez_words(gold.pixels)
    ratio = (int(rng.integers(2, 8)), int(rng.integers(2, 8)))
    stall = int(rng.choice([0, int(rng.integers(1, 256))]))
    gap_seed = int(rng.integers(0, 1 << 30)) if rng.random() < 0.7 else None
    seed = int(rng.integers(0, 1 << 30))
    if k % ZBM_RATIO_EVERY == 0:   # two clocks at a random ratio, the merge clock 1 ns behind
        clocks = bench_clocks(ratio)
    else:   # equal clocks in phase
        ratio = (5, 5)
        clocks = bench_clocks(ratio, phase=0)
    # the engine's separate clocks (held cycle-exact with the cocotb bench at ratios:
    # tests/test_engine_clocks.py), one build for every round
    r = run_scene([eps], width=ZBM_W, height=ZBM_H, interleave=ZBM_I, stall=stall, seed=seed,
                  gap_seed=gap_seed, build={**SPEED_BUILD, "depth": ZBM_SDEPTH}, clocks=clocks)
    bad = int(np.count_nonzero((r["s0"] != exp[0]) | (r["s1"] != exp[1])))
    bad += int(r.get("proto_errors", 0)) + int(not r.get("frames_ok", True)) + int(r.get("overflow", 0))
    return {"pixels": ZBM_W * ZBM_H, "mismatches": bad, "run_s": r["run_s"],
            "settings": f"{what} ratio={ratio[0]}:{ratio[1]} stall={stall} gaps={'on' if gap_seed is not None else 'off'}"}
