"""The PXP testbenches' line log (``RangeFromTokens.log``: every line's finish-time counter, the
per-line log the scene runs read) on both engines: the same words and stamps on pysim and
Verilator, with and without idle gaps and back-pressure, equal to the cycle model when exact; and
the scene runs' job player (``scene.run_jobs``) giving the same on both engines."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.engines import run
from rasterhw.sim.experts.pxp_jobs import job_list, span_job_list
from rasterhw.sim.experts.scene import IN_DEPTH, OUT_DEPTH, run_jobs
from rasterhw.sim.experts.testbench import PxpBench, PxpCoherentBench, PxpSpanBench
from rasterhw.sim.testbench import compare

SCENE_BUILD = {"depth": IN_DEPTH, "out_depth": OUT_DEPTH}


def _need(exp) -> dict[str, int]:
    return {k: len(v) for k, v in exp.words.items()}


@pytest.mark.parametrize("cls", [PxpBench, PxpSpanBench, PxpCoherentBench], ids=["zbuffer", "span", "coherent"])
def test_line_log_is_the_same_on_pysim_and_verilator(cls):
    tb = cls(log=True)
    p = tb.params(width=64, aj="c")
    stim = tb.stimulus(p, seed=4)
    exp = tb.expect(p, stim)
    jb = stim.source
    assert tb.outputs_of(p) == ("o", "log") and len(exp.words["log"]) == jb["lines"] >= 2
    for kw in ({}, {"idle": 0.25, "stall": 120, "seed": 9}):
        a = run(tb, p, stim, engine="pysim", expect_words=_need(exp), **kw)
        # the scene runs' memories (scene.run_jobs): the build test_run_jobs_same_on_both_engines uses
        b = run(tb, p, stim, engine="verilator", expect_words=_need(exp), build=SCENE_BUILD, **kw)
        assert (a.words, a.stamps) == (b.words, b.stamps), kw
        assert b.protocol_errors == 0
        c = compare(exp, b, cycle_exact=not kw)
        assert c["ports"]["o"]["mismatches"] == 0
        if not kw:   # exact: the log is the cycle model's, and the last pixel comes after the last line's log
            assert c["mismatches"] == 0 and c["cycle_mismatches"] == 0
            assert b.stamps["log"][-1] < b.stamps["o"][-1]
        else:        # the log is never back-pressured: one word per line, none faster than its resolve work
            assert len(b.words["log"]) == jb["lines"]
    # without the log (the registered testbench): the pixel port alone, the same cycles
    plain = cls()
    assert plain.outputs_of(p) == ("o",)
    r = run(plain, p, stim, engine="pysim", expect_words={"o": len(exp.words["o"])})
    assert compare(plain.expect(p, stim), r)["cycle_mismatches"] == 0


@pytest.mark.parametrize("pxp", ["zbuffer", "span", "coherent"])
def test_run_jobs_same_on_both_engines(pxp):
    """The scene runs' player: pixels, line cycles and the PXP's edges equal on pysim and
    Verilator (exact, and with idle gaps and back-pressure), exact equal to the cycle model."""
    fr = render_frame(run_geometry(build_scene("experts-tilt-1000"), 64, 64, z_bits=16), model="bit", aj="c")
    todo = [(y, lo, hi) for y in (5, 20, 21, 40) for lo, hi in ((0, 20), (20, 64))]
    jb = job_list(fr, todo) if pxp == "zbuffer" else span_job_list(fr, todo, pxp=pxp)
    for kw in ({}, {"idle": 40, "stall": 40, "seed": 3}):
        a = run_jobs(jb, width=64, engine="pysim", **kw)
        b = run_jobs(jb, width=64, engine="verilator", **kw)
        for k in ("pixels", "cycles"):
            assert np.array_equal(a[k], b[k]), (k, kw)
        assert a["sim_cycles"] == b["sim_cycles"] == a["last_pixel"]
        assert a["pixels"].tolist() == jb["pixels"].tolist()
        if not kw:
            assert a["cycles"].tolist() == jb["cycles"].tolist()
            assert a["sim_cycles"] == jb["last_pixel"] + (1 if pxp != "zbuffer" else 2)
        else:
            assert (a["cycles"] >= (jb["cycles"] if pxp == "zbuffer" else
                                    np.array([t[1] + 1 for t in jb["timing"]]))).all()
