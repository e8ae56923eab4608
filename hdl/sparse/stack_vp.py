"""A video processor whose raster processor is the paper's "процессор со стеком": one coverage-test
unit and a stack of windows, depth first, in front of the same pixel processor."""

from __future__ import annotations

from amaranth.hdl import Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, memory, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import (
    EDGE_BITS,
    MATRIX_LOG2_MAX,
    SUBPIXEL_BITS,
    TRI_BITS,
    UV_BITS,
    Z_ACC_BITS,
)
from rasterhw.hdl.sparse.benchread import bench_read_ports, check_lanes, forward_bench_read
from rasterhw.hdl.sparse.layouts import layouts
from rasterhw.hdl.sparse.pixel import PixelProcessor
from rasterhw.hdl.sparse.stage import param_charge
from rasterhw.hdl.sparse.vp import check_params, rewrite_record

__all__ = ["StackProcessor", "make_stack_vp"]


class StackProcessor(wiring.Component):
    """A video processor of a ``p x q`` matrix with ``2**n x 2**n`` sparse rasters whose raster
    processor is one coverage-test unit and a stack (seed 002's "процессор со стеком", eq. (8)),
    bit and cycle for cycle ``golden_model/sparse/stack.py``'s ``stack_processor``.

    * **Set-up** (3 cycles, as the pipeline processor's): take the broadcast record (``i``), rewrite
      it for processor ``(a, b)`` into a header (``A' = pA``, ``B' = qB``, aperture growth, depth
      ``zu = p zx``, ``zv = q zy``), load the root window (``C' = C + aA + bB``, ``Z0``) into the
      current-window register.
    * **Search**, one coverage test per cycle (τ = one cycle): sub-window ``c`` (``(0,0), (1,0),
      (0,1), (1,1)``) of the current window of level ``l`` is its corner plus ``A' 2**(n-l-1)`` /
      ``B' 2**(n-l-1)`` (a shift by the level, no multiplier) and gets the pipeline's test (window
      rectangle against the edges and the bounding box below the pixel level, the top-left point
      test at it). Survivors ``c < 3`` are pushed; a surviving ``c = 3`` is the next current window
      at once; otherwise the top of the stack is popped into the register in the same cycle (the
      stack's read is combinational). A pixel goes to the :class:`PixelProcessor` in the cycle of
      its test (it never pushes back). A record ends in the cycle of a fourth test with no survivor
      and an empty stack; the next record is taken on the next cycle. So a record holds the
      processor ``3 + tests`` cycles (``cycles.service_times(vp="stack")``).
    * The stack holds ``3 (n - 1)`` windows (three waiting siblings per level above the pixels).
    * **Surface parameters** (``colour``): the record is ``BROADCAST_RGB``; R, G, B are carried with
      every window and stepped with the edges, like depth; a written pixel's colour
      (``clamp((c + 2**15) >> 16)``, ``fixed.colour_rgb8``'s rounding) goes into the pixel
      processor's colour memory with its depth (``rd_rgb``), as in the pipeline processor. **Their cost** (``kp`` > 0): formula (5)'s ``w_i k_p / k_e`` — every surviving
      window or pixel of level ``i`` needs ``kp`` parameter additions on the ``ke`` edge adders,
      paid in whole cycles in which the test unit waits, with what is left of a cycle's ``ke``
      additions kept per level for the next survivor of the same record (``stack.param_cycles``):
      ``ceil(w_i kp / ke)`` cycles per level and record, ``cycles.service_times(vp="stack", kp=kp)``.

    Members
    -------
    a, b : In(MATRIX_LOG2_MAX) — the processor's place in the matrix (held constant).
    i : In(stream BROADCAST) — triangles, in submission order.
    rd_addr, rd_z, rd_tri — the local memory's video-controller read port (one cycle latency).
    tests_1 .. tests_n : Out(32) — coverage tests per level.
    busy_cycles : Out(32) — cycles holding a record (the take cycle, set-up and tests).
    records : Out(32) — records taken.
    max_stack : Out(8) — the most windows the stack held.
    rd_rgb : Out(24) (``colour`` only) — R | G << 8 | B << 16 at ``rd_addr`` (one cycle latency).
    writes : Out(32) — pixels written.
    busy : Out(1) — a record is still somewhere in the processor.
    rdw_addr, rdw_data (``read_lanes`` > 0 only) — the pixel processor's bench read port
        (``hdl/sparse/benchread.py``; not the paper's).
    """

    def __init__(self, *, n: int, p: int = 4, q: int = 4, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                 colour: bool = False, kp: int = 0, ke: int = 3, read_lanes: int = 0):
        try:
            self._lp, self._lq = check_params(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, colour=colour,
                                              kp=kp, ke=ke)
            check_lanes(n, read_lanes)
        except ValueError:
            self._MustUse__silence = True  # a rejected parameter set is not an unused design
            raise
        self._n, self._p, self._q, self._alpha, self._beta, self._z_bits = n, p, q, alpha, beta, z_bits
        self._colour, self._kp, self._ke, self._lanes = colour, kp, ke, read_lanes
        ports = {"a": In(MATRIX_LOG2_MAX), "b": In(MATRIX_LOG2_MAX),
                 "i": In(stream.Signature(layouts(colour)[0])),
                 "rd_addr": In(2 * n), "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS), "writes": Out(32),
                 "busy": Out(1), "busy_cycles": Out(32), "records": Out(32), "max_stack": Out(8)}
        if colour:
            ports["rd_rgb"] = Out(24)
        for lvl in range(1, n + 1):
            ports[f"tests_{lvl}"] = Out(32)
        ports.update(bench_read_ports(n, z_bits, colour, read_lanes))
        super().__init__(ports)

    @property
    def n(self) -> int:
        return self._n

    @property
    def stack_depth(self) -> int:
        return max(1, 3 * (self._n - 1))

    def elaborate(self, platform):
        m = Module()
        n = self._n
        lp, lq, ls = self._lp, self._lq, SUBPIXEL_BITS
        lvl_bits = max(1, (n - 1).bit_length())
        fields = {"lvl": unsigned(lvl_bits), "E": data.ArrayLayout(signed(EDGE_BITS), 3),
                  "z": signed(Z_ACC_BITS), "u": unsigned(UV_BITS), "v": unsigned(UV_BITS)}
        if self._colour:
            fields["c"] = data.ArrayLayout(signed(Z_ACC_BITS), 3)
        entry = data.StructLayout(fields)
        D = self.stack_depth
        m.submodules.stack = st = memory.Memory(shape=entry, depth=D, init=[])
        wr = st.write_port()
        rd = st.read_port(domain="comb")
        m.submodules.pixel = px = PixelProcessor(n=n, z_bits=self._z_bits, colour=self._colour, read_lanes=self._lanes)
        forward_bench_read(m, self, px, self._lanes)
        m.d.comb += [px.rd_addr.eq(self.rd_addr), self.rd_z.eq(px.rd_z), self.rd_tri.eq(px.rd_tri),
                     self.writes.eq(px.writes)]
        if self._colour:
            m.d.comb += self.rd_rgb.eq(px.rd_rgb)

        broadcast, header, _ = layouts(self._colour)
        bc = Signal(broadcast)
        hdr = Signal(header)
        cur = Signal(entry)
        sp = Signal(range(D + 1))
        child = Signal(2)
        du, dv = child[0], child[1]
        a, b = self.a, self.b

        # set-up: the header and the root window from the latched record (the pipeline's arithmetic)
        hdr_c = Signal(header)
        root = Signal(entry)
        rewrite_record(m, bc, hdr_c, root, a=a, b=b, lp=lp, lq=lq, alpha=self._alpha, beta=self._beta,
                       colour=self._colour)

        # the sub-window under test: shift by sh = n - 1 - level (the child side 2**sh)
        sh = Signal(range(n))
        m.d.comb += sh.eq(n - 1 - cur.lvl)
        N1 = Signal(UV_BITS)  # 2**sh - 1
        m.d.comb += N1.eq((Const(1, UV_BITS + 1) << sh) - 1)
        out = Signal(entry)
        m.d.comb += [out.lvl.eq(cur.lvl + 1), out.u.eq(cur.u + (du << sh)), out.v.eq(cur.v + (dv << sh)),
                     out.z.eq(cur.z + Mux(du, hdr.zu << sh, 0) + Mux(dv, hdr.zv << sh, 0))]
        for k in range(3):
            m.d.comb += out.E[k].eq(cur.E[k] + Mux(du, hdr.Ap[k] << sh, 0) + Mux(dv, hdr.Bp[k] << sh, 0))
        if self._colour:
            for ch in range(3):
                m.d.comb += out.c[ch].eq(cur.c[ch] + Mux(du, hdr.cu[ch] << sh, 0) + Mux(dv, hdr.cv[ch] << sh, 0))
        last = Signal()
        m.d.comb += last.eq(cur.lvl == n - 1)
        pt, win = [], []
        for k in range(3):
            pos = Signal(signed(EDGE_BITS), name=f"pos{k}")
            mx = Signal(signed(EDGE_BITS + 2), name=f"mx{k}")
            m.d.comb += [pos.eq(Mux(hdr.Ap[k] > 0, hdr.Ap[k], 0) + Mux(hdr.Bp[k] > 0, hdr.Bp[k], 0)),
                         mx.eq(out.E[k] + (pos << sh) - pos + hdr.ext[k])]
            pt.append(out.E[k] >= hdr.thr[k])
            win.append(mx >= hdr.thr[k])
        us, vs = Signal(signed(24)), Signal(signed(24))
        m.d.comb += [us.eq(out.u), vs.eq(out.v)]
        half, al, be = 1 << (SUBPIXEL_BITS - 1), self._alpha, self._beta
        x0 = (((us << lp) + a) << ls) + half - al * half
        x1 = ((((us + N1) << lp) + a) << ls) + half + al * half
        y0 = (((vs << lq) + b) << ls) + half - be * half
        y1 = ((((vs + N1) << lq) + b) << ls) + half + be * half
        win += [x1 >= hdr.bbox[0], x0 <= hdr.bbox[1], y1 >= hdr.bbox[2], y0 <= hdr.bbox[3]]
        ok_pt, ok_win = Signal(), Signal()
        acc = pt[0]
        for c in pt[1:]:
            acc = acc & c
        m.d.comb += ok_pt.eq(acc)
        acc = win[0]
        for c in win[1:]:
            acc = acc & c
        m.d.comb += ok_win.eq(acc)

        # the pixel processor: every pixel carries its triangle's header (it takes it with the pixel)
        m.d.comb += [px.i.payload.new.eq(1), px.i.payload.u.eq(out.u), px.i.payload.v.eq(out.v),
                     px.i.payload.z.eq(out.z), px.i_hdr.payload.eq(hdr), px.i_hdr.valid.eq(px.i.valid)]
        for k in range(3):
            m.d.comb += px.i.payload.E[k].eq(out.E[k])
            if self._colour:
                m.d.comb += px.i.payload.c[k].eq(out.c[k])
        m.d.comb += [rd.addr.eq(sp - 1), wr.addr.eq(sp), wr.data.eq(out)]

        # formula (5)'s parameter cycles: per level, additions left from its last parameter cycle
        kp, ke = self._kp, self._ke
        cmax = max(ke, kp + 1)
        credit = [Signal(range(cmax), name=f"credit{lvl}") for lvl in range(n)]
        extra = Signal(range(kp + 2))
        pcount = Signal(range(kp + 2))
        after_idle = Signal()
        survivor = Signal()
        idle = Signal()
        if kp:
            with m.If(survivor):
                with m.Switch(cur.lvl):
                    for lvl in range(n):
                        with m.Case(lvl):
                            param_charge(m, credit[lvl], extra, kp, ke)
        with m.FSM(name="stack"):
            with m.State("IDLE"):
                m.d.comb += [self.i.ready.eq(1), idle.eq(1)]
                with m.If(self.i.valid):
                    m.d.sync += [bc.eq(self.i.payload), self.busy_cycles.eq(self.busy_cycles + 1),
                                 self.records.eq(self.records + 1)]
                    m.next = "HDR"
            with m.State("HDR"):
                m.d.sync += [hdr.eq(hdr_c), self.busy_cycles.eq(self.busy_cycles + 1)]
                m.next = "ROOT"
            with m.State("ROOT"):
                m.d.sync += [cur.eq(root), child.eq(0), self.busy_cycles.eq(self.busy_cycles + 1)]
                m.d.sync += [c.eq(0) for c in credit]
                m.next = "TEST"
            with m.State("PARAM"):
                # the test unit waits while the edge adders step the surface parameters
                m.d.sync += [self.busy_cycles.eq(self.busy_cycles + 1), pcount.eq(pcount - 1)]
                with m.If(pcount == 1):
                    with m.If(after_idle):
                        m.next = "IDLE"
                    with m.Else():
                        m.next = "TEST"
            with m.State("TEST"):
                m.d.sync += [self.busy_cycles.eq(self.busy_cycles + 1), child.eq(child + 1)]
                with m.Switch(cur.lvl):
                    for lvl in range(n):
                        with m.Case(lvl):
                            cnt = getattr(self, f"tests_{lvl + 1}")
                            m.d.sync += cnt.eq(cnt + 1)
                keep = Signal()
                m.d.comb += [keep.eq(~last & ok_win), survivor.eq(keep | (last & ok_pt))]
                with m.If(last & ok_pt):
                    m.d.comb += px.i.valid.eq(1)
                done = Signal()
                m.d.comb += done.eq((child == 3) & ~keep & (sp == 0))
                with m.If(extra != 0):
                    m.d.sync += [pcount.eq(extra), after_idle.eq(done)]
                    m.next = "PARAM"
                with m.If(child != 3):
                    with m.If(keep):
                        m.d.comb += wr.en.eq(1)
                        m.d.sync += sp.eq(sp + 1)
                        with m.If(sp + 1 > self.max_stack):
                            m.d.sync += self.max_stack.eq(sp + 1)
                with m.Elif(keep):
                    m.d.sync += cur.eq(out)
                with m.Elif(sp != 0):
                    m.d.sync += [cur.eq(rd.data), sp.eq(sp - 1)]
                with m.Elif(extra == 0):
                    m.next = "IDLE"
        m.d.comb += self.busy.eq(~idle | ~px.idle)
        return m


def make_stack_vp(*, n: int = 7, p: int = 4, q: int = 4, alpha: int = 2, beta: int = 2,
                  z_bits: int = 24, colour: bool = False, kp: int = 0, ke: int = 3) -> StackProcessor:
    """Factory for ``rasterhw verilog sparse-stack-vp``: by default a processor of a 4x4 matrix on
    the 512 x 512 raster (n = 7), depth only, parameter additions unpriced (``kp = 0``, as the
    pipeline processor); ``colour=True, kp=4`` carries R, G, B and prices depth + RGB as (5)."""
    return StackProcessor(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, colour=colour, kp=kp, ke=ke)
