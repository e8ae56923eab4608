"""EXPERTS PXP unit: the DMM/P double bank in front of the PXP datapath (what one PXP board holds)."""

from __future__ import annotations

from amaranth import Module, unsigned
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import X_END_BITS, X_INT
from rasterhw.hdl.experts.dmm import ExpertsDmm
from rasterhw.hdl.experts.pxp import ExpertsPxp, seg_layout

__all__ = ["ExpertsPxpUnit"]


class ExpertsPxpUnit(wiring.Component):
    """DMM/P -> PXP. The SLP writes line k+1 while the PXP works on line k.

    Parameters
    ----------
    width, intensity_bits : as :class:`ExpertsPxp`.
    depth : int
        DMM/P bank depth (segments), as :class:`ExpertsDmm`.

    Members
    -------
    i : In(stream.Signature(seg_layout()))   ASL lines from the SLP (segments, then ``last``)
    o : Out(stream.Signature(unsigned(RGB_BITS + intensity_bits)))   the range's pixels, line by line
    lo, hi : In(X_INT), In(X_END_BITS)   the range, sampled when a line starts
    overflow : Out(1)   sticky DMM/P overflow (the SLP side stalls; nothing is dropped)
    line_cycles, lines : Out(16)   the PXP's finish-time counter and line count
    """

    def __init__(self, *, width: int = 512, intensity_bits: int = 7, depth: int = 256):
        self._pxp = ExpertsPxp(width=width, intensity_bits=intensity_bits)
        self._dmm = ExpertsDmm(depth=depth)
        super().__init__({
            "i": In(stream.Signature(seg_layout())),
            "o": Out(stream.Signature(unsigned(self._pxp.o.payload.shape().width))),
            "lo": In(X_INT), "hi": In(X_END_BITS), "overflow": Out(1), "line_cycles": Out(16), "lines": Out(16),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.dmm = dmm = self._dmm
        m.submodules.pxp = pxp = self._pxp
        wiring.connect(m, wiring.flipped(self.i), dmm.i)
        wiring.connect(m, dmm.o, pxp.i)
        wiring.connect(m, pxp.o, wiring.flipped(self.o))
        m.d.comb += [pxp.lo.eq(self.lo), pxp.hi.eq(self.hi), self.overflow.eq(dmm.overflow),
                     self.line_cycles.eq(pxp.line_cycles), self.lines.eq(pxp.lines)]
        return m
