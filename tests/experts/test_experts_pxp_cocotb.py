"""The PXP under cocotb (the generic cocotb engine, ``sim/engines/cocotb.py``, on Verilator; on
Icarus when installed): the PXP's testbench (``PxpBench``) with idle input clocks, output
back-pressure and stream checkers on both ports, against the golden PXP (``scene.check_jobs``:
every pixel in order, every line's finish-time counter). These tests checked the PXP's own
cocotb bench before it was retired for the generic engine; their assertions are the same."""

from __future__ import annotations

import shutil
from functools import cache

import pytest
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.pxp_jobs import job_list
from rasterhw.sim.experts.scene import check_jobs

pytestmark = pytest.mark.cocotb

SIMS = ["cocotb-verilator", pytest.param("cocotb-icarus", marks=pytest.mark.skipif(
    shutil.which("iverilog") is None, reason="iverilog not on PATH"))]


@cache
def _frame(name: str, aj: str):
    return render_frame(run_geometry(build_scene(name), 512, 512, z_bits=16), model="bit", aj=aj)


def _jobs(name="experts-tilt-1000", aj="c", lines=range(200, 206)):
    # ranges at odd alignments, one of them empty of segments near the frame edge
    todo = [(y, lo, hi) for y in lines for lo, hi in ((0, 64), (61, 190), (448, 512))]
    return job_list(_frame(name, aj), todo)


@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.heavy
def test_cocotb_pxp_cycle_exact_free_running(sim):
    jb = _jobs()
    r = check_jobs(jb, width=512, engine=sim)
    assert len(r["pixels"]) == 6 * (64 + 129 + 64) and len(r["cycles"]) == jb["lines"] == 18
    assert r["pixel_mismatches"] == 0 and r["line_mismatches"] == 0


@pytest.mark.parametrize("sim", SIMS)
def test_cocotb_pxp_idle_and_back_pressure(sim):
    # idle 0.3 and stall 0.4 of the retired bench, as the engines' byte probabilities
    r = check_jobs(_jobs("experts-solids", "c", range(150, 156)), width=512, engine=sim, idle=77, stall=102, seed=5)
    assert len(r["pixels"]) == 6 * 257 and r["pixel_mismatches"] == 0 and r["line_mismatches"] == 0


def test_cocotb_pxp_bench_catches_a_wrong_pixel():
    jb = _jobs(lines=range(200, 202))
    jb["pixels"] = jb["pixels"].copy()
    jb["pixels"][17] ^= 1
    assert check_jobs(jb, width=512, engine="cocotb-verilator")["pixel_mismatches"] == 1
