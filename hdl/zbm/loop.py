"""ZB/M segment loop: the segment processor and 8 pixel processors on a 112-bit ring.

Paper, sec. 5.4: "The segment loop is 112 bits wide; segment packets holding the start
coordinate, the segment length, the pixel information and its increments move from pixel
processor to pixel processor every cycle. A segment packet is at most 8 cycles long, and only
one segment packet is put into the loop at a time." "The segment processor controls the loop:
it decides whether a packet may enter the loop and, if so, makes a new packet and puts it in."
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.layouts import GAP, GAP_PENDING, PACKET, PIXEL2, PKT_HEADER, check_interleave
from rasterhw.hdl.zbm.pixel import ZbmPixelProcessor

__all__ = ["ZbmLoop", "PACKET", "LOOP_GAP"]

#: cycles between a packet's header entering the loop and the next header: len + LOOP_GAP
#: (the paper's "waits len cycles, then 8 cycles from the start of input", sec. 6.1 cond. 6)
LOOP_GAP = F.PACKET_FLITS


@params("interleave", "width")
class ZbmLoop(wiring.Component):
    """Segment processor + 8 pixel processors.

    Parameters
    ----------
    interleave : int
        Chips per unit, 1, 2, 4, 8 or 16 (chip pixel ``q = x // interleave``).
    width : int
        Screen width; the chip holds ``ceil(width / interleave)`` pixels per line.

    Members
    -------
    i : In(stream.Signature(PACKET))
        Segment packets (header ``len >= 1``), one transfer per packet.
    swap : In(1)
        Exchange loop-side and merge-bus-side memories; only while ``idle``.
    idle : Out(1)
        No packet held or travelling: every Z write of the line has landed.
    swap_ok : Out(1)
        (Added.) No packet held, and the last Z write of the travelling packet (if any) lands
        at the end of this cycle: a ``swap`` now is safe. High one cycle before ``idle``, so
        the first packet of the next line can enter ``len + LOOP_GAP`` cycles after the last
        one of this line, as within a line.
    gap : Out(GAP)
        (Added, for the paper schedule.) Cycles until a new packet could start on the ring: the
        spacing counter, or ``GAP_PENDING`` while a held packet has not started.
    mb_addr : In(range(chip pixels)), mb_rd : In(1), mb_data : Out(PIXEL2)
        The merge bus: chip pixel ``q`` (processor ``q % 8``, address ``q // 8``) appears on
        ``mb_data`` one cycle after ``mb_rd`` and is cleared for the next line.

    Timing: a packet accepted in cycle ``t`` enters the loop (header at the processor owning
    its first pixel) in cycle ``t + 1`` if the loop is free, then one flit per cycle; the next
    header may enter ``len + LOOP_GAP`` cycles after this one. One packet is held while the
    previous one travels, so ``i.ready`` is high again as soon as the held packet's last flit
    has entered the loop.
    """

    def __init__(self, *, interleave: int = 1, width: int = F.MAX_WIDTH):
        check_interleave(interleave)
        if not 1 <= width <= F.MAX_WIDTH:
            raise ValueError(f"width must be 1..{F.MAX_WIDTH}, not {width!r}")
        self._interleave = interleave
        self._width = width
        self._npx = -(-width // interleave)
        super().__init__({
            "i": In(stream.Signature(PACKET)),
            "swap": In(1),
            "idle": Out(1),
            "swap_ok": Out(1),
            "gap": Out(GAP),
            "mb_addr": In(range(self._npx)),
            "mb_rd": In(1),
            "mb_data": Out(PIXEL2),
        })

    @property
    def chip_pixels(self) -> int:
        return self._npx

    def elaborate(self, platform):
        m = Module()
        n = F.PP_PER_CHIP
        lg = self._interleave.bit_length() - 1
        pps = [ZbmPixelProcessor(index=k, interleave=self._interleave, width=self._width) for k in range(n)]
        for k, pp in enumerate(pps):
            m.submodules[f"pp{k}"] = pp

        # ---- segment processor
        buf = Signal(PACKET)
        full = Signal()
        inj = Signal(range(F.PACKET_FLITS + 1))      # flits of the held packet already injected
        inj_pp = Signal(range(n))
        wait = Signal(range(F.MAX_WIDTH + LOOP_GAP + 1))
        hdr = data.View(PKT_HEADER, buf[0])
        start = full & (inj == 0) & (wait == 0)
        injecting = full & ((inj != 0) | start)
        m.d.comb += self.i.ready.eq(~full)
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += [buf.eq(self.i.payload), full.eq(1), inj.eq(0)]
        with m.If(wait != 0):
            m.d.sync += wait.eq(wait - 1)
        with m.If(start):
            m.d.sync += [inj_pp.eq((hdr.x >> lg)[:F.PP_BITS]), wait.eq(hdr.len + LOOP_GAP - 1)]
        with m.If(injecting):
            m.d.sync += inj.eq(inj + 1)
            with m.If(inj == F.PACKET_FLITS - 1):
                m.d.sync += [full.eq(0), inj.eq(0)]
        cur_pp = Mux(start, (hdr.x >> lg)[:F.PP_BITS], inj_pp)
        flit = Signal(unsigned(F.LOOP_BITS))
        m.d.comb += flit.eq(buf[inj[:F.FLIT_BITS]])

        # ---- the ring: processor k's input is k-1's output unless the segment processor injects
        for k, pp in enumerate(pps):
            prev = pps[k - 1].o_loop
            here = injecting & (cur_pp == k)
            m.d.comb += [
                pp.i_loop.valid.eq(Mux(here, 1, prev.valid)),
                pp.i_loop.idx.eq(Mux(here, inj[:F.FLIT_BITS], prev.idx)),
                pp.i_loop.flit.eq(Mux(here, flit, prev.flit)),
                pp.swap.eq(self.swap),
                pp.mb_addr.eq(self.mb_addr >> F.PP_BITS),
                pp.mb_rd.eq(self.mb_rd & (self.mb_addr[:3] == k)),
            ]
        m.d.comb += self.idle.eq(~full & (wait == 0))
        m.d.comb += self.gap.eq(Mux(full & (inj == 0), GAP_PENDING, wait))
        # The last flit (7) of a packet started in cycle t0 writes its last pixel (hop len - 1)
        # in cycle t0 + len + 6; wait == 1 in cycle t0 + len + 7.
        m.d.comb += self.swap_ok.eq(~full & (wait <= 1))

        # ---- merge bus
        sel = Signal(range(n))
        with m.If(self.mb_rd):
            m.d.sync += sel.eq(self.mb_addr[:3])
        with m.Switch(sel):
            for k, pp in enumerate(pps):
                with m.Case(k):
                    m.d.comb += self.mb_data.eq(pp.mb_data)
        return m
