"""ZB/M initial processor: segment words -> one segment packet for this chip (paper, sec. 5.4).

Paper, sec. 5.4: the initial processor does the interleave pre-processing — from the segment
broadcast to every chip it keeps what this chip's pixels need — and puts it in the packet
format of the segment loop. Golden twin: :func:`rasterhw.golden_model.zbm.initial.initial_processor`.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.layouts import (
    FLIT,
    GAP,
    PACKET,
    PKT_HEADER,
    SEG_HEADER,
    check_interleave,
    check_schedule,
    paper_lead,
)

__all__ = ["ZbmInitialProcessor"]


@params("schedule", "interleave", "chip")
class ZbmInitialProcessor(wiring.Component):
    """Turns a segment (``SEG_HEADER`` + one ``FLIT`` per channel) into this chip's packet.

    For a segment starting at ``x`` with ``len`` pixels, this chip's first pixel is
    ``x + j`` with ``j = (chip - x) mod interleave``; the packet carries that x, the number of
    this chip's pixels ``n = ceil((len - j) / interleave)`` (dropped when 0), every channel's
    value stepped ``j`` pixels (``value + j * inc``) and the increment scaled to the chip's
    pixel spacing (``inc * interleave``).

    Parameters
    ----------
    interleave : int
        Chips per unit: 1, 2, 4, 8 or 16.
    chip : int
        This chip's slot, ``0 <= chip < interleave``.
    schedule : str
        ``"overlap"`` (ours: a segment is taken whenever no packet waits here) or ``"paper"``
        (a segment header is taken only when ``gap <= paper_lead(mode)``, so its packet
        reaches the ring exactly when the ring frees and nothing is buffered ahead of it).

    Members
    -------
    i : In(stream.Signature(unsigned(112)))
        Segment words (format in :mod:`rasterhw.hdl.zbm.chip`); an end-of-line record
        (``SEG_HEADER`` with ``len == 0``) is accepted and reported on ``eol``.
    o : Out(stream.Signature(PACKET))
        One 8-flit packet per segment that has a pixel on this chip.
    eol : Out(1)
        High in the cycle an end-of-line record is accepted.
    hold : In(1)
        While high, no input is accepted (the chip has two ends of line pending).
    busy : Out(1)
        A segment is being received or a packet waits on ``o``.
    gap : In(GAP) (``schedule="paper"`` only)
        The loop's ring gap (``ZbmLoop.gap``).

    Timing: a segment is received in ``1 + channels`` cycles; the packet is offered the cycle
    after its last channel word; no input is taken while a packet waits.
    """

    def __init__(self, *, interleave: int = 1, chip: int = 0, schedule: str = "overlap"):
        check_interleave(interleave, chip)
        check_schedule(schedule)
        self._interleave = interleave
        self._chip = chip
        self._schedule = schedule
        members = {
            "i": In(stream.Signature(unsigned(F.LOOP_BITS))),
            "o": Out(stream.Signature(PACKET)),
            "eol": Out(1),
            "hold": In(1),
            "busy": Out(1),
        }
        if schedule == "paper":
            members["gap"] = In(GAP)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        lg = self._interleave.bit_length() - 1
        n_int = self._interleave
        pkt = Signal(PACKET)
        pkt_valid = Signal()     # complete packet waiting for the segment processor
        recv = Signal(range(F.PACKET_FLITS))   # channel words still expected
        j = Signal(4)            # pixels skipped to reach this chip's first pixel
        keep = Signal()
        seg_hdr = data.View(SEG_HEADER, self.i.payload)
        seg_flit = data.View(FLIT, self.i.payload)
        if self._schedule == "paper":
            lead = Mux(seg_hdr.mode == F.MODE_MAPPING, paper_lead(F.MODE_MAPPING), paper_lead(F.MODE_COLOUR))
            early = (recv == 0) & (seg_hdr.len != 0) & (self.gap > lead)   # ring not free in time
        else:
            early = 0
        m.d.comb += [
            self.i.ready.eq(~pkt_valid & ~self.hold & ~early),
            self.o.valid.eq(pkt_valid),
            self.o.payload.eq(pkt),
            self.busy.eq((recv != 0) | pkt_valid),
        ]
        with m.If(self.i.valid & self.i.ready):
            with m.If(recv == 0):
                with m.If(seg_hdr.len == 0):
                    m.d.comb += self.eol.eq(1)
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
        with m.If(self.o.valid & self.o.ready):
            m.d.sync += pkt_valid.eq(0)
        return m
