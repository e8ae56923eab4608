"""A.J. (c) at a segment boundary in the PXP's drain, shared by both PXPs (``pxp.py``, the line
Z-buffer; ``pxp_span.py`` and ``pxp_coherent.py``, the span PXPs): the paper's anti-jagging blends the two pixels at
a boundary between two polygons by the covered fraction alpha of the edge that crosses it
(eq. (5), C = alpha C_L + (1 - alpha) C_R per R, G, B, I field, Q0.8, rounded), alpha from the
edge's end x and slope (``golden_model/experts/alpha.py`` is the golden side)."""

from __future__ import annotations

from amaranth import Mux, Signal, signed
from rasterhw.golden_model.experts.formats import (
    ADDR_BITS,
    ALPHA_BITS,
    SLOPE_FRAC,
    WORD,
    X_END_BITS,
    X_FRAC,
    XP_BITS,
)

__all__ = ["aj_boundary", "aj_boundary_shared", "MUL_IN"]

NONE = (1 << ADDR_BITS) - 1     # ASB address / polygon number of the background


def _edge(m, *, dx, width: int, p_ok, p_addr, p_ent, c_addr, c_ent) -> dict:
    """The boundary between pixels ``dx - 1`` and ``dx`` (:func:`aj_boundary`'s arguments): whether
    an edge between two polygons is blended there (``use_a``: the left pixel's segment ends,
    ``use_b``: the right pixel's starts), which pixel (``right``: ``dx``, else ``dx - 1``), the
    edge's offset ``delta`` (Q.6) from that pixel's centre, ``|dy/dx|`` ``aq`` and ``steep``."""
    bg_c = Signal()
    bg_p = Signal()
    m.d.comb += [bg_c.eq(c_addr == NONE), bg_p.eq(p_addr == NONE)]
    poly_c = Signal(ADDR_BITS)
    poly_p = Signal(ADDR_BITS)
    m.d.comb += [poly_c.eq(Mux(bg_c, NONE, c_ent.poly)), poly_p.eq(Mux(bg_p, NONE, p_ent.poly))]
    cc0 = Signal(signed(XP_BITS))
    pc1 = Signal(signed(XP_BITS))
    m.d.comb += [cc0.eq((c_ent.xl + 31) >> X_FRAC), pc1.eq(((p_ent.xr + 31) >> X_FRAC) - 1)]
    starts = Signal()
    ends = Signal()
    m.d.comb += [starts.eq(~bg_c & (dx == Mux(cc0 < 0, 0, cc0))),
                 ends.eq(~bg_p & (dx - 1 == Mux(pc1 > width - 1, width - 1, pc1)))]
    edge = Signal()
    use_b = Signal()
    use_a = Signal()
    m.d.comb += [edge.eq(p_ok & (dx > 0) & (p_addr != c_addr) & (poly_p != poly_c)),
                 use_b.eq(edge & starts), use_a.eq(edge & ~starts & ends)]
    xe = Signal(WORD)
    esl = Signal(signed(WORD))
    qq = Signal(signed(WORD))
    m.d.comb += [xe.eq(Mux(use_b, c_ent.xl, p_ent.xr)), esl.eq(Mux(use_b, c_ent.sl, p_ent.sr)),
                 qq.eq(Mux(use_b, c_ent.ql, p_ent.qr))]
    right = Signal()              # the blended pixel is dx (else dx - 1)
    m.d.comb += right.eq((xe >> X_FRAC) >= dx)
    q = Signal(X_END_BITS)
    m.d.comb += q.eq(Mux(right, dx, dx - 1))
    delta = Signal(signed(20))
    m.d.comb += delta.eq(xe - ((q << X_FRAC) + (1 << (X_FRAC - 1))))
    steep = Signal()
    m.d.comb += steep.eq(Mux(esl < 0, -esl, esl) <= (1 << SLOPE_FRAC))
    aq = Signal(WORD + 1)
    m.d.comb += aq.eq(Mux(qq < 0, -qq, qq))
    return {"use_a": use_a, "use_b": use_b, "right": right, "q": q, "delta": delta, "steep": steep, "aq": aq}


def _fields(ib: int) -> tuple:
    """The pixel's (lsb, width) fields R, G, B, I (hue 3/3/3, intensity ``ib`` bits)."""
    return ((ib + 6, 3), (ib + 3, 3), (ib, 3), (0, ib))


def _clamp_alpha(m, araw, name: str = "alpha") -> Signal:
    one_a = 1 << ALPHA_BITS
    alpha = Signal(ALPHA_BITS + 1, name=name)
    m.d.comb += alpha.eq(Mux(araw < 0, 0, Mux(araw > one_a, one_a, araw)))
    return alpha


def aj_boundary(m, *, dx, width: int, ib: int, p_ok, p_pix, p_out, p_addr, p_ent, c_pix, c_addr, c_ent):
    """Combinational logic in ``m`` for the boundary between drained pixel ``dx - 1`` (``p_*``:
    its pixel before A.J., as it will be output, its ASB address and entry; ``p_ok``: there is
    one) and pixel ``dx`` (``c_*``). Returns ``(o_prev, o_cur)``: both pixels after this
    boundary's blend (unchanged where the boundary is not an edge between two polygons)."""
    pb = len(p_pix)
    e = _edge(m, dx=dx, width=width, p_ok=p_ok, p_addr=p_addr, p_ent=p_ent, c_addr=c_addr, c_ent=c_ent)
    use_a, use_b, right, delta, steep, aq = e["use_a"], e["use_b"], e["right"], e["delta"], e["steep"], e["aq"]
    araw = Signal(signed(40))
    m.d.comb += araw.eq(Mux(steep, (1 << (ALPHA_BITS - 1)) + (delta << (ALPHA_BITS - X_FRAC)),
                            (1 << (ALPHA_BITS - 1)) + ((delta * aq) >> (X_FRAC + SLOPE_FRAC - ALPHA_BITS))))
    one_a = 1 << ALPHA_BITS
    alpha = _clamp_alpha(m, araw)
    # eq. (5) per field (R, G, B, I), C = alpha C_L + (1 - alpha) C_R, Q0.8, rounded
    blend = Signal(pb)
    parts = []
    for lsb, w in _fields(ib):
        fl = p_pix[lsb:lsb + w]
        fr = c_pix[lsb:lsb + w]
        v = Signal(w, name=f"blend_{lsb}")
        m.d.comb += v.eq((alpha * fl + (one_a - alpha) * fr + (one_a >> 1)) >> ALPHA_BITS)
        parts.append((lsb, v))
    m.d.comb += blend.eq(sum((v << lsb) for lsb, v in parts))
    o_prev = Signal(pb)
    o_cur = Signal(pb)
    m.d.comb += [o_prev.eq(Mux((use_a | use_b) & ~right, blend, p_out)),
                 o_cur.eq(Mux((use_a | use_b) & right, blend, c_pix))]
    return o_prev, o_cur


#: operand width of the shared multiplier's inputs (``mul16.sm_mul``: magnitudes below 2**16)
MUL_IN = signed(WORD + 2)


def aj_boundary_shared(m, *, dx, width: int, ib: int, lo, hi, prod, p_ok, p_pix, p_out, p_addr, p_ent, c_pix,
                       c_addr, c_ent) -> dict:
    """:func:`aj_boundary` on the PXP's one multiplier (``--datapath paper``), one multiply a cycle.

    ``prod``: the shared multiplier's product of this cycle's operands ``a``, ``b`` (returned).
    A boundary that blends a pixel of the range ``[lo, hi)`` (``need``; a guard pixel is another
    PXP's and is not blended) takes, in the cycles the drain repeats its blend-and-offer step:
    for a shallow edge (``|dx/dy| > 1``) ``delta * |dy/dx|`` for alpha (clamped to 0..256 and
    kept), then per field R, G, B ``alpha * (C_L - C_R)`` (the blended field
    ``(256 C_R + alpha (C_L - C_R) + 128) >> 8``, equal to eq. (5)'s ``(alpha C_L + (256 - alpha) C_R
    + 128) >> 8``, kept), then the I field's multiply in the offer cycle itself: 5 multiplies and
    cycles, 4 for a steep edge (alpha = 1/2 + delta is a shift). Operands: ``|delta| <= 32``
    (the blended pixel holds the edge's end, ``docs/experts.md``), ``|dy/dx| <= 32768``,
    ``alpha <= 256``, ``|C_L - C_R| <= 127``. Returns ``o_prev``, ``o_cur`` (valid in the
    offer cycle), ``need``, ``a``, ``b``, ``last`` (this cycle offers: no blend, or its last
    multiply), ``step()`` (sync statements of a multiply cycle that is not the last) and ``done``
    (sync statements once the pixel is offered)."""
    pb = len(p_pix)
    e = _edge(m, dx=dx, width=width, p_ok=p_ok, p_addr=p_addr, p_ent=p_ent, c_addr=c_addr, c_ent=c_ent)
    use, right, q, delta, steep, aq = e["use_a"] | e["use_b"], e["right"], e["q"], e["delta"], e["steep"], e["aq"]
    need = Signal(name="aj_need")
    m.d.comb += need.eq(use & (q >= lo) & (q < hi))
    bk = Signal(3, name="aj_bk")          # the next multiply of this pixel's blend (0: alpha)
    ph = Signal(3, name="aj_ph")
    m.d.comb += ph.eq(Mux((bk == 0) & steep, 1, bk))
    alpha_r = Signal(ALPHA_BITS + 1, name="alpha_r")
    alpha_s = _clamp_alpha(m, (1 << (ALPHA_BITS - 1)) + (delta << (ALPHA_BITS - X_FRAC)), "alpha_s")
    alpha_p = _clamp_alpha(m, (1 << (ALPHA_BITS - 1)) + (prod >> (X_FRAC + SLOPE_FRAC - ALPHA_BITS)), "alpha_p")
    alpha = Signal(ALPHA_BITS + 1, name="alpha_m")
    m.d.comb += alpha.eq(Mux(steep, alpha_s, alpha_r))
    a, b = Signal(MUL_IN, name="aj_mul_a"), Signal(MUL_IN, name="aj_mul_b")
    blend_r = Signal(pb, name="blend_r")   # R, G, B kept; its I bits stay 0
    blend = Signal(pb, name="blend_m")
    one_h = 1 << (ALPHA_BITS - 1)
    vals = []
    for lsb, w in _fields(ib):
        v = Signal(w, name=f"blend_{lsb}")
        m.d.comb += v.eq(((c_pix[lsb:lsb + w] << ALPHA_BITS) + prod + one_h) >> ALPHA_BITS)
        vals.append((lsb, w, v))
    with m.Switch(ph):
        with m.Case(0):
            m.d.comb += [a.eq(delta), b.eq(aq)]
        for k, (lsb, w, _) in enumerate(vals, start=1):
            with m.Case(k):
                m.d.comb += [a.eq(alpha), b.eq(p_pix[lsb:lsb + w] - c_pix[lsb:lsb + w])]
    lsb_i, w_i, v_i = vals[-1]
    m.d.comb += blend.eq(blend_r | (v_i << lsb_i))      # the I field from this (last) cycle's multiply
    last = Signal(name="aj_last")
    m.d.comb += last.eq(~need | (ph == len(vals)))

    def step():
        with m.If(ph == 0):
            m.d.sync += alpha_r.eq(alpha_p)
        for k, (lsb, w, v) in enumerate(vals[:-1], start=1):
            with m.If(ph == k):
                m.d.sync += blend_r[lsb:lsb + w].eq(v)
        m.d.sync += bk.eq(ph + 1)

    o_prev = Signal(pb)
    o_cur = Signal(pb)
    m.d.comb += [o_prev.eq(Mux(need & ~right, blend, p_out)), o_cur.eq(Mux(need & right, blend, c_pix))]
    return {"o_prev": o_prev, "o_cur": o_cur, "need": need, "a": a, "b": b, "last": last, "step": step,
            "done": [bk.eq(0)]}
