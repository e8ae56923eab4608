"""``rasterhw sim pxp``: a whole (small) frame through the PXP HDL; the full frame on Verilator (slow)."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.scene import simulate_scene
from rasterhw.sim.registry import SIM_KEYS, sim_blocks


@pytest.mark.parametrize("aj", ["none", "c"])
def test_small_frame_pysim_pixel_and_cycle_exact(aj):
    """The default PXP (span); the zbuffer one: tests/experts/test_experts_pxp_span.py."""
    r = simulate_scene(build_scene("experts-tilt-1000"), 64, 16, engine="pysim", sn=2, pn=4, aj=aj)
    assert r["pxp"] == "span"
    assert set(SIM_KEYS) <= set(r)
    assert r["pixels_compared"] == 64 * 16 and r["mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["last_pixel_mismatch"] == 0
    assert r["frame_cycles"] < r["cycles"]


def test_balanced_ranges_through_the_hdl():
    """Ranges moved line by line by method ii from the finish-time counters: still exact
    (the line Z-buffer PXP; the span PXP: tests/experts/test_experts_pxp_span.py)."""
    kw = {"engine": "pysim", "sn": 1, "pn": 4, "aj": "c", "pxp": "zbuffer"}
    r = simulate_scene(build_scene("experts-uneven"), 128, 32, ranges="ii", **kw)
    assert r["mismatches"] == 0 and r["cycle_mismatches"] == 0 and r["last_pixel_mismatch"] == 0
    s = simulate_scene(build_scene("experts-uneven"), 128, 32, **kw)
    assert r["frame_cycles"] <= s["frame_cycles"]


def test_registered_and_bad_engine():
    m, b = sim_blocks()["pxp"]
    assert m.name == "experts" and b.default_scene == "experts-1000"
    with pytest.raises(RasterhwError, match="engine"):
        simulate_scene(build_scene("experts-tilt-1000"), 64, 16, engine="modelsim")   # icarus runs (cocotb on Icarus); an unknown one does not
    with pytest.raises(RasterhwError, match="aj must be"):
        simulate_scene(build_scene("experts-tilt-1000"), 64, 16, aj="b")
    with pytest.raises(RasterhwError, match="ranges must be"):
        simulate_scene(build_scene("experts-tilt-1000"), 64, 16, ranges="iii")


@pytest.mark.slow
@pytest.mark.parametrize("pxp", ["span", "zbuffer"])
def test_experts_1000_frame_on_verilator(pxp):
    r = simulate_scene(build_scene("experts-1000"), 512, 512, engine="verilator", sn=8, pn=8, aj="c", pxp=pxp)
    assert r["pixels_compared"] == 262144 and r["mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["last_pixel_mismatch"] == 0
    # the span PXP's resolve side chains asynchronous reads (a slower Verilator model per clock)
    assert r["cycles_per_s"] > (3e5 if pxp == "span" else 1e6)


def test_a_frame_smaller_than_the_bench_memory_compares_its_own_pixels():
    """The Verilator engine's pixel sink is 2^19 words deep for every scene run (one build); a
    512 x 16 frame is compared on its own 8,192 pixels (the old plain bench's dump of its whole
    memory once counted its tail as 253,952 mismatches)."""
    r = simulate_scene(build_scene("c50"), 512, 16, engine="verilator", sn=2, pn=2, aj="c")
    assert r["pixels_compared"] == 512 * 16 and r["mismatches"] == 0 and r["cycle_mismatches"] == 0


def test_verilator_idle_and_backpressure_same_pixels_no_line_faster():
    """Random input idle clocks and output back-pressure on the Verilator engine (``run_jobs``): every
    pixel still equals the golden model and no line finishes faster than the cycle model, while
    the run takes more clocks than the cycle-exact one; bad settings are one-line errors."""
    sc = build_scene("experts-tilt-1000")
    exact = simulate_scene(sc, 512, 512, engine="verilator", sn=2, pn=2, aj="c")
    timed = simulate_scene(sc, 512, 512, engine="verilator", sn=2, pn=2, aj="c", idle=90, stall=120, seed=3)
    assert exact["mismatches"] == 0 and exact["cycle_mismatches"] == 0 and exact["last_pixel_mismatch"] == 0
    assert timed["mismatches"] == 0 and timed["pixels_compared"] == exact["pixels_compared"] == 512 * 512
    assert timed["cycle_mismatches"] == 0 and timed["cycles"] > exact["cycles"]
    with pytest.raises(RasterhwError, match="stall"):
        simulate_scene(sc, 512, 512, engine="verilator", stall=256)
    with pytest.raises(RasterhwError, match="Verilator bench"):
        simulate_scene(sc, 64, 16, engine="pysim", idle=5)
