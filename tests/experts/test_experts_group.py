# amaranth: UnusedElaboratable=no
"""``experts-group`` (one SLP + Pn span PXPs clocked together): the DMM/P writer keeps exactly its
PXP's words; pixels against golden run in tests/test_engines.py (``GroupBench``)."""

from __future__ import annotations

import pytest
from amaranth.sim import Simulator
from rasterhw.hdl.experts.group import ExpertsGroup, _DmmWriter
from rasterhw.hdl.experts.pxp_span import NO_PTR, dmm_layout
from rasterhw.hdl.experts.slp import slp_out_layout
from rasterhw.hdl.pack import pack


def test_dmm_writer_keeps_its_pxps_words():
    lo, dl = slp_out_layout(), dmm_layout()
    asb = {"xl": 100, "xr": 900, "zl": 7, "addr": 5}
    words = [pack(lo, {"kind": 0, "pos": 0, "t": 5, "asb": asb}),        # an ASB: every PXP
             pack(lo, {"kind": 1, "p": 0, "pos": 0}),                    # lead of range 0: not ours
             pack(lo, {"kind": 2, "p": 0, "pos": 0}),                    # bucket of range 0: not ours
             pack(lo, {"kind": 2, "p": 1, "pos": 0}),                    # bucket of range 1: ours
             pack(lo, {"kind": 0, "pos": 1, "t": 6, "asb": dict(asb, addr=6)}),
             pack(lo, {"kind": 1, "p": 1, "pos": 1}),                    # our leading pointer
             pack(lo, {"kind": 3, "y": 3}),                              # end of line: the token
             pack(lo, {"kind": 3, "y": 4})]                              # an empty line: no lead
    want = [pack(dl, {**asb}), pack(dl, {"list": 1, "ptr": 0}), pack(dl, dict(asb, addr=6)),
            pack(dl, {"last": 1, "ptr": 1}), pack(dl, {"last": 1, "ptr": NO_PTR})]
    dut = _DmmWriter(1)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got = []

    async def bench(ctx):
        ctx.set(dut.o.ready, 1)
        for w in words:
            ctx.set(dut.i.payload.as_value(), w)
            ctx.set(dut.i.valid, 1)
            _, _, v, pl, r = await ctx.tick().sample(dut.o.valid, dut.o.payload.as_value(), dut.i.ready)
            assert r
            if v:
                got.append(pl)

    sim.add_testbench(bench)
    sim.run()
    assert got == want


def test_group_bad_parameters():
    with pytest.raises(ValueError, match="pn must be"):
        ExpertsGroup(width=64, pn=0)
    with pytest.raises(ValueError, match="aj must be"):
        ExpertsGroup(width=64, pn=2, aj="b")
