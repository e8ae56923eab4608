# amaranth: UnusedElaboratable=no
"""ZB/M widths live in golden_model/zbm/formats.py: every HDL layout equals its golden layout."""

from __future__ import annotations

from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm import layouts as L
from rasterhw.hdl.zbm.chip import ZbmChip
from rasterhw.hdl.zbm.seggen import ZbmSegmentGenerator


def test_every_hdl_layout_equals_its_golden_layout():
    golden = {n: v for n, v in vars(F).items() if isinstance(v, F.Layout)}
    assert {"EP_HEADER", "EP_CHANNEL", "SEG_HEADER", "FLIT", "PKT_HEADER", "SAMPLE", "PIXEL2"} <= set(golden)
    for name, g in golden.items():
        h = getattr(L, name)
        assert h.size == g.width, name
        for f in g.fields:
            shape = h[f.name].shape
            width = shape.width if hasattr(shape, "width") else shape.size
            assert width == f.width, (name, f.name)
    assert L.PACKET.size == F.LOOP_BITS * F.PACKET_FLITS


def test_ports_use_the_formats():
    chip = ZbmChip(interleave=8, chip=3, width=64)
    assert len(chip.i_seg.payload) == F.LOOP_BITS
    assert chip.o_merge.payload.shape().size == F.PIXEL2.width
    sg = ZbmSegmentGenerator(width=64, height=16)
    assert len(sg.i.payload) == F.EP_WORD_BITS
