"""The pixel processor of a video processor: Z test into the local video memory."""

from __future__ import annotations

from amaranth.hdl import Cat, Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import memory, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.fixed import COLOUR_BITS
from rasterhw.golden_model.sparse.formats import TRI_BITS, Z_ACC_BITS, Z_FRAC_BITS
from rasterhw.hdl.sparse.benchread import bench_read_ports, check_lanes
from rasterhw.hdl.sparse.layouts import layouts

__all__ = ["PixelProcessor"]


class PixelProcessor(wiring.Component):
    """Takes the last level's pixels (and the triangle headers before them); for each pixel
    ``zq = clamp(z >> Z_FRAC_BITS, 0, 2**z_bits - 1)`` and, if ``zq < stored`` (strict, so the
    first-submitted triangle keeps a tie), writes ``zq`` and the triangle index into the local
    memory of ``2**n x 2**n`` words (address ``v * 2**n + u``). Empty words hold
    ``z = 2**z_bits`` (beyond every depth) and ``tri = 2**TRI_BITS - 1``.

    Members
    -------
    i, i_hdr : In(stream WINDOW), In(stream HEADER).
    rd_addr : In(2n) — video-controller read port (one cycle latency);
    rd_z : Out(z_bits + 1), rd_tri : Out(TRI_BITS).
    writes : Out(32) — pixels written (passed the Z test).
    idle : Out(1).
    rd_rgb : Out(24) (``colour`` only) — R | G << 8 | B << 16 at ``rd_addr`` (one cycle latency).
    rdw_addr : In, rdw_data : Out (``read_lanes`` > 0 only) — the bench's read port
        (``hdl/sparse/benchread.py``): ``read_lanes`` more read ports on each memory, reading sparse
        addresses ``rdw_addr * read_lanes + j`` (one cycle latency), word ``j`` ``{rgb, tri, z}``.

    ``colour``: the pixels are ``WINDOW_RGB`` (the headers ``HEADER_RGB``); each pixel's colour is
    rounded as ``fixed.colour_rgb8`` (``clamp((c + 2**15) >> 16, 0, 255)``) beside its depth and
    written into a third local memory (0 where empty) with its depth, in the same cycle.

    Throughput: one pixel per cycle (accept, read, compare/write pipelined; the compare read is
    transparent for the write, so back-to-back pixels at one address see each other).
    """

    def __init__(self, *, n: int, z_bits: int = 24, colour: bool = False, read_lanes: int = 0):
        self._n, self._z_bits, self._colour, self._lanes = n, z_bits, colour, read_lanes
        self._lane_log2 = check_lanes(n, read_lanes)
        _, header, window = layouts(colour)
        ports = {"i": In(stream.Signature(window)), "i_hdr": In(stream.Signature(header)), "rd_addr": In(2 * n),
                 "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS), "writes": Out(32), "idle": Out(1)}
        if colour:
            ports["rd_rgb"] = Out(3 * COLOUR_BITS)
        ports.update(bench_read_ports(n, z_bits, colour, read_lanes))
        super().__init__(ports)

    def elaborate(self, platform):
        m = Module()
        n, zb = self._n, self._z_bits
        depth = 1 << (2 * n)
        m.submodules.zmem = zmem = memory.Memory(shape=unsigned(zb + 1), depth=depth, init=[1 << zb] * depth)
        m.submodules.tmem = tmem = memory.Memory(shape=unsigned(TRI_BITS), depth=depth,
                                                 init=[(1 << TRI_BITS) - 1] * depth)
        # compare-port read is transparent for the write port: a pixel read in the cycle its
        # address is written sees the new depth, so one pixel per cycle needs no stall
        zw, tw = zmem.write_port(), tmem.write_port()
        zr = zmem.read_port(transparent_for=(zw,))
        zo, to = zmem.read_port(), tmem.read_port()
        m.d.comb += [zo.addr.eq(self.rd_addr), to.addr.eq(self.rd_addr), self.rd_z.eq(zo.data),
                     self.rd_tri.eq(to.data)]
        tri = Signal(TRI_BITS)
        zmax = (1 << zb) - 1
        sh = self.i.payload.z >> Z_FRAC_BITS
        # stage 1: read issued; stage 2: compare and write
        v1, v2 = Signal(), Signal()
        a1, a2 = Signal(2 * n), Signal(2 * n)
        z1, z2 = Signal(zb + 1), Signal(zb + 1)
        t1, t2 = Signal(TRI_BITS), Signal(TRI_BITS)
        need = self.i.payload.new
        m.d.comb += [self.i.ready.eq(~need | self.i_hdr.valid), self.i_hdr.ready.eq(self.i.valid & need),
                     self.idle.eq(~v1 & ~v2), zr.addr.eq(a1)]
        take = self.i.valid & (~need | self.i_hdr.valid)
        this_tri = Signal(TRI_BITS)
        m.d.comb += this_tri.eq(tri)
        with m.If(take & need):
            m.d.comb += this_tri.eq(self.i_hdr.payload.tri)
            m.d.sync += tri.eq(self.i_hdr.payload.tri)
        m.d.sync += [v1.eq(take), a1.eq((self.i.payload.v << n) | self.i.payload.u), t1.eq(this_tri)]
        with m.If(sh < 0):
            m.d.sync += z1.eq(0)
        with m.Elif(sh > zmax):
            m.d.sync += z1.eq(zmax)
        with m.Else():
            m.d.sync += z1.eq(sh)
        m.d.sync += [v2.eq(v1), a2.eq(a1), z2.eq(z1), t2.eq(t1)]
        m.d.comb += [zw.addr.eq(a2), tw.addr.eq(a2), zw.data.eq(z2), tw.data.eq(t2)]
        with m.If(v2 & (z2 < zr.data)):
            m.d.comb += [zw.en.eq(1), tw.en.eq(1)]
            m.d.sync += self.writes.eq(self.writes + 1)
        mems = [zmem, tmem]
        if self._colour:
            mems.append(self._rgb(m, depth, a2, zw.en))
        if self._lanes:
            self._bench_read(m, mems)
        return m

    def _bench_read(self, m, mems):
        """The bench's port: ``read_lanes`` read ports on every memory, lane ``j`` at sparse address
        ``rdw_addr * read_lanes + j``."""
        words = []
        for j in range(self._lanes):
            addr = Cat(Const(j, self._lane_log2), self.rdw_addr)
            ports = [mem.read_port() for mem in mems]
            m.d.comb += [rp.addr.eq(addr) for rp in ports]
            words.append(Cat(*(rp.data for rp in ports)))
        m.d.comb += self.rdw_data.eq(Cat(*words))

    def _rgb(self, m, depth, a2, wen):
        """The colour memory (returned): the pixel's R, G, B rounded on its way in, carried beside
        the pipeline's depth and written with it."""
        m.submodules.cmem = cmem = memory.Memory(shape=unsigned(3 * COLOUR_BITS), depth=depth, init=[0] * depth)
        cw, cr = cmem.write_port(), cmem.read_port()
        m.d.comb += [cr.addr.eq(self.rd_addr), self.rd_rgb.eq(cr.data)]
        half, top = 1 << (Z_FRAC_BITS - 1), (1 << COLOUR_BITS) - 1
        rgb = Signal(3 * COLOUR_BITS)
        for ch in range(3):
            lv = Signal(signed(Z_ACC_BITS + 1), name=f"lv{ch}")
            m.d.comb += lv.eq((self.i.payload.c[ch] + half) >> Z_FRAC_BITS)
            m.d.comb += rgb[COLOUR_BITS * ch:COLOUR_BITS * (ch + 1)].eq(Mux(lv < 0, 0, Mux(lv > top, top, lv[:COLOUR_BITS])))
        c1, c2 = Signal(3 * COLOUR_BITS), Signal(3 * COLOUR_BITS)
        m.d.sync += [c1.eq(rgb), c2.eq(c1)]
        m.d.comb += [cw.addr.eq(a2), cw.data.eq(c2), cw.en.eq(wen)]
        return cmem
