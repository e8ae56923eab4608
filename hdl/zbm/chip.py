"""ZB/M chip: initial processor (``ZbmInitialProcessor``) -> segment processor -> segment loop -> pixel memories ->
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
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.initial import ZbmInitialProcessor
from rasterhw.hdl.zbm.layouts import GAP, GAP_PENDING, PIXEL2, check_interleave, check_schedule
from rasterhw.hdl.zbm.loop import ZbmLoop
from rasterhw.hdl.zbm.merger import ZbmMerger

__all__ = ["ZbmChip"]


@params("schedule", "interleave", "chip", "width")
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
    schedule : str
        ``"overlap"`` (ours) or ``"paper"`` (sec. 6.1: see ``ZbmInitialProcessor`` and
        ``docs/zbm.md#paper-schedule``).

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
    gap : Out(GAP)
        (Added.) Cycles until the ring could start a new packet (``ZbmLoop.gap``),
        ``GAP_PENDING`` while a packet waits in the chip; the paper-schedule generator loads
        only when every chip's gap is small enough.

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
                 fifo_depth: int = 16, schedule: str = "overlap"):
        check_interleave(interleave, chip)
        check_schedule(schedule)
        self._schedule = schedule
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
            "gap": Out(GAP),
        })

    @property
    def chip_pixels(self) -> int:
        """Pixels per line this chip sends down the merge chain."""
        return self._npx

    def elaborate(self, platform):
        m = Module()
        n_int = self._interleave
        m.submodules.loop = loop = ZbmLoop(interleave=n_int, width=self._width)
        m.submodules.merger = merger = ZbmMerger(word_layout=PIXEL2, fifo_depth=self._fifo_depth)
        wiring.connect(m, wiring.flipped(self.i_merge), merger.i_merge)
        wiring.connect(m, merger.o_merge, wiring.flipped(self.o_merge))

        m.d.sync += self.cycles.eq(self.cycles + 1)

        # ---- initial processor: segment words -> one packet for this chip's interleave slot
        m.submodules.initial = ip = ZbmInitialProcessor(interleave=n_int, chip=self._chip,
                                                        schedule=self._schedule)
        if self._schedule == "paper":
            m.d.comb += ip.gap.eq(loop.gap)
        m.d.comb += self.gap.eq(Mux(ip.o.valid, GAP_PENDING, loop.gap))
        wiring.connect(m, wiring.flipped(self.i_seg), ip.i)
        eol = Signal(2)          # end-of-line records seen whose swap is pending (0..2)
        # The next line's segment may be received while a swap is pending: a held packet
        # always belongs after every pending end of line (it blocks further input).
        m.d.comb += ip.hold.eq(eol == 2)
        eol_in = ip.eol
        # The next line's packet may enter the segment processor in the swap cycle itself: it
        # starts on the ring the cycle after, when the memories have been exchanged. The gate
        # depends on the swap condition only, never on the loop's ready.
        swap = Signal()
        gate = (eol == 0) | ((eol == 1) & swap)
        m.d.comb += [loop.i.payload.eq(ip.o.payload),
                     loop.i.valid.eq(ip.o.valid & gate),
                     ip.o.ready.eq(loop.i.ready & gate)]

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
        with m.If(self.i_seg.valid | ip.busy | ~loop.idle | (eol != 0)):
            m.d.sync += self.busy_cycles.eq(self.busy_cycles + 1)
        return m
