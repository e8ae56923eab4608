"""cocotb on the generated PXP Verilog (Verilator; Icarus when installed): idle input clocks,
output back-pressure, stream checkers and in-order scoreboards, against the golden PXP."""

from __future__ import annotations

import shutil
from functools import cache

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.pxp_cocotb import run_cocotb_bench
from rasterhw.sim.experts.pxp_sim import job_list

pytestmark = pytest.mark.cocotb

SIMS = ["verilator", pytest.param("icarus", marks=pytest.mark.skipif(
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
    r = run_cocotb_bench(_jobs(), sim=sim)
    assert r["pixels"] == 6 * (64 + 129 + 64) and r["lines"] == 18


@pytest.mark.parametrize("sim", SIMS)
def test_cocotb_pxp_idle_and_back_pressure(sim):
    r = run_cocotb_bench(_jobs("experts-solids", "c", range(150, 156)), sim=sim, idle=0.3, stall=0.4, seed=5)
    assert r["pixels"] == 6 * 257


def test_cocotb_pxp_bench_catches_a_wrong_pixel():
    jb = _jobs(lines=range(200, 202))
    jb["pixels"] = jb["pixels"].copy()
    jb["pixels"][17] ^= 1
    with pytest.raises(RasterhwError, match="cocotb: 1 of 1 tests failed"):
        run_cocotb_bench(jb)
