"""``rasterhw sim experts``: a whole (small) frame, every band through the SLP HDL and its lists into
every span PXP's DMM/P; the 512 x 512 8 x 8 run is a measurement (docs/experts.md), not a test."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.experts.span_cycles import dmm_line, line_job
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.scene import simulate_frame
from rasterhw.sim.registry import SIM_KEYS, sim_blocks


def test_small_frame_slp_and_pxp_hdl_exact(experts_tilt_300):
    r = simulate_frame(experts_tilt_300, 48, 16, engine="pysim", sn=2, pn=3, aj="c", accuracy=True)
    assert set(SIM_KEYS) <= set(r)
    assert r["pixels_compared"] == 48 * 16 and r["mismatches"] == 0 and r["slp_words"] > 300
    assert r["slp_cycle_mismatches"] == 0 and r["pxp_cycle_mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["slp_clock_for_30fps_hz"] == 30 * r["slp_cycles"] and r["pxp_clock_for_30fps_hz"] == 30 * r["pxp_cycles"]
    assert r["bottleneck"] in ("SLP", "PXP") and r["slp_cycles"] > 0 and r["pxp_cycles"] > 0
    # the SLP's set-up in HDL (experts-slp-setup), its words fed to the list work, and one SLP clock with it
    assert r["slp_setup_word_mismatches"] == 0 and r["slp_setup_cycle_mismatches"] == 0
    assert r["slp_setup_words"] > 0
    b = r["slp_busiest_band"]
    assert r["slp_setup_cycles"] == r["slp_setup_cycles_per_band"][b] > 0
    assert r["slp_cycles"] == r["slp_setup_cycles"] + r["slp_list_cycles"] == max(
        a + c for a, c in zip(r["slp_setup_cycles_per_band"], r["slp_list_cycles_per_band"], strict=True))
    # the machine's frame: the slower of the busiest SLP and the busiest PXP
    assert r["cycles"] == max(r["slp_cycles"], r["pxp_cycles"]) < r["sim_cycles"]
    # today's datapath as its elaborated HDL has it (the list work's 48-bit products; the default PXP,
    # the coherent span PXP: 5 multipliers, z at two pixels of two segments and i, and the A.J. blend's 9),
    # and (accuracy=True) its golden bit model's error against float
    assert (r["pxp"], r["pxp_block"]) == ("coherent", "experts-pxp-coherent")
    assert (r["datapath"], r["datapath_bits"], r["multipliers"], r["accuracy_source"]) == ("ours", 48, 14, "golden")
    assert r["hdl_multipliers"]["pxp_coherent"] == 14
    assert r["census_source"] == "hdl:elaborated"
    assert r["pixels_differing_from_ours"] == 0 and r["max_abs_error"] >= 0


@pytest.mark.parametrize(("aj", "pxp", "block"), [("c", "default", "coherent"), ("none", "span", "span")])
def test_paper_datapath_hdl_against_the_golden_model_at_its_widths(aj, pxp, block, experts_tilt_300):
    """--datapath paper: the SLP HDL with 16-bit increments and accumulators and the PXP (the default,
    the coherent span PXP, with A.J. (c); the span PXP without) with one 16 x 16 multiplier and z, i
    in two words (its jobs on span_cycles.paper_jobs' schedule), against the golden bit model at
    the paper's widths; the result says what the elaborated HDL has beside the contract (16, 1): with
    A.J. (c) too, the blend on the PXP's one multiplier (the drain first, the resolve side holding)."""
    from rasterhw.sim.experts.scene import jobs
    r = simulate_frame(experts_tilt_300, 48, 16, engine="pysim", sn=2, pn=3, aj=aj, datapath="paper", pxp=pxp)
    assert (r["pxp"], r["pxp_block"]) == (block, f"experts-pxp-{block}")
    assert r["pixels_compared"] == 48 * 16 and r["mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["slp_setup_word_mismatches"] == 0 and r["slp_word_mismatches"] == 0 and r["slp_words"] > 300
    assert (r["datapath"], r["datapath_bits"], r["multipliers"]) == ("paper", 16, 1)
    assert r["hdl_multipliers"] == {"slp_setup": 1, "slp_list": 1, f"pxp_{block}": 1}
    assert (r["contract_datapath_bits"], r["contract_multipliers"]) == (16, 1)
    # the PXP ran the paper's schedule, each line as the HDL took it, and it is slower than ours' on the
    # same frame: ours' cycle model (golden; the HDL matches it line for line, the tests of each PXP)
    fr = render_frame(run_geometry(experts_tilt_300, 48, 16, z_bits=16), model="bit", aj=aj)
    ours = int(jobs(fr, 2, 3, pxp=block)["pxp_frame_cycles"].max())
    assert r["pxp_cycles"] > ours and r["pxp_cycle_mismatches"] == 0
    with pytest.raises(RasterhwError, match="datapath must be"):
        simulate_frame(build_scene("experts-1000"), 64, 16, engine="pysim", datapath="wide")
    with pytest.raises(RasterhwError, match="path at chained"):
        simulate_frame(build_scene("experts-1000"), 64, 16, engine="pysim", datapath="paper", path="group")
    with pytest.raises(RasterhwError, match="experts-group's PXPs are span PXPs"):
        simulate_frame(build_scene("experts-1000"), 64, 16, engine="pysim", path="group", pxp="coherent")
    with pytest.raises(RasterhwError, match="pxp must be"):
        simulate_frame(build_scene("experts-1000"), 64, 16, engine="pysim", pxp="zbuffer")


def test_the_pxp_needs_the_slps_bucket_list():
    """The bucket list is data the PXP uses: without it a range loses the segments that start to
    its left (so wrong SLP lists would show as wrong pixels in the run above)."""
    fr = render_frame(run_geometry(build_scene("experts-tilt-1000"), 128, 32, z_bits=16), model="bit", aj="none")
    wrong = 0
    for y in range(32):
        segs, lead, buckets = dmm_line(fr, y, equal_bounds(128, 4))
        for p in range(1, 4):
            lo, hi = 32 * p, 32 * p + 32
            good = line_job(segs, buckets[p], lead[p], lo, hi, aj="none", width=128)["visible"]
            bad = line_job(segs, [], lead[p], lo, hi, aj="none", width=128)["visible"]
            ids = np.array([-1 if v < 0 else v for v in good])
            assert (ids >= -1).all()
            wrong += good != bad
    assert wrong > 10


def test_registered_and_bad_arguments():
    m, b = sim_blocks()["experts"]
    assert m.name == "experts" and b.default_scene == "experts-1000"
    with pytest.raises(RasterhwError, match="engine"):
        simulate_frame(build_scene("experts-tilt-1000"), 64, 16, engine="modelsim")   # icarus runs (cocotb on Icarus); an unknown one does not
    with pytest.raises(RasterhwError, match="sn must be"):
        simulate_frame(build_scene("experts-tilt-1000"), 64, 16, engine="pysim", sn=0)
    with pytest.raises(RasterhwError, match="aj must be"):
        simulate_frame(build_scene("experts-tilt-1000"), 64, 16, engine="pysim", aj="b")


def test_the_float_model_only_when_its_error_is_asked_for():
    """``sim experts`` renders the float model for the error keys only with ``accuracy`` (or
    ``--datapath paper``); the HDL's and the contract's widths are there either way."""
    from rasterhw.sim.experts.scene import _accuracy
    tris = run_geometry(build_scene("experts-tilt-1000"), 48, 16, z_bits=16)
    # pxp coherent: the census entry test_small_frame_slp_and_pxp_hdl_exact's frame writes (one elaboration
    # of the three designs a fresh run, not two)
    without, with_ = (_accuracy(tris, "ours", "c", e, width=48, height=16, pxp="coherent") for e in (False, True))
    errors = {"max_abs_error", "pixels_differing_from_float", "psnr_db", "visible_differing_from_float",
              "pixels_differing_from_ours", "accuracy_source"}
    assert errors.isdisjoint(without) and errors <= set(with_) and set(without) <= set(with_)
    assert with_["pixels_differing_from_ours"] == 0 and without["datapath_bits"] == with_["datapath_bits"]
