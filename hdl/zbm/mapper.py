"""ZB/M mapping after the merge: texture and illumination lookups on the two surviving samples
(paper, sec. 3.3: "mapping after the Z merge centralises the references to mapping memory and
eliminates wasted accesses"; sec. 5.4: the mapping-mode DDA channels um, vm, ui, vi).

Golden twin: :func:`rasterhw.golden_model.zbm.mapping.map_samples` (bit for bit). Only a sample
that reaches the output is looked up: s0 if present, s1 if present behind a translucent s0
(``a0 < 255``). Colour per channel = ``(tex[vm, um] * illum[vi, ui] + 127) // 255``.
"""

from __future__ import annotations

import numpy as np
from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm.layouts import PIXEL2

__all__ = ["ZbmMapper", "div255_round"]

_TEXEL = data.StructLayout({"r": unsigned(8), "g": unsigned(8), "b": unsigned(8)})


def div255_round(x):
    """``(x + 127) // 255`` for ``0 <= x <= 255 * 255`` without a divider: with ``n = x + 127``,
    ``(n + (n >> 8) + 1) >> 8`` (exact on that range; checked exhaustively in the tests)."""
    n = x + 127
    return (n + (n >> 8) + 1) >> 8


class ZbmMapper(wiring.Component):
    """Merged double-Z words (mapping mode) in, mapped colour-mode double-Z words out.

    Parameters
    ----------
    texture : (256, 256, 3) integer array
        RGB texture, indexed ``[vm, um]``.
    illum : (256, 256) integer array
        Illumination map, indexed ``[vi, ui]``.

    Members
    -------
    i : In(stream.Signature(PIXEL2))
        The last unit's merge output (one chip slot), mapping-mode samples.
    o : Out(stream.Signature(PIXEL2))
        The same samples with c0..c2 = mapped r, g, b and c3 = 0; c = 0 where a sample needs no
        lookup (empty, or hidden behind an opaque s0), as ``map_samples``.
    texture_lookups, illum_lookups : Out(32)
        Mapping-memory reads so far (one of each per sample that reaches the output).

    Timing: one pixel per cycle; two read ports per map (s0 and s1 looked up in the same cycle);
    latency 2 (memory read, then the multiply and rounding into the output register).
    """

    def __init__(self, *, texture, illum):
        tex = np.asarray(texture, np.int64)
        il = np.asarray(illum, np.int64)
        if tex.shape != (F.TEX, F.TEX, 3) or il.shape != (F.TEX, F.TEX):
            raise ValueError(f"texture must be ({F.TEX}, {F.TEX}, 3) and illum ({F.TEX}, {F.TEX}), "
                             f"not {tex.shape}, {il.shape}")
        if tex.min() < 0 or tex.max() > 255 or il.min() < 0 or il.max() > 255:
            raise ValueError("texture and illum values must be 0..255")
        self._tex = [int(r) | int(g) << 8 | int(b) << 16 for r, g, b in tex.reshape(-1, 3)]
        self._il = [int(v) for v in il.reshape(-1)]
        super().__init__({
            "i": In(stream.Signature(PIXEL2)),
            "o": Out(stream.Signature(PIXEL2)),
            "texture_lookups": Out(32),
            "illum_lookups": Out(32),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.tex = tex = Memory(shape=unsigned(_TEXEL.size), depth=F.TEX * F.TEX, init=self._tex)
        m.submodules.il = il = Memory(shape=unsigned(8), depth=F.TEX * F.TEX, init=self._il)
        tp = [tex.read_port() for _ in range(2)]
        ip = [il.read_port() for _ in range(2)]

        # stage 1 holds the accepted word while its lookups are read; stage 2 is the output
        s1 = Signal(PIXEL2)
        s1_valid = Signal()
        s1_need = Signal(2)
        out = Signal(PIXEL2)
        out_valid = Signal()
        adv2 = ~out_valid | self.o.ready          # output register free at the next edge
        adv1 = ~s1_valid | adv2                    # stage 1 can take a new word
        m.d.comb += [self.i.ready.eq(adv1), self.o.valid.eq(out_valid), self.o.payload.eq(out)]

        w = self.i.payload
        # as map_samples: s1 is looked up if present and s0 is not opaque (empty s0: a = 0)
        need = [w.s0.z != F.Z_EMPTY, (w.s1.z != F.Z_EMPTY) & (w.s0.a < 255)]
        for k, s in enumerate((w.s0, w.s1)):
            m.d.comb += [tp[k].addr.eq(s.c1 << F.TEX_BITS | s.c0), ip[k].addr.eq(s.c3 << F.TEX_BITS | s.c2),
                         tp[k].en.eq(adv1), ip[k].en.eq(adv1)]
        take = self.i.valid & adv1
        with m.If(adv1):
            m.d.sync += [s1.eq(w), s1_valid.eq(self.i.valid), s1_need.eq(Mux(self.i.valid, need[0] | need[1] << 1, 0))]
        with m.If(take):
            n = need[0].as_unsigned() + need[1].as_unsigned()
            m.d.sync += [self.texture_lookups.eq(self.texture_lookups + n),
                         self.illum_lookups.eq(self.illum_lookups + n)]

        with m.If(adv2):
            m.d.sync += out_valid.eq(s1_valid)
            with m.If(s1_valid):
                for k, (src, dst) in enumerate(((s1.s0, out.s0), (s1.s1, out.s1))):
                    t, lit = data.View(_TEXEL, tp[k].data), ip[k].data
                    m.d.sync += [dst.z.eq(src.z), dst.a.eq(src.a), dst.c3.eq(0)]
                    with m.If(s1_need[k]):
                        m.d.sync += [dst.c0.eq(div255_round(t.r * lit)), dst.c1.eq(div255_round(t.g * lit)),
                                     dst.c2.eq(div255_round(t.b * lit))]
                    with m.Else():
                        m.d.sync += [dst.c0.eq(0), dst.c1.eq(0), dst.c2.eq(0)]
        return m
