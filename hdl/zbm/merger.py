"""ZB/M merger: keeps the nearest 2 of 4 samples, on its own ``merge`` clock.

The paper (sec. 5.2, 5.4): "the merger Z-merges the pixel information from the merge input
port with the pixel information in the pixel processors' memories and outputs the result on
the merge output port"; with double Z it takes "2 points from the neighbouring merger and
its own 2 points, 4 in all, keeps the nearest 2 by Z and outputs them to the next merger".
The pixel processors, initial and segment processors run on the segment clock, the merger on
an independent merge clock, "so the merge bus is asynchronous".

Here the merge-bus side of the pixel memories is read in the segment domain (``sync``) and
its words cross into the ``merge`` domain through an :class:`amaranth.lib.fifo.AsyncFIFO`;
the neighbour's merge input and the merge output live in ``merge``.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import data, fifo, stream, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["ZbmMerger", "merge_words"]


def merge_words(a, b) -> tuple:
    """Nearest-2-of-4 on two double-Z words (each ``s0`` nearer than or as near as ``s1``).

    Returns ``(s0, s1)`` as combinational values. ``a`` wins ties (it is the upstream merge
    input), so on equal Z the sample that entered the chain first stays in front, like the
    reference's "first submitted keeps the pixel".
    """
    a_first = a.s0.z <= b.s0.z
    # Having taken a.s0, the candidates are a.s1 and b.s0; having taken b.s0, a.s0 and b.s1.
    s1_if_a = Mux(a.s1.z <= b.s0.z, a.s1, b.s0)
    s1_if_b = Mux(a.s0.z <= b.s1.z, a.s0, b.s1)
    return Mux(a_first, a.s0, b.s0), Mux(a_first, s1_if_a, s1_if_b)


class ZbmMerger(wiring.Component):
    """Nearest-2-of-4 Z merge with a real segment -> merge clock crossing.

    Parameters
    ----------
    word_layout : data.StructLayout
        Layout of one double-Z merge word: fields ``s0`` and ``s1`` (each a sample with a
        ``z`` field, smaller = nearer, ``s0`` nearer or equal), optionally more (e.g. ``last``),
        which are taken from the own word.
    fifo_depth : int
        Depth of the asynchronous FIFO (a power of 2, at least 4).

    Members
    -------
    i_own : In(stream.Signature(word_layout)), domain ``sync`` (segment clock)
        Words read from the merge-bus side of the pixel memories, in pixel order.
    i_merge : In(stream.Signature(word_layout)), domain ``merge``
        Merge input port from the neighbouring chip (the head of a chain feeds empty words).
    o_merge : Out(stream.Signature(word_layout)), domain ``merge``
        Merge output port: per pixel, the nearest 2 of the 4 samples.

    Latency and throughput: one word per ``merge`` cycle when both inputs have data and the
    output is ready (a register stage after the FIFO); the crossing adds the AsyncFIFO's
    2-3 flop synchroniser latency.
    """

    def __init__(self, *, word_layout: data.StructLayout, fifo_depth: int = 8):
        if fifo_depth < 4 or fifo_depth & (fifo_depth - 1):
            raise ValueError(f"fifo_depth must be a power of 2 >= 4, not {fifo_depth!r}")
        for f in ("s0", "s1"):
            if f not in word_layout.members:
                raise ValueError(f"word_layout must have field {f!r}, has {list(word_layout.members)!r}")
        self._layout = word_layout
        self._fifo_depth = fifo_depth
        super().__init__({
            "i_own": In(stream.Signature(word_layout)),
            "i_merge": In(stream.Signature(word_layout)),
            "o_merge": Out(stream.Signature(word_layout)),
        })

    @property
    def word_layout(self) -> data.StructLayout:
        return self._layout

    def elaborate(self, platform):
        m = Module()
        width = self._layout.size
        m.submodules.cdc = cdc = fifo.AsyncFIFO(width=width, depth=self._fifo_depth,
                                                w_domain="sync", r_domain="merge")
        # the FIFO's streams carry the raw word: the same stream, viewed as its layout here
        w, r = cdc.w_stream, cdc.r_stream
        m.d.comb += [
            w.payload.eq(self.i_own.payload.as_value()),
            w.valid.eq(self.i_own.valid),
            self.i_own.ready.eq(w.ready),
        ]
        own = data.View(self._layout, r.payload)
        # Output register stage (stream docs' template): load when empty or being taken.
        take = Signal()
        m.d.comb += take.eq(r.valid & self.i_merge.valid & (~self.o_merge.valid | self.o_merge.ready))
        m.d.comb += [r.ready.eq(take), self.i_merge.ready.eq(take)]
        with m.If(self.o_merge.ready):
            m.d.merge += self.o_merge.valid.eq(0)
        with m.If(take):
            m.d.merge += self.o_merge.valid.eq(1)
            for name in self._layout.members:
                if name not in ("s0", "s1"):
                    m.d.merge += getattr(self.o_merge.payload, name).eq(getattr(own, name))
        s0, s1 = merge_words(self.i_merge.payload, own)
        with m.If(take):
            m.d.merge += [self.o_merge.payload.s0.eq(s0), self.o_merge.payload.s1.eq(s1)]
        return m
