"""EXPERTS widths: the HDL's ports and fields are the format contract's (``golden_model/experts/formats.py``).

The blocks take their widths from the contract by name; these tests tie what the blocks expose (port
and field widths, read from the constructed components, not elaborated) to the contract's fields and
to what the golden bit model assumes, so a width changed on one side only fails here. That a rename
left the netlists alone is checked by ``python tests/experts/netlist_check.py --base COMMIT``.
"""

from __future__ import annotations

import pytest
from amaranth import Shape
from rasterhw.golden_model.experts import formats as F
from rasterhw.golden_model.experts import slp_cycles
from rasterhw.hdl.experts.group import ExpertsGroup
from rasterhw.hdl.experts.pxp import RUN_BITS, ExpertsPxp, seg_layout
from rasterhw.hdl.experts.slp import slp_in_layout, slp_out_layout
from rasterhw.hdl.experts.slp_setup import pl_layout
from rasterhw.hdl.experts.unit import ExpertsPxpUnit


def _widths(layout) -> dict:
    return {k: (Shape.cast(f.shape).width, Shape.cast(f.shape).signed) for k, f in layout}


def test_derived_widths_cover_the_formats():
    # a line or pixel number 0..MAX_SIDE in X_INT bits, an exclusive end MAX_SIDE + 1 in X_END_BITS
    assert (1 << F.X_INT) - 1 == F.MAX_SIDE and F.MAX_SIDE + 1 < 1 << F.X_END_BITS
    # a Q10.6 word held signed keeps its top bit; a difference of two such fits XD_BITS signed
    assert F.XS_BITS == F.WORD + 1 and 2 * ((1 << F.WORD) - 1) < 1 << (F.XD_BITS - 1)
    # a pixel x held signed (XP_BITS) reaches one past the widest frame
    assert F.MAX_SIDE + 1 < 1 << (F.XP_BITS - 1)
    # an SLP increment field holds the ours datapath's Q.22 increment (up to word_bits, signed)
    assert F.INC_BITS >= F.DATAPATHS["ours"].word_bits
    # the golden cycle model wraps the increment field at the HDL's width
    assert slp_cycles._INC_MASK == (1 << F.INC_BITS) - 1
    assert RUN_BITS == F.DATAPATHS["ours"].word_bits


def test_pl_and_slp_words_have_the_contract_widths():
    pl = _widths(pl_layout())
    for j in range(3):
        assert pl[f"x{j}"] == pl[f"y{j}"] == (F.XS_BITS, True)
        assert pl[f"z{j}"] == (F.Z_BITS, False) and pl[f"i{j}"] == (F.WORD, False)
    assert pl["hue"] == (3 * F.HUE_BITS, False) and pl["r0"] == pl["r1"] == (F.X_INT, False)
    sl = _widths(slp_in_layout())
    for e in ("ac", "ab", "bc"):
        assert sl[f"inc_{e}"] == sl[f"zinc_{e}"] == sl[f"iinc_{e}"] == (F.INC_BITS, True)
        assert sl[f"s_{e}"] == sl[f"q_{e}"] == (F.WORD, True)      # sQ7.8
    assert sl["dzdx"] == sl["didx"] == (F.WORD, True)
    assert {k: pl[k] for k in ("t", "hue", "poly")} == {k: sl[k] for k in ("t", "hue", "poly")}
    assert _widths(slp_out_layout())["y"] == (F.X_INT, False)


def test_asb_fields_are_the_asb_words():
    seg = _widths(seg_layout())
    for k in ("xl", "xr", "il"):                     # Q10.6, Q10.6, QI.(16-I): one word each
        assert seg[k] == (F.WORD, False)
    assert seg["zl"] == (F.Z_BITS, False)
    for k in ("dzdx", "didx", "sl", "ql", "sr", "qr"):
        assert seg[k] == (F.WORD, True)
    assert seg["addr"] == seg["poly"] == (F.ADDR_BITS, False)
    assert F.X_FRAC < F.WORD


@pytest.mark.parametrize("ib", [1, 4, 7])
def test_pixel_ports_are_the_contract_pixel(ib):
    assert ExpertsPxp(intensity_bits=ib).o.payload.shape().width == F.Formats(ib).pixel_bits
    unit = ExpertsPxpUnit(intensity_bits=ib, width=64)
    assert unit.o.payload.shape().width == F.Formats(ib).pixel_bits
    assert (len(unit.lo), len(unit.hi)) == (F.X_INT, F.X_END_BITS)


def test_group_pixels_fill_the_word():
    g = ExpertsGroup(width=64, pn=2, aj="none", lines=16)
    assert [p.payload.shape().width for p in g.o] == [F.Formats().pixel_bits] * 2 == [F.WORD] * 2


@pytest.mark.parametrize("block", ["span", "coherent"])
@pytest.mark.parametrize("datapath", ["ours", "paper"])
def test_span_pxps_ports_and_the_paper_datapaths_words_are_the_contracts(block, datapath):
    """The span PXPs' range ports and pixel port, and the paper datapath's one multiplier (its operand
    ``MUL_IN`` holds a 16-bit magnitude with its sign: a word of Q10.6 pixel offset or an increment),
    are the contract's widths."""
    from rasterhw.hdl.experts.aj import MUL_IN
    from rasterhw.hdl.experts.pxp_coherent import ExpertsPxpCoherent
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan
    p = {"span": ExpertsPxpSpan, "coherent": ExpertsPxpCoherent}[block](width=64, depth=16, datapath=datapath)
    assert (len(p.lo), len(p.hi)) == (F.X_INT, F.X_END_BITS)
    assert p.o.payload.shape().width == F.Formats().pixel_bits
    w = Shape.cast(MUL_IN)          # a 16-bit magnitude, either sign, fits the operand
    assert w.signed and (1 << F.WORD) - 1 <= (1 << (w.width - 1)) - 1
