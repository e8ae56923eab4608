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


def test_interleave_is_checked_once_where_every_block_is_built():
    """One check (``formats.check_interleave``, RasterhwError) for the golden model, every HDL
    block's signature and the drivers; the command line prints it as one line, exit 2."""
    import subprocess
    import sys

    import pytest
    from rasterhw.golden_model import zbm as G
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.hdl.zbm.loop import ZbmLoop
    from rasterhw.hdl.zbm.unit import ZbmUnit
    from rasterhw.sim.zbm.cycles_hdl import measure_table1

    assert L.check_interleave is F.check_interleave
    for bad in (3, 0, 32, True, "8", 8.0):
        for build in (lambda i: ZbmUnit(interleave=i, width=64, height=16), lambda i: ZbmLoop(interleave=i),
                      lambda i: ZbmChip(interleave=i), lambda i: G.render_zbm(None, interleave=i),
                      lambda i: measure_table1(i)):
            with pytest.raises(RasterhwError, match=f"interleave must be 1, 2, 4, 8 or 16, not {bad!r}"):
                build(bad)
    with pytest.raises(RasterhwError, match="chip must be in 0..3, not 4"):
        ZbmChip(interleave=4, chip=4)
    for args in (("sim", "zbm", "--interleave", "3", "--size", "32x32", "--engine", "pysim"),
                 ("verilog", "zbm-unit", "--interleave", "3", "-o", "never.v")):
        r = subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 2 and r.stderr.strip() == "error: ZB/M: interleave must be 1, 2, 4, 8 or 16, not 3", r.stderr
