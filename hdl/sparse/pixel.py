"""The pixel processor of a video processor: Z test into the local video memory."""

from __future__ import annotations

from amaranth.hdl import Module, Signal, unsigned
from amaranth.lib import memory, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import TRI_BITS, Z_FRAC_BITS

from .layouts import RECORD

__all__ = ["PixelProcessor"]


class PixelProcessor(wiring.Component):
    """Takes the last level's pixels (and the triangle headers before them); for each pixel
    ``zq = clamp(z >> Z_FRAC_BITS, 0, 2**z_bits - 1)`` and, if ``zq < stored`` (strict, so the
    first-submitted triangle keeps a tie), writes ``zq`` and the triangle index into the local
    memory of ``2**n x 2**n`` words (address ``v * 2**n + u``). Empty words hold
    ``z = 2**z_bits`` (beyond every depth) and ``tri = 2**TRI_BITS - 1``.

    Members
    -------
    i : In(stream RECORD).
    rd_addr : In(2n) — video-controller read port (one cycle latency);
    rd_z : Out(z_bits + 1), rd_tri : Out(TRI_BITS).
    writes : Out(32) — pixels written (passed the Z test).
    idle : Out(1).

    Throughput: one pixel per 3 cycles (accept, read, compare/write), no hazards.
    """

    def __init__(self, *, n: int, z_bits: int = 24):
        self._n, self._z_bits = n, z_bits
        super().__init__({"i": In(stream.Signature(RECORD)), "rd_addr": In(2 * n),
                          "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS), "writes": Out(32), "idle": Out(1)})

    def elaborate(self, platform):
        m = Module()
        n, zb = self._n, self._z_bits
        depth = 1 << (2 * n)
        m.submodules.zmem = zmem = memory.Memory(shape=unsigned(zb + 1), depth=depth, init=[1 << zb] * depth)
        m.submodules.tmem = tmem = memory.Memory(shape=unsigned(TRI_BITS), depth=depth,
                                                 init=[(1 << TRI_BITS) - 1] * depth)
        zr = zmem.read_port()
        zw, tw = zmem.write_port(), tmem.write_port()
        zo, to = zmem.read_port(), tmem.read_port()
        m.d.comb += [zo.addr.eq(self.rd_addr), to.addr.eq(self.rd_addr), self.rd_z.eq(zo.data),
                     self.rd_tri.eq(to.data)]
        tri = Signal(TRI_BITS)
        addr = Signal(2 * n)
        zq = Signal(zb + 1)
        zmax = (1 << zb) - 1
        sh = self.i.payload.z >> Z_FRAC_BITS
        m.d.comb += [zr.addr.eq(addr), zw.addr.eq(addr), tw.addr.eq(addr), zw.data.eq(zq), tw.data.eq(tri)]
        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += [self.i.ready.eq(1), self.idle.eq(1)]
                with m.If(self.i.valid):
                    with m.If(self.i.payload.hdr):
                        m.d.sync += tri.eq(self.i.payload.tri)
                    with m.Else():
                        m.d.sync += addr.eq((self.i.payload.v << n) | self.i.payload.u)
                        with m.If(sh < 0):
                            m.d.sync += zq.eq(0)
                        with m.Elif(sh > zmax):
                            m.d.sync += zq.eq(zmax)
                        with m.Else():
                            m.d.sync += zq.eq(sh)
                        m.next = "READ"
            with m.State("READ"):
                m.next = "CMP"
            with m.State("CMP"):
                with m.If(zq < zr.data):
                    m.d.comb += [zw.en.eq(1), tw.en.eq(1)]
                    m.d.sync += self.writes.eq(self.writes + 1)
                m.next = "IDLE"
        return m
