"""Soak round of the EXPERTS PXP (``rasterhw soak --block pxp``; sim/flow/soak.py runs it): the
span PXP (``rasterhw sim pxp``'s default; a timed line may not be faster than its resolve work).

A round (512 x 512, anti-jagging (c)) renders a random EXPERTS / cube scene (seeded) with random
Sn x Pn and range method (static, i, ii); every PXP pixel is compared, and every line's cycle
count: equal to the model's in half the rounds (input back to back, output always ready), no
faster than the model's in the other half (random idle clocks on the input, random back-pressure
on the pixel output: the Verilator engine's, ``scene.pxp_job``). Round 0 instead runs random
lines of the (line) PXP under cocotb (the generic cocotb engine on Verilator) with the same kinds of
timing (stream checkers on both ports; ``scene.check_jobs``).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.pxp_jobs import job_list
from rasterhw.sim.experts.scene import check_jobs, simulate_scene

__all__ = ["pxp_round"]

PXP_W, PXP_H = 512, 512


def _pxp_cocotb_round(rng: np.random.Generator) -> dict:
    """Random lines of a random frame through the PXP under cocotb: random idle clocks on the
    segment stream, random back-pressure on the pixel stream, stream checkers on both."""
    name = str(rng.choice(["experts-1000", "experts-tilt-1000", "c100"]))
    seed = int(rng.integers(0, 1 << 30))
    fr = render_frame(run_geometry(build_scene(name, seed=seed), PXP_W, PXP_H, z_bits=16), model="bit", aj="c")
    todo = []
    for y in sorted(rng.choice(PXP_H, 6, replace=False).tolist()):
        lo = int(rng.integers(0, PXP_W // 2))
        todo.append((y, lo, int(rng.integers(lo + 1, PXP_W + 1))))
    idle, stall = int(rng.choice([0, 51, 154])), int(rng.choice([0, 51, 154]))   # of 256: 0, 20 %, 60 %
    jb = job_list(fr, todo)
    what = f"cocotb: scene {name} seed={seed} lines={[t[0] for t in todo]} idle={idle} stall={stall}"
    try:
        r = check_jobs(jb, width=PXP_W, engine="cocotb-verilator", idle=idle, stall=stall,
                       seed=int(rng.integers(1, 1 << 30)))
        bad = r["pixel_mismatches"] + r["line_mismatches"]
    except RasterhwError as e:
        bad, what = 1, f"{what}: {e}"
    return {"pixels": int(jb["pixels"].size), "mismatches": bad, "run_s": 0.0, "settings": what}


def pxp_round(rng: np.random.Generator, k: int) -> dict:
    """Round ``k``: lines under cocotb for round 0, whole frames on plain Verilator after it."""
    if k == 0:  # the first round of every soak: idle and back-pressure through the cocotb bench
        return _pxp_cocotb_round(rng)
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
