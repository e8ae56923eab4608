# amaranth: UnusedElaboratable=no
"""Bench adapter of the two ZB/M blocks without a stream output: the segment loop (``zbm-loop``)
and one pixel processor (``zbm-pixel``).

Both take segment packets and keep a double-buffered line memory whose merge-bus side is read
by address (``swap``, ``mb_addr``, ``mb_rd``, ``mb_data``). :class:`LineBench` turns that into
two streams, so the engines (``sim/engines/``) can run the block like any other:

- ``i``: 8-flit packets (``PACKET``). A packet whose header has ``len == 0`` ends the scan line
  (as on the chip's segment port, ``hdl/zbm/chip.py``).
- ``o``: the finished line, one ``PIXEL2`` word per pixel of the merge-bus side, in address order.

A loop takes every other packet on its own stream port. A pixel processor is a stop of a ring
that never stalls: the adapter plays each packet (a *visit*: the packet as it reaches this
processor, see ``sim/zbm/testbench.py: pixel_visits``) one flit per clock onto ``i_loop``, and
takes the stream word with the last flit.

The end of a line waits until the block may swap (loop: ``idle``; pixel processor: the last
visit's write has landed, which it has once the adapter is between visits) and the previous line
has been read out, then swaps; the line is then read out over the merge bus while the next
line's packets go on (the read-out side is the chip's merge-bus reader, ``hdl/zbm/chip.py``).
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm.layouts import PACKET, PIXEL2, PKT_HEADER

__all__ = ["LineBench"]


class LineBench(wiring.Component):
    """``block`` (a ``ZbmLoop`` or a ``ZbmPixelProcessor``) with a packet stream in and its
    finished lines out; ``pixels``: words per line (the loop's ``chip_pixels``, the pixel
    processor's ``depth``)."""

    def __init__(self, block, pixels: int):
        self.block, self._pixels = block, pixels
        super().__init__({"i": In(stream.Signature(PACKET)), "o": Out(stream.Signature(PIXEL2))})

    def elaborate(self, platform):
        m = Module()
        m.submodules.block = b = self.block
        npx = self._pixels
        eol = data.View(PKT_HEADER, self.i.payload[0]).len == 0

        # ---- merge-bus reader (the read port holds its data while not enabled: the output register)
        q = Signal(range(npx + 1), init=npx)
        dv = Signal()
        adv = ~dv | self.o.ready
        rd = adv & (q != npx)
        m.d.comb += [b.mb_addr.eq(q), b.mb_rd.eq(rd), self.o.valid.eq(dv), self.o.payload.eq(b.mb_data)]
        with m.If(adv):
            m.d.sync += dv.eq(rd)
        with m.If(rd):
            m.d.sync += q.eq(q + 1)
        reader_done = (q == npx) & ~dv

        # ---- packets in; the end of a line swaps
        swap = Signal()
        if hasattr(b, "i_loop"):           # a pixel processor: play the visit, one flit per clock
            k = Signal(range(F.PACKET_FLITS))
            play = self.i.valid & ~eol
            m.d.comb += [b.i_loop.valid.eq(play), b.i_loop.idx.eq(k), b.i_loop.flit.eq(self.i.payload[k]),
                         swap.eq(self.i.valid & eol & reader_done),
                         self.i.ready.eq(Mux(eol, swap, play & (k == F.PACKET_FLITS - 1)))]
            with m.If(play):
                m.d.sync += k.eq(k + 1)    # wraps to 0 after the last flit
        else:                              # the loop: its own packet stream
            m.d.comb += [b.i.valid.eq(self.i.valid & ~eol), b.i.payload.eq(self.i.payload),
                         swap.eq(self.i.valid & eol & b.idle & reader_done),
                         self.i.ready.eq(Mux(eol, swap, b.i.ready))]
        m.d.comb += b.swap.eq(swap)
        with m.If(swap):
            m.d.sync += q.eq(0)
        return m
