"""ZB/M last stage: alpha-compositing of the two surviving samples into one RGB pixel (paper, sec.
5.2: "in the end the nearest 2 points of the whole remain, and alpha compositing is done from
these 2 points"; sec. 7: "alpha compositing by the double Z buffer").

Golden twin: :func:`rasterhw.golden_model.zbm.composite.composite` (bit for bit):
``back = (a1 * c1 + (255 - a1) * bg + 127) // 255`` (``bg`` if s1 is empty), then
``out = (a0 * c0 + (255 - a0) * back + 127) // 255`` (``bg`` if s0 is empty), per channel
r, g, b = c0, c1, c2 of colour-mode samples (the mapper's output in mapping mode).
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm.layouts import PIXEL2, SAMPLE
from rasterhw.hdl.zbm.mapper import div255_round

__all__ = ["ZbmCompositor", "RGB"]

#: one output pixel, r in the low byte (as ``composite(...)[..., 0]``)
RGB = data.StructLayout({"r": unsigned(8), "g": unsigned(8), "b": unsigned(8)})


class ZbmCompositor(wiring.Component):
    """Double-Z words (colour-mode samples, s0 nearer) in, alpha-composited RGB out.

    Parameters
    ----------
    background : (int, int, int)
        Background r, g, b, 0..255 (what an empty sample shows).

    Members
    -------
    i : In(stream.Signature(PIXEL2))
        Merged (and, in mapping mode, mapped) pixels: samples ``z, a, c0..c2 = r, g, b``.
    o : Out(stream.Signature(RGB))
        One composited pixel per input word, in order.

    Timing: one pixel per cycle; latency 2 (stage 1 composites s1 over the background, stage 2
    s0 over that); back-pressure stalls both stages. Each stage: three 8 x 8 multiplies by
    alpha, three by ``255 - alpha`` and the ``(x + 127) // 255`` rounding without a divider
    (:func:`~rasterhw.hdl.zbm.mapper.div255_round`).
    """

    def __init__(self, *, background=(0, 0, 0)):
        bg = tuple(background)
        if len(bg) != 3 or not all(isinstance(v, int) and 0 <= v <= 255 for v in bg):
            raise ValueError(f"background must be three integers 0..255, not {background!r}")
        self._bg = bg
        super().__init__({"i": In(stream.Signature(PIXEL2)), "o": Out(stream.Signature(RGB))})

    @property
    def background(self) -> tuple[int, int, int]:
        return self._bg

    def elaborate(self, platform):
        m = Module()
        bg = self._bg
        # stage 1: s0 kept, s1 composited over the background
        front = Signal(SAMPLE)
        back = Signal(RGB)
        s1_valid = Signal()
        out = Signal(RGB)
        out_valid = Signal()
        adv2 = ~out_valid | self.o.ready
        adv1 = ~s1_valid | adv2
        m.d.comb += [self.i.ready.eq(adv1), self.o.valid.eq(out_valid), self.o.payload.eq(out)]

        w = self.i.payload
        s1 = w.s1
        with m.If(adv1):
            m.d.sync += [front.eq(w.s0), s1_valid.eq(self.i.valid)]
            for ch, c, b in zip(("r", "g", "b"), (s1.c0, s1.c1, s1.c2), bg, strict=True):
                blend = div255_round(s1.a * c + (~s1.a)[:8] * b)
                m.d.sync += back[ch].eq(Mux(s1.z != F.Z_EMPTY, blend[:8], b))

        # stage 2: s0 over stage 1's result
        with m.If(adv2):
            m.d.sync += out_valid.eq(s1_valid)
            with m.If(s1_valid):
                for ch, c, b in zip(("r", "g", "b"), (front.c0, front.c1, front.c2), bg, strict=True):
                    blend = div255_round(front.a * c + (~front.a)[:8] * back[ch])
                    m.d.sync += out[ch].eq(Mux(front.z != F.Z_EMPTY, blend[:8], b))
        return m
