# amaranth: UnusedElaboratable=no
"""Bench adapter of the SNU frame-memory blocks: the block's write streams in, its memory out.

The pixel-bus blocks (``pixelbus-bank``, ``pixelbus``) have no output stream: what they make is
the content of their frame memory, read through a side port (``rd_addr`` -> ``rd_rgb``,
``rd_z`` one clock later). :class:`ReadOut` turns that into a stream the generic engines
(``sim/engines/``) collect and compare, so the blocks run on the same testbench as every
other block.
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.sim.testbench import port_of

__all__ = ["ReadOut", "sweep"]


class ReadOut(wiring.Component):
    """A frame-memory block with an end token on every write stream and a read-out stream.

    Every port in ``ports`` (the block's write streams, same names) carries the block's payload
    with one more bit on top, ``end``: a word with ``end`` set is not a write but the port's last
    word (taken at once, never passed on). Once every port has given its end token and the block
    is idle (``busy`` low: every write and memory cycle finished), the adapter sweeps ``rd_addr``
    over ``0 .. words - 1`` (``rd_buf`` = 0, the draw buffer) and streams each word out on ``o``
    as ``{rgb, z}`` (``z`` in the low bits), one per clock while ``o.ready`` is high; the address
    is held while the sink stalls, so the payload holds too (the stream rules). ``i_cmd`` stays
    idle: no clear, no swap (the memory starts at zero, as after a clear).

    Timing: if the sweep starts at clock ``S`` (the first clock with every token taken and the
    block idle), word ``k`` is transferred at edge ``S + 1 + k`` when ``o`` is always ready, so
    ``S = first read-out stamp - 1`` is the block's own cycle count for the writes.
    """

    def __init__(self, block, ports: tuple[str, ...], words: int) -> None:
        self.block, self._ports, self._words = block, tuple(ports), words
        sig = {p: In(stream.Signature(len(port_of(block, p).payload.as_value()) + 1)) for p in self._ports}
        sig["o"] = Out(stream.Signature(len(block.rd_z) + len(block.rd_rgb)))
        super().__init__(sig)

    def extra_verilog(self) -> str:
        """The block's hand-written Verilog (its RAM model), for the Verilator bench."""
        return self.block.extra_verilog() if hasattr(self.block, "extra_verilog") else ""

    def elaborate(self, platform):
        m = Module()
        m.submodules.block = b = self.block
        ended = []
        for p in self._ports:
            src, dst = port_of(self, p), port_of(b, p)
            pw = len(dst.payload.as_value())
            end, seen = src.payload[pw], Signal(name=f"{p}_ended")
            m.d.comb += [dst.valid.eq(src.valid & ~end), dst.payload.eq(src.payload[:pw]),
                         src.ready.eq(end | dst.ready)]
            with m.If(src.valid & end):
                m.d.sync += seen.eq(1)
            ended.append(seen)
        m.d.comb += [b.i_cmd.valid.eq(0), b.rd_buf.eq(0)]

        sweep(m, b, self.o, self._words, Cat(*ended).all() & ~b.busy)
        return m


def sweep(m: Module, block, o, words: int, start) -> None:
    """In ``m``: once ``start`` is high, sweep ``block.rd_addr`` over ``0 .. words - 1`` and stream
    each word out on ``o`` as ``{rgb, z}``, one per clock while ``o.ready`` is high (the address,
    so the payload, held while the sink stalls); once only."""
    sweeping, finished = Signal(), Signal()
    ptr = Signal(range(words + 1))
    take = o.valid & o.ready
    with m.If(start & ~sweeping & ~finished):
        m.d.sync += sweeping.eq(1)
    with m.If(take):
        m.d.sync += ptr.eq(ptr + 1)
        with m.If(ptr == words - 1):
            m.d.sync += [sweeping.eq(0), finished.eq(1)]
    # present the next address on a transfer, so the data is there in the next clock
    m.d.comb += [block.rd_addr.eq(Mux(take, ptr + 1, ptr)), o.valid.eq(sweeping),
                 o.payload.eq(Cat(block.rd_z, block.rd_rgb))]
