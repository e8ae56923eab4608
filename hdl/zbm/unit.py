"""ZB/M polygon-processing unit: one segment generator broadcasting to ``interleave`` chips
(paper, sec. 6.1: "polygon processing unit = segment generator + scan-line Z-buffer merger").

Units are chained by their merge ports: chip ``c`` of unit ``k`` feeds chip ``c`` of unit
``k + 1`` (every chip of a slot sees the same pixels), so a chain of units is a chain per
interleave slot. The head unit (``head=True``) feeds its chips empty pixels itself.
"""

from __future__ import annotations

from amaranth import Module, Mux, unsigned
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.broadcast import StreamBroadcast
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.chip import ZbmChip
from rasterhw.hdl.zbm.layouts import PIXEL2, check_interleave, check_schedule
from rasterhw.hdl.zbm.pixel import EMPTY_PIXEL2
from rasterhw.hdl.zbm.seggen import EP_WORD_BITS, ZbmSegmentGenerator

__all__ = ["ZbmUnit"]


@params("interleave", "head", "schedule")
class ZbmUnit(wiring.Component):
    """Segment generator + ``interleave`` ZB/M chips.

    Parameters
    ----------
    interleave : int
        1, 2, 4, 8 or 16 chips.
    width, height : int
        Frame size (1..512).
    capacity : int
        Active-edge-pair memory depth.
    head : bool
        First unit of a chain: no merge input ports, chips merge against empty pixels.
    schedule : str
        ``"overlap"`` (ours) or ``"paper"`` (the paper's sec. 6.1 schedule: the generator
        loads only as the chips run dry, the chips take a segment only when their ring frees;
        ``docs/zbm.md#paper-schedule``).

    Members
    -------
    i : In(stream.Signature(unsigned(168)))
        Edge-pair words (``hdl/zbm/seggen.py``), segment clock.
    i_merge : In(stream.Signature(PIXEL2)).array(interleave), ``merge`` clock (not if ``head``)
    o_merge : Out(stream.Signature(PIXEL2)).array(interleave), ``merge`` clock
        Per chip slot, the merged double-Z pixels of each line (chip ``c``: x = c, c + I, ...).
    cycles : Out(32)
        Segment-clock cycles since reset.
    frames : Out(16)
        Frames the segment generator has finished.
    lines : Out(16)
        (Added.) Scan lines every chip has finished (pixel memories swapped): the minimum of
        the chips' ``lines`` counters.
    overflow : Out(1)
        (Added.) The segment generator's sticky overflow: a line needs more active edge pairs
        than ``capacity``; the unit has stopped without emitting that line.

    Timing: the segment generator's word goes to all chips in the same cycle and is taken
    when every chip is ready, so the busiest chip sets the pace (``len_chip + 8`` per segment).
    """

    def __init__(self, *, interleave: int = 8, width: int = F.MAX_WIDTH, height: int = F.MAX_HEIGHT,
                 capacity: int = F.AEP_CAPACITY, head: bool = True, schedule: str = "overlap"):
        check_interleave(interleave)
        check_schedule(schedule)
        self._schedule = schedule
        if not (isinstance(width, int) and interleave <= width <= F.MAX_WIDTH):
            raise ValueError(f"width must be {interleave}..{F.MAX_WIDTH}, not {width!r}")
        self._interleave, self._width, self._height = interleave, width, height
        self._capacity, self._head = capacity, head
        members = {
            "i": In(stream.Signature(unsigned(EP_WORD_BITS))),
            "o_merge": Out(stream.Signature(PIXEL2)).array(interleave),
            "cycles": Out(32),
            "frames": Out(16),
            "lines": Out(16),
            "overflow": Out(1),
        }
        if not head:
            members["i_merge"] = In(stream.Signature(PIXEL2)).array(interleave)
        super().__init__(members)

    def chip_pixels(self, chip: int) -> int:
        return -(-(self._width - chip) // self._interleave)

    def elaborate(self, platform):
        m = Module()
        n = self._interleave
        m.submodules.seggen = sg = ZbmSegmentGenerator(width=self._width, height=self._height,
                                                       capacity=self._capacity, schedule=self._schedule)
        wiring.connect(m, wiring.flipped(self.i), sg.i)
        chips = [ZbmChip(interleave=n, chip=c, width=self._width, schedule=self._schedule) for c in range(n)]
        m.submodules.broadcast = bc = StreamBroadcast(sg.o.payload.shape(), n=n)
        wiring.connect(m, sg.o, bc.i)
        for c, chip in enumerate(chips):
            m.submodules[f"chip{c}"] = chip
            wiring.connect(m, bc.o[c], chip.i_seg)
            wiring.connect(m, chip.o_merge, wiring.flipped(self.o_merge[c]))
            if self._head:
                m.d.comb += [chip.i_merge.valid.eq(1),
                             chip.i_merge.payload.eq(PIXEL2.const(EMPTY_PIXEL2))]
            else:
                wiring.connect(m, wiring.flipped(self.i_merge[c]), chip.i_merge)
        m.d.comb += [self.cycles.eq(chips[0].cycles), self.frames.eq(sg.frames),
                     self.overflow.eq(sg.overflow)]
        low = chips[0].lines
        for chip in chips[1:]:
            low = Mux(chip.lines < low, chip.lines, low)
        m.d.comb += self.lines.eq(low)
        if self._schedule == "paper":
            gap = chips[0].gap
            for chip in chips[1:]:
                gap = Mux(chip.gap > gap, chip.gap, gap)
            m.d.comb += sg.zbm_gap.eq(gap)
        return m
