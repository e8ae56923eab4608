"""A.J. (c) at a segment boundary in the PXP's drain, shared by both PXPs (``pxp.py``, the line
Z-buffer; ``pxp_span.py`` and ``pxp_coherent.py``, the span PXPs): the paper's anti-jagging blends the two pixels at
a boundary between two polygons by the covered fraction alpha of the edge that crosses it
(eq. (5), C = alpha C_L + (1 - alpha) C_R per R, G, B, I field, Q0.8, rounded), alpha from the
edge's end x and slope (``golden_model/experts/alpha.py`` is the golden side)."""

from __future__ import annotations

from amaranth import Mux, Signal, signed
from rasterhw.golden_model.experts.formats import ADDR_BITS, ALPHA_BITS, SLOPE_FRAC, X_FRAC

__all__ = ["aj_boundary"]

NONE = (1 << ADDR_BITS) - 1     # ASB address / polygon number of the background


def aj_boundary(m, *, dx, width: int, ib: int, p_ok, p_pix, p_out, p_addr, p_ent, c_pix, c_addr, c_ent):
    """Combinational logic in ``m`` for the boundary between drained pixel ``dx - 1`` (``p_*``:
    its pixel before A.J., as it will be output, its ASB address and entry; ``p_ok``: there is
    one) and pixel ``dx`` (``c_*``). Returns ``(o_prev, o_cur)``: both pixels after this
    boundary's blend (unchanged where the boundary is not an edge between two polygons)."""
    pb = len(p_pix)
    bg_c = Signal()
    bg_p = Signal()
    m.d.comb += [bg_c.eq(c_addr == NONE), bg_p.eq(p_addr == NONE)]
    poly_c = Signal(ADDR_BITS)
    poly_p = Signal(ADDR_BITS)
    m.d.comb += [poly_c.eq(Mux(bg_c, NONE, c_ent.poly)), poly_p.eq(Mux(bg_p, NONE, p_ent.poly))]
    cc0 = Signal(signed(12))
    pc1 = Signal(signed(12))
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
    xe = Signal(16)
    esl = Signal(signed(16))
    qq = Signal(signed(16))
    m.d.comb += [xe.eq(Mux(use_b, c_ent.xl, p_ent.xr)), esl.eq(Mux(use_b, c_ent.sl, p_ent.sr)),
                 qq.eq(Mux(use_b, c_ent.ql, p_ent.qr))]
    right = Signal()              # the blended pixel is dx (else dx - 1)
    m.d.comb += right.eq((xe >> X_FRAC) >= dx)
    q = Signal(11)
    m.d.comb += q.eq(Mux(right, dx, dx - 1))
    delta = Signal(signed(20))
    m.d.comb += delta.eq(xe - ((q << X_FRAC) + (1 << (X_FRAC - 1))))
    steep = Signal()
    m.d.comb += steep.eq(Mux(esl < 0, -esl, esl) <= (1 << SLOPE_FRAC))
    aq = Signal(17)
    m.d.comb += aq.eq(Mux(qq < 0, -qq, qq))
    araw = Signal(signed(40))
    m.d.comb += araw.eq(Mux(steep, (1 << (ALPHA_BITS - 1)) + (delta << (ALPHA_BITS - X_FRAC)),
                            (1 << (ALPHA_BITS - 1)) + ((delta * aq) >> (X_FRAC + SLOPE_FRAC - ALPHA_BITS))))
    one_a = 1 << ALPHA_BITS
    alpha = Signal(ALPHA_BITS + 1)
    m.d.comb += alpha.eq(Mux(araw < 0, 0, Mux(araw > one_a, one_a, araw)))
    # eq. (5) per field (R, G, B, I), C = alpha C_L + (1 - alpha) C_R, Q0.8, rounded
    blend = Signal(pb)
    parts = []
    for lsb, w in ((ib + 6, 3), (ib + 3, 3), (ib, 3), (0, ib)):
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
