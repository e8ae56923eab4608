"""The p x q matrix of video processors: a broadcast input and the interleaved read-out."""

from __future__ import annotations

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.hdl.sparse.layouts import BROADCAST
from rasterhw.hdl.sparse.vp import VideoProcessor

__all__ = ["Matrix", "make_matrix"]


class Matrix(wiring.Component):
    """``p x q`` :class:`VideoProcessor` s behind one broadcast register.

    The geometry processor's record is held in a register until every processor has taken it
    ("выдает описания геометрических примитивов всем видеопроцессорам матрицы в режиме
    Broadcast"); each processor's input FIFOs let it run ahead of or behind the others. The
    video controller reads pixel ``(x, y)`` of the full ``p*2**n x q*2**n`` raster from processor
    ``(x mod p, y mod q)`` at sparse address ``(y div q) * 2**n + x div p`` ("как единая память с
    расслоением по двум координатным осям").

    Members
    -------
    i : In(stream BROADCAST).
    rd_x, rd_y : In — full-raster pixel to read; rd_z, rd_tri : Out — its depth and triangle one
        cycle later (empty: ``z = 2**z_bits``, ``tri = 2**TRI_BITS - 1``).
    busy : Out(1) — a record is still in the broadcast register or in a processor.
    max_tests : Out(32) — the largest busy-cycle count of any stage of any processor.
    """

    def __init__(self, *, n: int, p: int = 2, q: int = 2, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                 fifo_depth: int = 8):
        self._vps = [VideoProcessor(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, fifo_depth=fifo_depth)
                     for _ in range(p * q)]
        self._n, self._p, self._q, self._z_bits = n, p, q, z_bits
        lp, lq = p.bit_length() - 1, q.bit_length() - 1
        super().__init__({"i": In(stream.Signature(BROADCAST)), "rd_x": In(n + lp), "rd_y": In(n + lq),
                          "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS), "busy": Out(1), "max_tests": Out(32)})

    def elaborate(self, platform):
        m = Module()
        n, p, q = self._n, self._p, self._q
        lp, lq = p.bit_length() - 1, q.bit_length() - 1
        P = p * q
        full = Signal()
        rec = Signal(BROADCAST)
        taken = Signal(P)
        all_taken = Signal()
        nxt = Signal(P)
        for k, vp in enumerate(self._vps):
            m.submodules[f"vp{k}"] = vp
            m.d.comb += [vp.a.eq(k % p), vp.b.eq(k // p), vp.i.payload.eq(rec),
                         vp.i.valid.eq(full & ~taken[k]),
                         nxt[k].eq(taken[k] | (vp.i.valid & vp.i.ready))]
        m.d.comb += all_taken.eq(nxt == (1 << P) - 1)
        # the register takes a new record when empty or when the last processor takes the old one
        m.d.comb += self.i.ready.eq(~full | all_taken)
        with m.If(full & all_taken):
            m.d.sync += [full.eq(0), taken.eq(0)]
        with m.Elif(full):
            m.d.sync += taken.eq(nxt)
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += [rec.eq(self.i.payload), full.eq(1), taken.eq(0)]
        # read-out: processor (x mod p, y mod q), address (y div q) * 2**n + x div p
        sel = Signal(range(P + 1))
        ypart = self.rd_y[:lq] * p if lq else 0
        xpart = self.rd_x[:lp] if lp else 0
        m.d.sync += sel.eq(ypart + xpart)
        addr = (self.rd_y[lq:] << n) | self.rd_x[lp:]
        busy = full
        mx = Signal(32)
        for k, vp in enumerate(self._vps):
            m.d.comb += vp.rd_addr.eq(addr)
            with m.If(sel == k):
                m.d.comb += [self.rd_z.eq(vp.rd_z), self.rd_tri.eq(vp.rd_tri)]
            busy = busy | vp.busy
        m.d.comb += self.busy.eq(busy)
        # the busiest stage anywhere (the matrix's P_p is set by it)
        best = Signal(32)
        vals = [getattr(vp, f"tests_{i}") for vp in self._vps for i in range(1, n + 1)]
        acc = vals[0]
        for j, v in enumerate(vals[1:]):
            nxt_max = Signal(32, name=f"max{j}")  # a signal per step keeps the expression linear
            m.d.comb += nxt_max.eq(Mux(v > acc, v, acc))
            acc = nxt_max
        m.d.comb += [best.eq(acc), mx.eq(best), self.max_tests.eq(mx)]
        return m


def make_matrix(*, n: int = 4, p: int = 2, q: int = 2, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                fifo_depth: int = 8) -> Matrix:
    """Factory for ``rasterhw verilog sparse-matrix`` (default: 2x2 processors on a 32x32 raster)."""
    return Matrix(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, fifo_depth=fifo_depth)
