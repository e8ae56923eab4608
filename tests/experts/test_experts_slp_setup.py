# amaranth: UnusedElaboratable=no
"""``experts-slp-setup`` (the SLP's set-up: one multiplier, the reciprocal ROM) against its golden
side (``golden_model/experts/slp_setup.py``): the ROM-and-correction reciprocal is
``formats.recip_rom``'s exactly, the set-up's words are ``slp_cycles.tri_words``' (the bit model's),
and the HDL gives those words on the cycles of the cycle model."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.experts.formats import recip_rom
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.experts.slp_cycles import tri_words
from rasterhw.golden_model.experts.slp_setup import (
    band_setup,
    pl_words,
    recip,
    rom_table,
    set_up_triangle,
)
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.engines import run
from rasterhw.sim.experts.testbench import SlpSetupBench, setup_words
from rasterhw.sim.testbench import Stimulus


def test_rom_is_2_15_words_of_16_bits():
    t = rom_table()
    assert t.size == 1 << 15 and int(t.max()) == (1 << 16) - 1 and int(t.min()) > 1 << 15


def test_reciprocal_from_rom_and_multiplier_is_recip_rom():
    rng = np.random.default_rng(5)
    ds = np.concatenate([np.arange(1, 1 << 17), rng.integers(1, 1 << 36, 50000),
                         (1 << rng.integers(16, 36, 2000)) + rng.integers(-3, 4, 2000)])
    r, s = recip_rom(ds)
    got = [recip(int(d)) for d in ds]
    assert [(a, b) for a, b, _ in got] == list(zip(r.tolist(), s.tolist(), strict=True))
    corr = np.array([c for _, _, c in got])
    # 16-bit divisors are exact in the ROM (one correction from ROM + 1); wider ones need up to 3
    assert corr[: (1 << 16) - 1].max() == 1 and corr.max() == 3


@pytest.mark.parametrize("name", ["experts-tilt-1000", "c100"])
def test_set_up_words_are_the_bit_models(name):
    fr = render_frame(run_geometry(build_scene(name), 128, 96, z_bits=16), model="bit", aj="c")
    tws, pls = tri_words(fr.setup), pl_words(fr.setup)
    bs = band_setup(pls, (0, 96), 96)
    assert bs["words"] == tws and bs["in_band"] == len(tws) > 50
    part = band_setup(pls, (40, 50), 96)
    for w, tw, c in zip(part["words"], tws, part["tri_cycles"], strict=True):
        if tw["r1"] >= 40 and tw["r0"] < 50:
            assert w == tw and c >= 39
        else:
            assert w == {"t": tw["t"], "r0": tw["r0"], "r1": tw["r1"]} and c == 2
    assert 0 < part["in_band"] < len(tws)


def _pl(rng, t):
    w = {"t": t, "hue": int(rng.integers(0, 512)), "poly": int(rng.integers(0, 4095))}
    ys = rng.integers(-2000, 6000, 3)
    if t % 3 == 0:
        ys[int(rng.integers(0, 3))] = ys[int(rng.integers(0, 3))]       # equal y: the sort keeps PL order
    for j in range(3):
        w.update({f"x{j}": int(rng.integers(-65472, 65473)), f"y{j}": int(ys[j]),
                  f"z{j}": int(rng.integers(0, 1 << 16)), f"i{j}": int(rng.integers(0, 1 << 16))})
    return w


def test_hdl_words_and_cycles_on_wide_random_triangles():
    """Random PL triangles over the whole Q10.6 range (vertices off the frame, ties in y, 36-bit
    eq. (3) denominators), through pysim: the cycle model's words on its cycles."""
    rng = np.random.default_rng(11)
    pls = [_pl(rng, t) for t in range(60)]
    sw = setup_words(pls, (0, 64), 64)
    assert sum(c > 2 for c in sw["tri_cycles"]) > 20
    assert max(c for c in sw["tri_cycles"]) > 39        # corrections were needed
    for pl, w in zip(pls, sw["words"], strict=True):
        assert w == set_up_triangle(pl, (0, 64), 64)[0]
    tb = SlpSetupBench()
    got = run(tb, tb.params(height=64), Stimulus({"i": sw["in"]}), engine="pysim",
              expect_words={"o": len(sw["out"])}, max_cycles=20000)
    assert got.words["o"] == sw["out"]
    assert list(got.stamps["o"]) == sw["stamps"]


def test_papers_multi_word_products_on_wide_random_triangles():
    """The paper's datapath (acc_extra 0): one 16 x 16 multiplier, the reciprocal remainders and
    eq. (3)'s 34-bit numerators and denominator as multi-word products (hdl/experts/slp_setup.py:
    LIMBS), on random PL triangles over the whole 16-bit vertex range, through pysim: the cycle
    model's words on its cycles (+ slp_setup.MULTIWORD a triangle in the band); a vertex off the
    16-bit word is refused in one line."""
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.golden_model.experts.slp_setup import MULTIWORD
    rng = np.random.default_rng(12)
    pls = [_pl(rng, t) for t in range(40)]
    for pl in pls:
        for j in range(3):
            pl[f"x{j}"] = abs(pl[f"x{j}"]) % 65536
            pl[f"y{j}"] = int(rng.integers(0, 4500))
    sw, ours = setup_words(pls, (0, 64), 64, extra=0), setup_words(pls, (0, 64), 64)
    inb = sum(c > 2 for c in sw["tri_cycles"])
    assert inb > 10 and sw["cycles"] - ours["cycles"] == MULTIWORD * inb == 15 * inb
    tb = SlpSetupBench()
    got = run(tb, tb.params(height=64, acc_extra=0), Stimulus({"i": sw["in"]}), engine="pysim",
              expect_words={"o": len(sw["out"])}, max_cycles=40000)
    assert got.words["o"] == sw["out"]
    assert list(got.stamps["o"]) == sw["stamps"]
    pls[3]["x1"] = -64
    with pytest.raises(RasterhwError, match="16-bit word"):
        setup_words(pls, (0, 64), 64, extra=0)
