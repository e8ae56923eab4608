"""The DSLB drain of an EXPERTS PXP, its ports and parameter checks, shared by both PXPs
(``pxp.py``, the line Z-buffer; ``pxp_span.py`` and ``pxp_coherent.py``, the span PXPs).

Paper (seed 000, 3.2, the seed's OCR): "DSLBもDMM同様、2重系の構成とい、PXPによる書き込みと、FBへの転送のため
の読み出しとを並行して同時にに行なう" -- the DSLB is double-banked; one bank is written by the resolve side while
the other is read out towards the frame buffer. The drain walks its bank left to right: without
A.J., over ``[lo, hi)``, one pixel per two cycles (read, offer); with A.J. (c), over the guarded
range ``[lo-1, hi+1)`` within the frame, one pixel per three cycles (read the DSLB, read the
visible segment's edges from the segment table or DMM/P bank, blend the boundary and offer the
pixel on its left: ``aj.py``), offering only ``[lo, hi)``; where the range ends at the frame's
right edge (no guard pixel), a flush cycle offers its last pixel. ``boundary_only`` (the span
PXPs): A.J. works at a segment's boundary pixels only (the paper: "多角形の境界線のところに発生する
jagの抑制", blending "直線成分の通過する画素"): the entry is read only for a pixel whose visible segment
differs from its left neighbour's (or the first of the walk), not background; every other pixel is
offered (and a polygon-background boundary blended from the entry already held) in its second
cycle: 2 cycles a pixel, 3 at a segment's first pixel. The resolve side hands a
finished bank over with :meth:`Drain.hand` once :attr:`Drain.dbusy` is low. With ``prod`` (the span
PXP at ``datapath="paper"``) the blend runs on the PXP's one multiplier (``aj.aj_boundary_shared``):
the blend-and-offer step repeats once per multiply (4 or 5 at a blended pixel), :attr:`Drain.mreq`
high in each. The paper does not
give the drain's rate; these are ours, as the golden cycle models (``pxp_cycles``,
``span_cycles``) count them.
"""

from __future__ import annotations

from amaranth import Mux, Signal, unsigned
from amaranth.lib import enum, stream
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import ADDR_BITS, X_END_BITS, X_INT
from rasterhw.hdl.experts.aj import MUL_IN, NONE, aj_boundary, aj_boundary_shared

__all__ = ["Drain", "check_pxp_params", "pxp_members"]


def check_pxp_params(*, width, aj) -> None:
    """The parameters both PXPs take: frame width 1..1024 (Q10.6 x), A.J. ``"none"`` or ``"c"``."""
    if isinstance(width, bool) or not isinstance(width, int) or not 1 <= width <= 1024:
        raise ValueError(f"width must be an integer in 1..1024, not {width!r}")
    if aj not in ("none", "c"):
        raise ValueError(f"aj must be 'none' or 'c', not {aj!r}")


def pxp_members(i_layout, pixel_bits: int) -> dict:
    """The ports both PXPs have: words in (``i_layout``), pixel words out, the range ``[lo, hi)``,
    the finish-time counter and the lines handed over."""
    return {
        "i": In(stream.Signature(i_layout)),
        "o": Out(stream.Signature(unsigned(pixel_bits))),
        "lo": In(X_INT),
        "hi": In(X_END_BITS),
        "line_cycles": Out(16),
        "lines": Out(16),
    }


class _D(enum.Enum, shape=3):
    IDLE = 0
    DRD = 1       # read the DSLB
    DOUT = 2      # without A.J.: offer the pixel
    DSEG = 3      # with A.J.: read the visible segment's entry
    DAJ = 4       # with A.J.: blend the boundary, offer the pixel on its left
    FLUSH = 5     # with A.J.: offer the range's last pixel


class Drain:
    """Drain-side logic of a PXP, added to module ``m``.

    ``o``: the PXP's pixel output stream; ``drd``: the DSLB's drain read port (words with ``pix``,
    ``addr`` and ``slot`` fields of layout ``word``), bank bit at ``bank_bit``; with ``aj``:
    ``trd``, the read port of the segment entries (layout ``ent``, bank bit at ``ent_bank_bit``),
    ``width`` and ``ib`` (intensity bits) for the blend. ``done_comb(drain)``: combinational
    statements for the cycle the drain finishes its bank (e.g. freeing a DMM/P bank).
    """

    def __init__(self, m, *, o, drd, word, bank_bit: int, width: int, ib: int, aj: bool,
                 trd=None, ent=None, ent_bank_bit: int = 0, done_comb=None, boundary_only: bool = False,
                 prod=None):
        self._pb = len(o.payload)
        self.aj = aj
        shared = aj and prod is not None
        #: with ``prod`` (the PXP's one multiplier's product) and A.J.: the blend holds that multiplier
        #: this cycle, with operands ``mul_a``, ``mul_b`` (else ``None``)
        self.mreq = self.mul_a = self.mul_b = None
        if shared:
            self.mreq = Signal(name="aj_mreq")
            self.mul_a, self.mul_b = Signal(MUL_IN, name="drain_mul_a"), Signal(MUL_IN, name="drain_mul_b")
            m.d.comb += self.mreq.eq(0)
        self.dstate = Signal(_D)
        self.dbusy = Signal()
        self.dbank = Signal()
        self.dx = Signal(X_END_BITS)
        self.dlo = Signal(X_INT)
        self.dhi = Signal(X_END_BITS)
        self.dghi = Signal(X_END_BITS)
        dstored = Signal(word)
        self._dstored = dstored
        m.d.comb += [dstored.eq(drd.data), o.payload.eq(dstored.pix), o.valid.eq(0), drd.en.eq(0)]

        self._blend = self._aj_datapath(m, trd=trd, ent=ent, dstored=dstored, width=width, ib=ib,
                                        boundary_only=boundary_only, prod=prod, shared=shared) if aj else None
        self._walk(m, o=o, drd=drd, bank_bit=bank_bit, ent_bank_bit=ent_bank_bit, done_comb=done_comb,
                   trd=trd, shared=shared)

    def _aj_datapath(self, m, *, trd, ent, dstored, width, ib, boundary_only, prod, shared) -> dict:
        """With A.J. (c): the pixel on the walk's left (``p_*``, :attr:`p_ok`: there is one) and the
        current one (``c_*``; its entry from ``trd``), which of them needs its entry read (``skip``:
        ``boundary_only`` and the pixel's segment is its left neighbour's, or background), the blend
        (``aj.aj_boundary``, or ``aj.aj_boundary_shared`` on the PXP's one multiplier ``prod``) and
        ``emit`` (the left pixel is in ``[lo, hi)``). Returns them by name for :meth:`_walk`."""
        dx, dlo, dhi, dstate, pb = self.dx, self.dlo, self.dhi, self.dstate, self._pb
        m.d.comb += trd.en.eq(0)
        p_pix = Signal(pb)            # pixel dx-1 before A.J.
        p_out = Signal(pb)            # pixel dx-1 as it will be output
        p_addr = Signal(ADDR_BITS)
        p_ent = Signal(ent)
        self.p_ok = p_ok = Signal()   # there is a pixel dx-1 in the walk
        c_pix_r = Signal(pb)
        c_addr_r = Signal(ADDR_BITS)
        c_ent = Signal(ent)
        m.d.comb += c_ent.eq(trd.data)
        # boundary_only: in DSEG, a pixel whose segment is its left neighbour's (or background)
        # needs no entry read: it is blended (or passed) in that cycle from the DSLB word itself
        # (the sync read ports hold their data: trd still has the run's segment's entry)
        seg_read = Signal()
        skip = Signal()
        m.d.comb += [seg_read.eq(~((dstored.addr == NONE) | (p_ok & (dstored.addr == p_addr)))),
                     skip.eq((dstate == _D.DSEG) & ~seg_read if boundary_only else 0)]
        c_pix = Signal(pb)
        c_addr = Signal(ADDR_BITS)
        m.d.comb += [c_pix.eq(Mux(skip, dstored.pix, c_pix_r)), c_addr.eq(Mux(skip, dstored.addr, c_addr_r))]
        bnd = {"dx": dx, "width": width, "ib": ib, "p_ok": p_ok, "p_pix": p_pix, "p_out": p_out, "p_addr": p_addr,
               "p_ent": p_ent, "c_pix": c_pix, "c_addr": c_addr, "c_ent": c_ent}
        if shared:
            sh = aj_boundary_shared(m, lo=dlo, hi=dhi, prod=prod, **bnd)
            o_prev, o_cur = sh["o_prev"], sh["o_cur"]
            m.d.comb += [self.mul_a.eq(sh["a"]), self.mul_b.eq(sh["b"])]
        else:
            o_prev, o_cur = aj_boundary(m, **bnd)
        emit = Signal()
        m.d.comb += emit.eq(p_ok & (dx >= dlo + 1) & (dx <= dhi))
        return {"p_pix": p_pix, "p_out": p_out, "p_addr": p_addr, "p_ent": p_ent, "p_ok": p_ok,
                "c_pix_r": c_pix_r, "c_addr_r": c_addr_r, "c_ent": c_ent, "skip": skip, "c_pix": c_pix,
                "c_addr": c_addr, "o_prev": o_prev, "o_cur": o_cur, "emit": emit, "sh": sh if shared else None}

    def _walk(self, m, *, o, drd, bank_bit, ent_bank_bit, done_comb, trd, shared) -> None:
        """The drain's walk over its bank, one state machine (:class:`_D`): ``DRD`` reads the DSLB,
        ``DOUT`` offers the pixel (without A.J.); with A.J. the blend's states (:meth:`_aj_states`)."""
        aj, dstate, dbusy, dbank, dx, dhi = self.aj, self.dstate, self.dbusy, self.dbank, self.dx, self.dhi

        def drain_done():
            m.d.sync += [dbusy.eq(0), dstate.eq(_D.IDLE)]
            if done_comb is not None:
                m.d.comb += done_comb(self)

        with m.If(dbusy), m.Switch(dstate):
            with m.Case(_D.DRD):
                m.d.comb += [drd.addr.eq((dbank << bank_bit) | dx), drd.en.eq(1)]
                m.d.sync += dstate.eq(_D.DSEG if aj else _D.DOUT)
            with m.Case(_D.DOUT):
                m.d.comb += o.valid.eq(1)
                with m.If(o.ready):
                    m.d.sync += dx.eq(dx + 1)
                    with m.If(dx + 1 >= dhi):
                        drain_done()
                    with m.Else():
                        m.d.sync += dstate.eq(_D.DRD)
            if aj:
                self._aj_states(m, o=o, trd=trd, ent_bank_bit=ent_bank_bit, shared=shared, drain_done=drain_done)

    def _aj_states(self, m, *, o, trd, ent_bank_bit, shared, drain_done) -> None:
        """With A.J. (c): ``DSEG`` reads the visible segment's entry (or, ``skip``, blends and offers
        at once), ``DAJ`` blends the boundary and offers the pixel on its left (with ``shared``, one
        multiply a cycle on the PXP's one multiplier, the step repeated), ``FLUSH`` offers the
        range's last pixel at the frame's right edge."""
        dstate, dbank, dx, dhi, dghi, dstored = self.dstate, self.dbank, self.dx, self.dhi, self.dghi, self._dstored
        b = self._blend
        p_pix, p_out, p_addr, p_ent, p_ok, c_pix_r, c_addr_r, c_ent, skip, c_pix, c_addr, o_prev, o_cur, emit, sh = (
            b[k] for k in ("p_pix", "p_out", "p_addr", "p_ent", "p_ok", "c_pix_r", "c_addr_r", "c_ent", "skip",
                           "c_pix", "c_addr", "o_prev", "o_cur", "emit", "sh"))

        def offer():
            m.d.comb += [o.valid.eq(emit), o.payload.eq(o_prev)]
            with m.If(~emit | o.ready):
                m.d.sync += [p_pix.eq(c_pix), p_out.eq(o_cur), p_addr.eq(c_addr), p_ent.eq(c_ent),
                             p_ok.eq(1), dx.eq(dx + 1)]
                if shared:
                    m.d.sync += sh["done"]
                with m.If(dx + 1 >= dghi):
                    with m.If(dghi == dhi):
                        m.d.sync += dstate.eq(_D.FLUSH)
                    with m.Else():
                        drain_done()
                with m.Else():
                    m.d.sync += dstate.eq(_D.DRD)

        def blend_offer():
            if not shared:
                offer()
                return
            # the blend's multiplies, one a cycle, this step repeated; the last one offers
            m.d.comb += self.mreq.eq(sh["need"])
            with m.If(sh["last"]):
                offer()
            with m.Else():
                sh["step"]()

        with m.Case(_D.DSEG):
            with m.If(skip):
                blend_offer()
            with m.Else():
                m.d.comb += [trd.addr.eq((dbank << ent_bank_bit) | dstored.slot), trd.en.eq(1)]
                m.d.sync += [c_pix_r.eq(dstored.pix), c_addr_r.eq(dstored.addr), dstate.eq(_D.DAJ)]
        with m.Case(_D.DAJ):
            blend_offer()
        with m.Case(_D.FLUSH):
            m.d.comb += [o.valid.eq(1), o.payload.eq(p_out)]
            with m.If(o.ready):
                drain_done()

    def hand(self, *, bank, lo, hi, glo, ghi) -> list:
        """Sync statements that hand the resolved ``bank`` (range ``[lo, hi)``, guarded
        ``[glo, ghi)``) to the drain; only while :attr:`dbusy` is low."""
        stmts = [self.dbusy.eq(1), self.dbank.eq(bank), self.dlo.eq(lo), self.dhi.eq(hi), self.dghi.eq(ghi),
                 self.dx.eq(glo), self.dstate.eq(_D.DRD)]
        if self.aj:
            stmts.append(self.p_ok.eq(0))
        return stmts
