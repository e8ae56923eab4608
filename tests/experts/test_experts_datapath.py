"""EXPERTS datapath contract (issue 48 item 2): the golden bit model at ours (40-bit) and the paper's 16 bits."""

from __future__ import annotations

from functools import cache

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.accuracy import float_error
from rasterhw.golden_model.experts.formats import DATAPATHS, X_FRAC, Formats, rom_div, sat
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene

PAPER = Formats(datapath=DATAPATHS["paper"])


@cache
def _tris(name: str):
    return run_geometry(build_scene(name), 512, 512, z_bits=16)


def test_contract():
    assert (DATAPATHS["paper"].word_bits, DATAPATHS["paper"].multipliers, DATAPATHS["paper"].acc_extra) == (16, 1, 0)
    assert Formats().datapath is DATAPATHS["ours"]
    with pytest.raises(RasterhwError, match="datapath"):
        Formats(datapath="paper")


def test_paper_accumulator_is_a_stepped_16_bit_word():
    """The paper datapath's left-edge x on every line equals a 16-bit accumulator stepped line by line
    from its multiplier start value with one saturated 16-bit increment; z and i stay 16-bit words."""
    f = render_frame(_tris("experts-1000"), model="bit", fmt=PAPER)
    st, r = f.setup, f.records
    for a in (r.zl, r.il, r.xl, r.xr):
        assert 0 <= a.min() and a.max() < (1 << 16)
    checked = 0
    for t in range(0, st.n, 7):
        if not st.long_left[t]:
            continue
        X0, Y0, X2, Y2 = (int(v) for v in (st.X[0, t], st.Y[0, t], st.X[2, t], st.Y[2, t]))
        inc = int(sat(rom_div(X2 - X0, Y2 - Y0, X_FRAC), 16))
        lo = int(r.first[t])
        n = int(st.r1[t] - st.r0[t] + 1)
        yc = int(r.row[lo]) * 64 + 32
        acc = X0 + (((yc - Y0) * inc) >> X_FRAC)        # the start value: one multiply
        for k in range(n):
            assert r.xl[lo + k] == acc, (t, k)
            acc += inc                                   # then one 16-bit add a line
            checked += 1
    assert checked > 1000


@pytest.mark.parametrize("aj", ["none", "c"])
def test_error_against_float_beside_ours(aj):
    """Measured on experts-1000 (512x512, z_bits 16): the paper's 16 bits move 1,618 visible pixels
    where ours moves 367, and (A.J. (c)) change 19,504 pixels of ours' image; PSNR against float drops."""
    ours, paper = float_error(_tris("experts-1000"), "ours", aj=aj), float_error(_tris("experts-1000"), "paper", aj=aj)
    assert (ours["datapath_bits"], ours["multipliers"], paper["datapath_bits"], paper["multipliers"]) == (40, 3, 16, 1)
    assert ours["pixels_differing_from_ours"] == 0
    assert (ours["visible_differing"], paper["visible_differing"]) == (367, 1618)
    assert paper["pixels_differing_from_ours"] > 0
    assert paper["psnr_db"] < ours["psnr_db"]
    want = {"none": (241, 221272, 31.697, 247, 221363, 28.936), "c": (203, 222858, 32.479, 203, 222974, 31.401)}[aj]
    got = (ours["max_abs_error"], ours["pixels_differing_from_float"], round(ours["psnr_db"], 3),
           paper["max_abs_error"], paper["pixels_differing_from_float"], round(paper["psnr_db"], 3))
    assert got == want


@pytest.mark.parametrize("name", ["experts-tilt-1000", "c100"])
def test_slp_cycle_model_and_set_up_at_the_papers_widths(name):
    """The golden side the SLP HDL runs against, at the paper's widths (acc_extra 0): the set-up's
    triangle words are the paper bit model's, and every ASB (x, z, i by 16-bit accumulators) is the
    paper bit model's record; at ours' widths the same words give different ASBs (the test can fail)."""
    from rasterhw.golden_model.experts.slp_cycles import asb, tri_words
    from rasterhw.golden_model.experts.slp_setup import band_setup, pl_words
    from rasterhw.golden_model.experts.span_cycles import line_asl
    fr = render_frame(run_geometry(build_scene(name), 128, 96, z_bits=16), model="bit", aj="c", fmt=PAPER)
    tws, pls = tri_words(fr.setup), pl_words(fr.setup)
    assert band_setup(pls, (0, 96), 96, extra=0)["words"] == tws
    assert band_setup(pls, (0, 96), 96)["words"] != tws
    n = wide = 0
    for y in range(96):
        segs, _ = line_asl(fr, y)
        for s in segs:
            assert asb(tws[s["addr"]], y, extra=0) == s
            wide += asb(tws[s["addr"]], y) != s
            n += 1
    assert n > 300 and wide > 0


def test_slp_hdl_at_the_papers_widths_pysim(experts_tilt_300):
    """experts-slp-setup and experts-slp with acc_extra 0 (the paper's 16-bit increments and edge
    accumulators), pysim, on one band of the paper bit model's frame: words and cycle stamps equal
    the golden side's at the same widths; the same words at ours' widths differ (the test can fail)."""
    from rasterhw.golden_model.experts.model import equal_bounds
    from rasterhw.golden_model.experts.slp_setup import pl_words
    from rasterhw.sim.engines import run
    from rasterhw.sim.experts.testbench import SlpBench, SlpSetupBench, setup_words, slp_words
    from rasterhw.sim.testbench import Stimulus
    fr = render_frame(run_geometry(experts_tilt_300, 64, 32, z_bits=16), model="bit", aj="c", fmt=PAPER)
    su = setup_words(pl_words(fr.setup), (8, 16), 32, extra=0)
    assert su["out"] != setup_words(pl_words(fr.setup), (8, 16), 32)["out"]
    tb = SlpSetupBench()
    got = run(tb, tb.params(height=32, acc_extra=0), Stimulus({"i": su["in"]}), engine="pysim",
              expect_words={"o": len(su["out"])}, max_cycles=40000)
    assert got.words["o"] == su["out"] and list(got.stamps["o"]) == su["stamps"]
    sw = slp_words(fr, (8, 16), equal_bounds(64, 3), guard=1)
    tb = SlpBench()
    got = run(tb, tb.params(width=64, tris=1024, lines=32, asl=256, guard=1, acc_extra=0), Stimulus({"i": sw["in"]}),
              engine="pysim", expect_words={"o": len(sw["out"])}, max_cycles=40000)
    assert got.words["o"] == sw["out"] and int(got.stamps["o"][-1]) + 1 == sw["cycles"]
    assert len(sw["out"]) > 8 * 10


def test_papers_slp_shares_one_multiplier_in_its_cycles(monkeypatch):
    """The paper's SLP list work (acc_extra 0): one multiplier, so every survivor's and entering
    segment's ASL update and every ASL word takes one more cycle than with a multiplier per operand
    (slp_cycles.MUL_CYCLES); the cycle model counts exactly those (recounted here from its ASLs)."""
    from rasterhw.golden_model.experts import slp_cycles
    from rasterhw.golden_model.experts.model import equal_bounds
    from rasterhw.golden_model.experts.slp_cycles import MUL_CYCLES, band_run, tri_words
    fr = render_frame(run_geometry(build_scene("experts-tilt-1000"), 64, 32, z_bits=16), model="bit", aj="c",
                      fmt=PAPER)
    tws = tri_words(fr.setup)
    args = (tws, (8, 16), equal_bounds(64, 3))
    assert MUL_CYCLES == {0: 1, 16: 0}
    one = band_run(*args, width=64, guard=1, extra=0)
    monkeypatch.setitem(slp_cycles.MUL_CYCLES, 0, 0)        # the same widths, a multiplier per operand
    many = band_run(*args, width=64, guard=1, extra=0)
    assert many["words"] == one["words"]
    extra = 0
    prev: list = []
    for y, asl in zip(range(8, 16), one["asl"], strict=True):
        r1 = {t: tws[t]["r1"] for t in prev}
        surv = sum(r1[t] >= y for t in prev)
        entering = len(set(asl) - set(prev))
        extra += surv + entering + len(asl)
        prev = asl
    assert extra > 50
    assert one["cycles"] - many["cycles"] == extra


def test_multipliers_are_counted_from_the_elaborated_hdl():
    """hdl/experts/census.py counts the $mul cells of the elaborated design whose operands are both
    signals: the paper's SLP list work has one 16 x 16 multiplier, ours nine (x of three edges, z and
    i of three edges each, 19 x 48); constant multiplies (2 * run width) are not counted."""
    from rasterhw.hdl.experts.census import census, multipliers
    from rasterhw.hdl.experts.slp import ExpertsSlp
    paper = census(ExpertsSlp(width=64, tris=64, lines=32, asl=64, acc_extra=0))
    ours = census(ExpertsSlp(width=64, tris=64, lines=32, asl=64))
    assert (paper["multipliers"], paper["bits"], paper["widths"]) == (1, 16, [(16, 16)])
    assert (ours["multipliers"], ours["bits"]) == (9, 48)

    from amaranth import Module, Signal
    from amaranth.lib import wiring
    from amaranth.lib.wiring import In, Out

    class Two(wiring.Component):
        def __init__(self):
            super().__init__({"a": In(8), "b": In(12), "y": Out(24)})

        def elaborate(self, platform):
            m = Module()
            k = Signal(8)
            m.d.sync += k.eq(k + 1)
            m.d.comb += self.y.eq(self.a * self.b + 3 * k + k * self.a)
            return m
    assert sorted(multipliers(Two())) == [(8, 8), (8, 12)]
    # the chained frame at the paper's datapath without A.J.: one 16 x 16 multiplier a processor (the
    # set-up's products wider than that multi-word); with A.J. (c) the blend's 9 are not shared yet.
    # frame_census through sim experts' cache entry (the frame test's [none] one at the paper's datapath):
    # keyed by the three blocks' design digests and census.py's, so a changed block or count elaborates again
    from rasterhw.sim.experts.scene import _census
    f = _census("paper", 48, 16, "none", "span")
    assert {b: (c["multipliers"], c["bits"]) for b, c in f["per_block"].items()} == {
        "experts-slp-setup": (1, 16), "experts-slp": (1, 16), "experts-pxp-span": (1, 16)}
    assert (f["multipliers"], f["datapath_bits"]) == (1, 16)
    f = _census("ours", 48, 16, "none", "span")
    assert {b: (c["multipliers"], c["bits"]) for b, c in f["per_block"].items()} == {
        "experts-slp-setup": (1, 40), "experts-slp": (9, 48), "experts-pxp-span": (3, 20)}
