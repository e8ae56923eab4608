# amaranth: UnusedElaboratable=no
"""EXPERTS SLP group: one SLP, its DMM/Ps and its Pn span PXPs, clocked together (one band's machine).

Paper (seed 000, section 3): each SLP drives Pn PXPs through one DMM/P per PXP ("DMMは、物理的には下位
のプロセッサ1台に1組ずつ装備"), the PXPs working "他のPXPとの通信なしに独立に動作". Here the SLP's
output stream (``hdl/experts/slp.py``: per line every ASB, the leading pointers and bucket entries of
all ranges, the end of line) is broadcast to Pn small writers (``_DmmWriter``), each of which keeps
what its PXP's DMM/P takes -- every ASB, its own range's bucket entries, its own leading pointer,
sent with the end-of-line token -- and writes it into the DMM/P bank of its ``ExpertsPxpSpan``. The
SLP waits while any PXP's free bank is still being read (back-pressure through the broadcast,
nothing dropped); each PXP has its own pixel output. Ranges are the static equal split of the
width (``model.equal_bounds``), which the SLP must also be given as its bounds.
"""

from __future__ import annotations

from amaranth import Module, Signal, unsigned
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import Formats
from rasterhw.golden_model.experts.model import equal_bounds
from rasterhw.hdl.broadcast import StreamBroadcast
from rasterhw.hdl.experts.pxp_span import NO_PTR, PTR_BITS, ExpertsPxpSpan, asb_layout, dmm_layout
from rasterhw.hdl.experts.slp import ExpertsSlp, slp_in_layout, slp_out_layout

__all__ = ["ExpertsGroup"]

class _DmmWriter(wiring.Component):
    """SLP words -> the DMM/P words of PXP ``p`` (see the module docstring)."""

    def __init__(self, p: int):
        self._p = p
        super().__init__({"i": In(stream.Signature(slp_out_layout())), "o": Out(stream.Signature(dmm_layout()))})

    def elaborate(self, platform):
        m = Module()
        w = self.i.payload
        lead = Signal(PTR_BITS, init=NO_PTR)
        mine = w.p == self._p
        m.d.comb += [self.o.payload.ptr.eq(0), self.o.valid.eq(0), self.i.ready.eq(1)]
        for name in asb_layout().members:
            m.d.comb += getattr(self.o.payload, name).eq(getattr(w.asb, name))
        with m.Switch(w.kind):
            with m.Case(0):                                      # an ASB of the line's ASL
                m.d.comb += [self.o.valid.eq(self.i.valid), self.i.ready.eq(self.o.ready)]
            with m.Case(1):                                      # a leading pointer
                with m.If(self.i.valid & mine):
                    m.d.sync += lead.eq(w.pos)
            with m.Case(2):                                      # a bucket list entry
                with m.If(mine):
                    m.d.comb += [self.o.valid.eq(self.i.valid), self.i.ready.eq(self.o.ready),
                                 self.o.payload.list.eq(1), self.o.payload.ptr.eq(w.pos)]
            with m.Case(3):                                      # end of line: the token
                m.d.comb += [self.o.valid.eq(self.i.valid), self.i.ready.eq(self.o.ready),
                             self.o.payload.last.eq(1), self.o.payload.ptr.eq(lead)]
                with m.If(self.i.valid & self.o.ready):
                    m.d.sync += lead.eq(NO_PTR)
        return m


class ExpertsGroup(wiring.Component):
    """One SLP and its Pn span PXPs.

    Parameters
    ----------
    width : int
        Frame width (1..1024).
    pn : int
        PXPs (1..63), ranges the equal split of the width.
    aj : str
        ``"none"`` or ``"c"`` (the PXPs' A.J.; the SLP's block lists then cover one guard pixel).
    tris, lines, asl : int
        As :class:`ExpertsSlp`.
    depth : int
        ASBs per DMM/P bank, as :class:`ExpertsPxpSpan`.

    Members
    -------
    i : In(stream.Signature(slp_in_layout()))   the SLP's input (band, bounds, PL, go)
    o : Out(stream.Signature(unsigned(Formats().pixel_bits))).array(pn)   each PXP's pixels, line by line
    overflow : Out(1)   an SLP ASL or a DMM/P bank overflowed (sticky)
    """

    def __init__(self, *, width: int = 512, pn: int = 8, aj: str = "c", tris: int = 4095, lines: int = 64,
                 asl: int = 256, depth: int = 256):
        if isinstance(pn, bool) or not isinstance(pn, int) or not 1 <= pn <= min(63, width):
            raise ValueError(f"pn must be an integer in 1..{min(63, width)}, not {pn!r}")
        # the parts are built in elaborate (checked here, so a bad parameter fails at once)
        self._slp_kw = {"width": width, "tris": tris, "lines": lines, "asl": asl, "guard": 1 if aj == "c" else 0}
        self._pxp_kw = {"width": width, "aj": aj, "depth": depth}
        for cls, kw in ((ExpertsPxpSpan, self._pxp_kw), (ExpertsSlp, self._slp_kw)):
            cls(**kw)          # a throw-away, built only to check the parameters (not elaborated: no warning, line 1)
        b = equal_bounds(width, pn)
        self._ranges = [(int(b[k]), int(b[k + 1])) for k in range(pn)]
        self._pn = pn
        super().__init__({"i": In(stream.Signature(slp_in_layout())),
                          "o": Out(stream.Signature(unsigned(Formats().pixel_bits))).array(pn),
                          "overflow": Out(1)})

    def elaborate(self, platform):
        m = Module()
        m.submodules.slp = slp = ExpertsSlp(**self._slp_kw)
        m.submodules.fan = fan = StreamBroadcast(slp_out_layout(), n=self._pn)
        wiring.connect(m, wiring.flipped(self.i), slp.i)
        wiring.connect(m, slp.o, fan.i)
        ovf = [slp.overflow]
        for k, (lo, hi) in enumerate(self._ranges):
            pxp = ExpertsPxpSpan(**self._pxp_kw)
            wr = _DmmWriter(k)
            m.submodules[f"dmm_writer{k}"] = wr
            m.submodules[f"pxp{k}"] = pxp
            wiring.connect(m, fan.o[k], wr.i)
            wiring.connect(m, wr.o, pxp.i)
            m.d.comb += [pxp.lo.eq(lo), pxp.hi.eq(hi), self.o[k].valid.eq(pxp.o.valid),
                         self.o[k].payload.eq(pxp.o.payload), pxp.o.ready.eq(self.o[k].ready)]
            ovf.append(pxp.overflow)
        m.d.comb += self.overflow.eq(sum(ovf) != 0)
        return m
