"""A video processor of the matrix: set-up, one pipeline stage per level with FIFOs, pixel processor."""

from __future__ import annotations

from amaranth.hdl import Module, Signal
from amaranth.lib import fifo, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import MATRIX_LOG2_MAX, TRI_BITS

from .layouts import BROADCAST, RECORD
from .pixel import PixelProcessor
from .stage import LevelStage

__all__ = ["VideoProcessor"]


def _log2(name: str, v: int) -> int:
    if not isinstance(v, int) or v < 1 or v & (v - 1) or v > 1 << MATRIX_LOG2_MAX:
        raise ValueError(f"{name} must be a power of two in 1..{1 << MATRIX_LOG2_MAX}, not {v!r}")
    return v.bit_length() - 1


class VideoProcessor(wiring.Component):
    """Video processor ``(a, b)`` of a ``p x q`` matrix with ``2**n x 2**n`` sparse rasters.

    The set-up rewrites each broadcast triangle for this processor's lattice — ``A' = pA``,
    ``B' = qB``, ``C' = C + aA + bB``, depth ``Z0 = z00 + a*zx + b*zy``, ``zu = p*zx``,
    ``zv = q*zy``, aperture growth ``(|A| alpha + |B| beta) / 2`` — and sends a header and the
    root window into the input FIFO of level 1. Levels 1..n are :class:`LevelStage` s, each fed
    by a FIFO (``fifo_depth`` records); the last one feeds the :class:`PixelProcessor`.

    Members
    -------
    i : In(stream BROADCAST) — triangles, in submission order.
    rd_addr, rd_z, rd_tri — the local memory's video-controller read port (one cycle latency).
    tests : Out(32) per level (``tests_1 .. tests_n``) — coverage tests (busy cycles) per stage.
    stalls : Out(32) per level.
    writes : Out(32) — pixels written.
    busy : Out(1) — a record is still somewhere in the processor.
    """

    def __init__(self, *, n: int, p: int = 4, q: int = 4, a: int = 0, b: int = 0, alpha: int = 2, beta: int = 2,
                 z_bits: int = 24, fifo_depth: int = 8, test: str = "exact"):
        if not isinstance(n, int) or not 1 <= n <= 12:
            raise ValueError(f"n must be an integer in 1..12, not {n!r}")
        self._lp, self._lq = _log2("p", p), _log2("q", q)
        if not (0 <= a < p and 0 <= b < q):
            raise ValueError(f"processor ({a}, {b}) is outside a {p}x{q} matrix")
        if not (isinstance(alpha, int) and isinstance(beta, int) and 0 <= alpha <= 15 and 0 <= beta <= 15):
            raise ValueError(f"aperture must be integers in 0..15, not {alpha}x{beta}")
        self._n, self._p, self._q, self._a, self._b = n, p, q, a, b
        self._alpha, self._beta, self._z_bits, self._depth, self._test = alpha, beta, z_bits, fifo_depth, test
        ports = {"i": In(stream.Signature(BROADCAST)), "rd_addr": In(2 * n), "rd_z": Out(z_bits + 1),
                 "rd_tri": Out(TRI_BITS), "writes": Out(32), "busy": Out(1)}
        for lvl in range(1, n + 1):
            ports[f"tests_{lvl}"] = Out(32)
            ports[f"stalls_{lvl}"] = Out(32)
        super().__init__(ports)

    @property
    def n(self) -> int:
        return self._n

    def elaborate(self, platform):
        m = Module()
        n = self._n
        stages = []
        fifos = []
        for lvl in range(1, n + 1):
            st = LevelStage(level=lvl, n=n, p=self._p, q=self._q, a=self._a, b=self._b, alpha=self._alpha,
                            beta=self._beta, test=self._test)
            m.submodules[f"level{lvl}"] = st
            stages.append(st)
        for k in range(n + 1):
            f = fifo.SyncFIFOBuffered(width=RECORD.size, depth=self._depth)
            m.submodules[f"fifo{k}"] = f
            fifos.append(f)
        m.submodules.pixel = px = PixelProcessor(n=n, z_bits=self._z_bits)

        def push(src, f):
            m.d.comb += [f.w_data.eq(src.payload), f.w_en.eq(src.valid), src.ready.eq(f.w_rdy)]

        def pop(f, dst):
            m.d.comb += [dst.payload.eq(f.r_data), dst.valid.eq(f.r_rdy), f.r_en.eq(dst.ready)]

        # set-up: header, then the root window, into FIFO 0
        setup_o = stream.Signature(RECORD).create()
        bc = Signal(BROADCAST)
        hdr = Signal(RECORD)
        root = Signal(RECORD)
        a, b, lp, lq = self._a, self._b, self._lp, self._lq
        for k in range(3):
            absA = (bc.A[k] < 0).as_unsigned() * -bc.A[k] + (bc.A[k] >= 0).as_unsigned() * bc.A[k]
            absB = (bc.B[k] < 0).as_unsigned() * -bc.B[k] + (bc.B[k] >= 0).as_unsigned() * bc.B[k]
            m.d.comb += [hdr.Ap[k].eq(bc.A[k] << lp), hdr.Bp[k].eq(bc.B[k] << lq), hdr.thr[k].eq(bc.thr[k]),
                         hdr.ext[k].eq((absA * self._alpha + absB * self._beta) >> 1),
                         root.E[k].eq(bc.C[k] + a * bc.A[k] + b * bc.B[k])]
        for k in range(4):
            m.d.comb += hdr.bbox[k].eq(bc.bbox[k])
        m.d.comb += [hdr.hdr.eq(1), hdr.zu.eq(bc.zx << lp), hdr.zv.eq(bc.zy << lq), hdr.tri.eq(bc.tri),
                     root.z.eq(bc.z00 + a * bc.zx + b * bc.zy)]
        setup_idle = Signal()
        with m.FSM(name="setup"):
            with m.State("IDLE"):
                m.d.comb += [self.i.ready.eq(1), setup_idle.eq(1)]
                with m.If(self.i.valid):
                    m.d.sync += bc.eq(self.i.payload)
                    m.next = "HDR"
            with m.State("HDR"):
                m.d.comb += [setup_o.valid.eq(1), setup_o.payload.eq(hdr)]
                with m.If(setup_o.ready):
                    m.next = "ROOT"
            with m.State("ROOT"):
                m.d.comb += [setup_o.valid.eq(1), setup_o.payload.eq(root)]
                with m.If(setup_o.ready):
                    m.next = "IDLE"
        push(setup_o, fifos[0])
        for k, st in enumerate(stages):
            pop(fifos[k], st.i)
            push(st.o, fifos[k + 1])
            m.d.comb += [getattr(self, f"tests_{k + 1}").eq(st.tests), getattr(self, f"stalls_{k + 1}").eq(st.stalls)]
        pop(fifos[n], px.i)
        m.d.comb += [px.rd_addr.eq(self.rd_addr), self.rd_z.eq(px.rd_z), self.rd_tri.eq(px.rd_tri),
                     self.writes.eq(px.writes)]
        idle = setup_idle & px.idle
        for st in stages:
            idle = idle & st.idle
        for f in fifos:
            idle = idle & (f.level == 0)
        m.d.comb += self.busy.eq(~idle)
        return m
