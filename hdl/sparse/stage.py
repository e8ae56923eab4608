"""One level of the recursive pixel search: a pipeline stage of the raster processor."""

from __future__ import annotations

from amaranth.hdl import Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import EDGE_BITS, MATRIX_LOG2_MAX, SUBPIXEL_BITS
from rasterhw.hdl.sparse.layouts import layouts

__all__ = ["LevelStage", "param_charge"]


def param_charge(m: Module, credit: Signal, extra: Signal, kp: int, ke: int) -> None:
    """Formula (5)'s parameter additions for one surviving window (or pixel), in the current
    control block: ``kp`` additions on ``ke`` edge adders, ``credit`` additions left over from the
    level's last parameter cycle (``golden_model/sparse/stack.py``, ``param_cycles``): ``extra`` (comb)
    is the whole cycles to spend now, ``credit`` (sync) what is left of them."""
    with m.Switch(credit):
        for c in range(max(ke, kp + 1)):
            need = kp - c
            dc, left = (0, -need) if need <= 0 else (-(-need // ke), -(-need // ke) * ke - need)
            with m.Case(c):
                m.d.comb += extra.eq(dc)
                m.d.sync += credit.eq(left)


class LevelStage(wiring.Component):
    """Level ``level`` (1..n) of processor ``(a, b)`` of a ``p x q`` matrix.

    A window marked ``new`` is taken together with the next triangle header; each window is split
    into its four sub-windows (``du, dv`` in 0, 1: corner values by the per-level increments
    ``A' * 2**(n-level)``, ``B' * 2**(n-level)``, depth likewise) and each sub-window gets one
    coverage test per cycle (τ = one cycle): below the pixel level the window rectangle
    ``[p(2**(n-i) - 1) + alpha] x [q(2**(n-i) - 1) + beta]`` against the three edges and (test
    ``"exact"``) the triangle's bounding box; at the pixel level the top-left point test.
    Survivors go out in order ``(0,0), (1,0), (0,1), (1,1)``, as the golden model's; before a
    triangle's first survivor its header goes out on ``o_hdr`` (one cycle, not a test).

    Members
    -------
    a, b : In(MATRIX_LOG2_MAX) — the processor's place in the matrix (only the exact test uses it).
    i, i_hdr : In(stream WINDOW), In(stream HEADER) — parent windows and their triangles' headers.
    o, o_hdr : Out(stream WINDOW), Out(stream HEADER) — surviving sub-windows (pixels at the last
        level) and their headers.
    tests : Out(32) — coverage tests made (one per busy cycle: the stage's ``t_i / τ``).
    stalls : Out(32) — cycles a survivor waited for ``o.ready``.
    idle : Out(1) — no record held.

    Throughput: 4 cycles per window (the next window is taken in the cycle of the last test),
    plus one cycle per triangle that has survivors here (its header).

    ``colour``: windows and headers carry R, G, B (``WINDOW_RGB``, ``HEADER_RGB``), stepped like
    depth. ``kp`` > 0: formula (5)'s parameter additions, ``kp`` per survivor on ``ke`` edge adders
    (:func:`param_charge`, the credit reset with every triangle), paid after the survivor has gone
    out in whole cycles in which the stage waits (``PARAM``); after a fourth sub-window the next
    window is taken in the last of them. A triangle then holds the stage
    ``4 w_(i-1) + [w_i > 0] + ceil(w_i kp / ke)`` cycles (``cycles.stage_cycles``) plus its stalls.
    """

    def __init__(self, *, level: int, n: int, p: int, q: int, alpha: int = 2, beta: int = 2,
                 test: str = "exact", colour: bool = False, kp: int = 0, ke: int = 3):
        if not 1 <= level <= n:
            raise ValueError(f"level must be in 1..{n}, not {level!r}")
        if test not in ("exact", "edges"):
            raise ValueError(f"test must be 'exact' or 'edges', not {test!r}")
        self._level, self._n, self._p, self._q = level, n, p, q
        self._alpha, self._beta, self._test = alpha, beta, test
        self._colour, self._kp, self._ke = colour, kp, ke
        _, header, window = layouts(colour)
        super().__init__({"a": In(MATRIX_LOG2_MAX), "b": In(MATRIX_LOG2_MAX),
                          "i": In(stream.Signature(window)), "i_hdr": In(stream.Signature(header)),
                          "o": Out(stream.Signature(window)), "o_hdr": Out(stream.Signature(header)),
                          "tests": Out(32), "stalls": Out(32), "idle": Out(1)})

    @property
    def level(self) -> int:
        return self._level

    def elaborate(self, platform):
        m = Module()
        n, lvl, p, q = self._n, self._level, self._p, self._q
        sh = n - lvl  # log2 of the sub-window side N
        N = 1 << sh
        last = lvl == n
        _, header, window = layouts(self._colour)
        hdr = Signal(header)
        win = Signal(window)
        sent = Signal()   # this triangle's header has gone out of this level
        fresh = Signal()  # ... and its first window has not
        child = Signal(2)
        du, dv = child[0], child[1]
        out = Signal(window)
        ok = Signal()
        half = 1 << (SUBPIXEL_BITS - 1)

        # the sub-window: corner values by increments, no multiplier (N is a power of two)
        m.d.comb += out.new.eq(fresh)
        # (a child bit selects the increment: a multiplexer, not a multiplier)
        for k in range(3):
            m.d.comb += out.E[k].eq(win.E[k] + Mux(du, hdr.Ap[k] << sh, 0) + Mux(dv, hdr.Bp[k] << sh, 0))
        m.d.comb += [out.z.eq(win.z + Mux(du, hdr.zu << sh, 0) + Mux(dv, hdr.zv << sh, 0)),
                     out.u.eq(win.u + (du << sh)), out.v.eq(win.v + (dv << sh))]
        if self._colour:
            for ch in range(3):
                m.d.comb += out.c[ch].eq(win.c[ch] + Mux(du, hdr.cu[ch] << sh, 0) + Mux(dv, hdr.cv[ch] << sh, 0))
        conds = []
        for k in range(3):
            if last:
                val = out.E[k]
            else:
                mx = Signal(signed(EDGE_BITS + 2), name=f"mx{k}")
                pos = Signal(signed(EDGE_BITS), name=f"pos{k}")
                m.d.comb += pos.eq(Mux(hdr.Ap[k] > 0, hdr.Ap[k], 0) + Mux(hdr.Bp[k] > 0, hdr.Bp[k], 0))
                m.d.comb += mx.eq(out.E[k] + (pos << sh) - pos + hdr.ext[k])
                val = mx
            conds.append(val >= hdr.thr[k])
        if self._test == "exact" and not last:
            us = Signal(signed(24))
            vs = Signal(signed(24))
            m.d.comb += [us.eq(out.u), vs.eq(out.v)]
            a, b, al, be = self.a, self.b, self._alpha, self._beta
            lp, lq, ls = p.bit_length() - 1, q.bit_length() - 1, SUBPIXEL_BITS   # p, q, sub: powers of two
            x0 = (((us << lp) + a) << ls) + half - al * half
            x1 = ((((us + (N - 1)) << lp) + a) << ls) + half + al * half
            y0 = (((vs << lq) + b) << ls) + half - be * half
            y1 = ((((vs + (N - 1)) << lq) + b) << ls) + half + be * half
            conds += [x1 >= hdr.bbox[0], x0 <= hdr.bbox[1], y1 >= hdr.bbox[2], y0 <= hdr.bbox[3]]
        acc = conds[0]
        for c in conds[1:]:
            acc = acc & c
        m.d.comb += ok.eq(acc)

        kp, ke = self._kp, self._ke
        if kp:
            credit = Signal(range(max(ke, kp + 1)))
            extra = Signal(range(kp + 2))
            pcount = Signal(range(kp + 2))
            pend = Signal()  # the parameter cycles follow a fourth sub-window: take the next window

        def accept():
            need = self.i.payload.new
            m.d.comb += [self.i.ready.eq(~need | self.i_hdr.valid), self.i_hdr.ready.eq(self.i.valid & need)]
            with m.If(self.i.valid & (~need | self.i_hdr.valid)):
                m.d.sync += [win.eq(self.i.payload), child.eq(0)]
                with m.If(need):
                    m.d.sync += [hdr.eq(self.i_hdr.payload), sent.eq(0), fresh.eq(0)]
                    if kp:
                        m.d.sync += credit.eq(0)
                m.next = "TEST"
            with m.Else():
                m.next = "IDLE"

        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += self.idle.eq(1)
                accept()
            with m.State("TEST"):
                advance = Signal()
                with m.If(ok & ~sent):
                    # the triangle's header goes ahead of its first survivor at this level
                    m.d.comb += [self.o_hdr.valid.eq(1), self.o_hdr.payload.eq(hdr)]
                    with m.If(self.o_hdr.ready):
                        m.d.sync += [sent.eq(1), fresh.eq(1)]
                with m.Elif(ok):
                    m.d.comb += [self.o.valid.eq(1), self.o.payload.eq(out), advance.eq(self.o.ready)]
                    with m.If(self.o.ready):
                        m.d.sync += fresh.eq(0)
                        if kp:
                            param_charge(m, credit, extra, kp, ke)
                    with m.Else():
                        m.d.sync += self.stalls.eq(self.stalls + 1)
                with m.Else():
                    m.d.comb += advance.eq(1)
                with m.If(advance):
                    m.d.sync += [self.tests.eq(self.tests + 1), child.eq(child + 1)]
                    if kp:
                        with m.If(extra != 0):
                            m.d.sync += [pcount.eq(extra), pend.eq(child == 3)]
                            m.next = "PARAM"
                        with m.Elif(child == 3):
                            accept()
                    else:
                        with m.If(child == 3):
                            accept()  # the next window is taken in the cycle of the last test: 4 cycles a window
            if kp:
                with m.State("PARAM"):
                    # the stage waits while the edge adders step the survivor's surface parameters
                    m.d.sync += pcount.eq(pcount - 1)
                    with m.If(pcount == 1):
                        with m.If(pend):
                            accept()
                        with m.Else():
                            m.next = "TEST"
        return m
