"""ZB/M chip: initial processor -> segment processor -> segment loop -> pixel memories ->
merge bus -> merger (paper, sec. 5.4, fig. 5).

Segment input protocol (our decision; the paper only names the port): a segment is a
``SEG_HEADER`` word followed by one ``FLIT`` word per channel of ``CHANNELS[mode]`` (5 in
colour mode, 6 in mapping mode), one 112-bit word per transfer; a ``SEG_HEADER`` with
``len == 0`` and no channel words marks the **end of a scan line** (real segments have
``len >= 1``). Every end-of-line record makes the chip swap its pixel memories and send the
finished line, ``ceil((width - chip) / interleave)`` double-Z words, down the merge chain.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm.layouts import FLIT, PIXEL2, PKT_HEADER, SEG_HEADER
from rasterhw.hdl.zbm.loop import PACKET, ZbmLoop
from rasterhw.hdl.zbm.merger import ZbmMerger

__all__ = ["ZbmChip"]


class ZbmChip(wiring.Component):
    """One ZB/M chip.

    Parameters
    ----------
    interleave : int
        Chips per unit: 1, 2, 4, 8 or 16 (paper, sec. 5.3).
    chip : int
        This chip's slot, ``0 <= chip < interleave``: it owns screen pixels ``x % interleave == chip``.
    width : int
        Screen width, 1..512.
    fifo_depth : int
        Depth of the merge-bus clock-crossing FIFO.

    Members
    -------
    i_seg : In(stream.Signature(unsigned(112))), segment clock (``sync``)
        Segment input port (see the module docstring for the record format).
    i_merge : In(stream.Signature(PIXEL2)), ``merge`` clock
        Merge input port from the upstream chip; the head of a chain feeds empty pixels.
    o_merge : Out(stream.Signature(PIXEL2)), ``merge`` clock
        Merge output port: per pixel of each finished line, the nearest 2 of 4 samples.
    cycles : Out(32)
        Segment-clock cycles since reset.
    busy_cycles : Out(32)
        Segment-clock cycles in which the chip held or processed a segment (input not idle).
    lines : Out(16)
        End-of-line records handled (pixel-memory swaps).

    Timing: a segment is received in ``1 + channels`` cycles, overlapping the loop; packets
    enter the loop ``len_chip + 8`` cycles apart (``ZbmLoop``); a segment with no pixel on this
    chip is dropped after its words are read. An end-of-line record waits for the loop to
    drain (its last Z write landing in this cycle: ``ZbmLoop.swap_ok``) and for the merge-bus
    reader to finish the previous line, then swaps; the next line's first packet is taken by
    the segment processor in the swap cycle, so across a line the loop keeps its
    ``len_chip + 8`` spacing. The merge-bus reader starts the cycle after the swap and
    finishes ``chip_pixels + 2`` cycles after it.
    """

    def __init__(self, *, interleave: int = 1, chip: int = 0, width: int = F.MAX_WIDTH,
                 fifo_depth: int = 16):
        if interleave not in F.INTERLEAVES:
            raise ValueError(f"interleave must be 1, 2, 4, 8 or 16, not {interleave!r}")
        if not (isinstance(chip, int) and 0 <= chip < interleave):
            raise ValueError(f"chip must be in 0..{interleave - 1}, not {chip!r}")
        if not (isinstance(width, int) and chip < width <= F.MAX_WIDTH):
            raise ValueError(f"width must be in {chip + 1}..{F.MAX_WIDTH}, not {width!r}")
        self._interleave = interleave
        self._chip = chip
        self._width = width
        self._fifo_depth = fifo_depth
        self._npx = -(-(width - chip) // interleave)
        super().__init__({
            "i_seg": In(stream.Signature(unsigned(F.LOOP_BITS))),
            "i_merge": In(stream.Signature(PIXEL2)),
            "o_merge": Out(stream.Signature(PIXEL2)),
            "cycles": Out(32),
            "busy_cycles": Out(32),
            "lines": Out(16),
        })

    @property
    def interleave(self) -> int:
        return self._interleave

    @property
    def chip(self) -> int:
        return self._chip

    @property
    def width(self) -> int:
        return self._width

    @property
    def chip_pixels(self) -> int:
        """Pixels per line this chip sends down the merge chain."""
        return self._npx

    def elaborate(self, platform):
        m = Module()
        lg = self._interleave.bit_length() - 1
        n_int = self._interleave
        m.submodules.loop = loop = ZbmLoop(interleave=n_int, width=self._width)
        m.submodules.merger = merger = ZbmMerger(word_layout=PIXEL2, fifo_depth=self._fifo_depth)
        wiring.connect(m, wiring.flipped(self.i_merge), merger.i_merge)
        wiring.connect(m, merger.o_merge, wiring.flipped(self.o_merge))

        m.d.sync += self.cycles.eq(self.cycles + 1)

        # ---- initial processor: segment words -> one packet for this chip's interleave slot
        pkt = Signal(PACKET)
        pkt_valid = Signal()     # complete packet waiting for the segment processor
        recv = Signal(range(F.PACKET_FLITS))   # channel words still expected
        j = Signal(4)            # pixels skipped to reach this chip's first pixel
        keep = Signal()
        eol = Signal(2)          # end-of-line records seen whose swap is pending (0..2)
        seg_hdr = data.View(SEG_HEADER, self.i_seg.payload)
        seg_flit = data.View(FLIT, self.i_seg.payload)
        # The next line's segment may be received while a swap is pending: a held packet
        # always belongs after every pending end of line (it blocks further input).
        m.d.comb += self.i_seg.ready.eq(~pkt_valid & (eol != 2))
        eol_in = Signal()
        with m.If(self.i_seg.valid & self.i_seg.ready):
            with m.If(recv == 0):
                with m.If(seg_hdr.len == 0):
                    m.d.comb += eol_in.eq(1)
                with m.Else():
                    jj = (self._chip - seg_hdr.x)[:lg] if lg else 0
                    n = Signal(11)
                    m.d.comb += n.eq(Mux(seg_hdr.len > jj, (seg_hdr.len - jj + (n_int - 1)) >> lg, 0))
                    m.d.sync += [
                        j.eq(jj), keep.eq(n != 0),
                        recv.eq(len(F.CHANNELS[F.MODE_COLOUR]) + seg_hdr.mode),
                        pkt[0].eq(0),
                    ]
                    hdr = data.View(PKT_HEADER, pkt[0])
                    m.d.sync += [hdr.x.eq(seg_hdr.x + jj), hdr.len.eq(n), hdr.y.eq(seg_hdr.y),
                                 hdr.mode.eq(seg_hdr.mode), hdr.dx.eq(n_int)]
                    for k in range(1, F.PACKET_FLITS):
                        m.d.sync += pkt[k].eq(0)
            with m.Else():
                out = Signal(FLIT)
                m.d.comb += [
                    out.value.eq(seg_flit.value + j * seg_flit.inc),
                    out.inc.eq(seg_flit.inc << lg),
                ]
                # channel word number c (1-based) = channels + mode - recv + 1
                cnum = Signal(range(F.PACKET_FLITS + 1))
                hdr_mode = data.View(PKT_HEADER, pkt[0]).mode
                m.d.comb += cnum.eq(len(F.CHANNELS[F.MODE_COLOUR]) + hdr_mode - recv + 1)
                with m.Switch(cnum):
                    for k in range(1, F.PACKET_FLITS):
                        with m.Case(k):
                            m.d.sync += pkt[k].eq(out.as_value())
                m.d.sync += recv.eq(recv - 1)
                with m.If((recv == 1) & keep):
                    m.d.sync += pkt_valid.eq(1)
        # The next line's packet may enter the segment processor in the swap cycle itself: it
        # starts on the ring the cycle after, when the memories have been exchanged.
        swap = Signal()
        m.d.comb += [loop.i.payload.eq(pkt),
                     loop.i.valid.eq(pkt_valid & ((eol == 0) | ((eol == 1) & swap)))]
        with m.If(loop.i.valid & loop.i.ready):
            m.d.sync += pkt_valid.eq(0)

        # ---- merge-bus reader: streams the merge-side buffer into the clock crossing.
        # The read port holds its data while not enabled, so it is the output register.
        q = Signal(range(self._npx + 1), init=self._npx)
        dv = Signal()
        adv = ~dv | merger.i_own.ready
        rd = adv & (q != self._npx)
        m.d.comb += [loop.mb_addr.eq(q), loop.mb_rd.eq(rd),
                     merger.i_own.valid.eq(dv), merger.i_own.payload.eq(loop.mb_data)]
        with m.If(adv):
            m.d.sync += dv.eq(rd)
        with m.If(rd):
            m.d.sync += q.eq(q + 1)
        reader_done = (q == self._npx) & ~dv

        # ---- end of line: swap once the loop has drained and the previous line is read
        m.d.comb += [swap.eq((eol != 0) & loop.swap_ok & reader_done), loop.swap.eq(swap)]
        m.d.sync += eol.eq(eol + eol_in - swap)
        with m.If(swap):
            m.d.sync += [q.eq(0), self.lines.eq(self.lines + 1)]
        with m.If(self.i_seg.valid | (recv != 0) | pkt_valid | ~loop.idle | (eol != 0)):
            m.d.sync += self.busy_cycles.eq(self.busy_cycles + 1)
        return m
