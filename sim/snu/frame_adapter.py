# amaranth: UnusedElaboratable=no
"""Bench adapter of the SNU headline frame: the pixel bus drawing one whole frame as the machine
does, on the generic engines (``sim/engines/``), beside the engines' read-out :class:`~rasterhw.sim.engines.readout.ReadOut` (its :func:`sweep`).

The schedule (the one the frame's dedicated Verilog bench played before this adapter replaced it):

1. CLEAR is offered in the first clock;
2. once the bus is idle again the two pipelines run: each write is offered ``gap`` clocks after
   its predecessor was accepted, plus one (the first one ``gap`` clocks after the pipelines are
   released); the 16-bit ``gap`` rides in the word and is counted here, so the engine plays the
   words back to back and its 8-bit gaps do not matter;
3. when both pipelines have given their end token and the bus is idle, SWAP is offered;
4. the display buffer (the frame just drawn) is streamed out on ``o`` (``{rgb, z}``, address
   order), and the schedule on ``o_sched``: five words of the bus's ``cycle`` counter --
   CLEAR accepted, first clock the pipelines run, both drained and idle, SWAP accepted, and the
   frame's length (SWAP + 1).
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.sim.engines.readout import sweep
from rasterhw.sim.snu.frame_format import GAP_BITS, SCHEDULE
from rasterhw.sim.testbench import port_of

__all__ = ["GAP_BITS", "FrameAdapter", "SCHEDULE"]



class FrameAdapter(wiring.Component):
    """The pixel bus with a frame's clear, producer gaps, swap and read-out around it.

    Every port in ``ports`` carries ``{end, gap, write}`` (the bus's write payload in the low bits,
    then ``GAP_BITS`` of gap, then ``end`` on top: the port's last word, taken at once). ``o``:
    ``words`` read-out words of the display buffer; ``o_sched``: the :data:`SCHEDULE` words.
    """

    def __init__(self, block, ports: tuple[str, ...], words: int) -> None:
        self.block, self._ports, self._words = block, tuple(ports), words
        sig = {p: In(stream.Signature(len(port_of(block, p).payload.as_value()) + GAP_BITS + 1))
               for p in self._ports}
        sig["o"] = Out(stream.Signature(len(block.rd_z) + len(block.rd_rgb)))
        sig["o_sched"] = Out(stream.Signature(32))
        super().__init__(sig)

    def extra_verilog(self) -> str:
        """The block's hand-written Verilog (its RAM model), for the Verilator bench."""
        return self.block.extra_verilog() if hasattr(self.block, "extra_verilog") else ""

    def elaborate(self, platform):
        m = Module()
        m.submodules.block = b = self.block
        t = {k: Signal(32, name=k) for k in SCHEDULE}
        run, drained, swapped, started = Signal(), Signal(), Signal(), Signal()
        cleared = Signal()

        # 1-3: CLEAR (payload 0) in the first clock, SWAP (payload 1) once drained
        m.d.comb += [b.i_cmd.valid.eq(~cleared | (drained & ~swapped)), b.i_cmd.payload.eq(cleared)]
        with m.If(b.i_cmd.valid & b.i_cmd.ready):
            with m.If(~cleared):
                m.d.sync += [cleared.eq(1), t["t_clear"].eq(b.cycle)]
            with m.Else():
                m.d.sync += [swapped.eq(1), t["t_swap"].eq(b.cycle), t["cycles"].eq(b.cycle + 1)]
        with m.If(cleared & ~run & b.idle):
            m.d.sync += run.eq(1)
        with m.If(run & ~started):
            m.d.sync += [started.eq(1), t["t_start"].eq(b.cycle)]

        # 2: each pipeline's writes, each after its gap (clocks since the previous acceptance)
        ended = []
        for p in self._ports:
            src, dst = port_of(self, p), port_of(b, p)
            pw = len(dst.payload.as_value())
            end, gap = src.payload[pw + GAP_BITS], src.payload[pw:pw + GAP_BITS]
            since = Signal(GAP_BITS, name=f"{p}_since")   # clocks the pipeline has run since its last write
            seen = Signal(name=f"{p}_ended")
            go = run & (since >= gap)
            m.d.comb += [dst.valid.eq(src.valid & ~end & go), dst.payload.eq(src.payload[:pw]),
                         src.ready.eq(end | (dst.ready & go))]
            with m.If(dst.valid & dst.ready):
                m.d.sync += since.eq(0)
            with m.Elif(run & (since != (1 << GAP_BITS) - 1)):
                m.d.sync += since.eq(since + 1)
            with m.If(src.valid & end):
                m.d.sync += seen.eq(1)
            ended.append(seen | (src.valid & end))
        with m.If(started & Cat(*ended).all() & b.idle & ~drained):
            m.d.sync += [drained.eq(1), t["t_pixels_done"].eq(b.cycle)]

        # 4: the schedule, then the display buffer read out (rd_buf = 1 after the swap)
        k = Signal(range(len(SCHEDULE) + 1))
        m.d.comb += [self.o_sched.valid.eq(swapped & (k < len(SCHEDULE))),
                     self.o_sched.payload.eq(Mux(k == 0, t["t_clear"], 0))]
        for i, name in enumerate(SCHEDULE[1:], start=1):
            with m.If(k == i):
                m.d.comb += self.o_sched.payload.eq(t[name])
        with m.If(self.o_sched.valid & self.o_sched.ready):
            m.d.sync += k.eq(k + 1)
        m.d.comb += b.rd_buf.eq(1)
        sweep(m, b.rd_addr, Cat(b.rd_z, b.rd_rgb), self.o, self._words, swapped)
        return m
