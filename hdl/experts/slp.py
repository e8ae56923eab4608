"""EXPERTS scan line processor (SLP): Y-sort, ASL update, L-sort, X-merge, block lists, the ASBs for the DMM/P.

Paper (seed 000, section 4): the SLP "すべての稜線を、y_min ... をキーとしてバケットソートする" (Y-sort),
per line "1スキャン・ライン内に現われるセグメントを、その左稜線のxs座標値をキーとして、マージソートする"
(X-merge) and "進入、退出するセグメントと ... リストとをバブルソートする" (L-sort), updates the ASL and
builds the block boundary bucket list and block leading segment pointer for its PXPs (section 3).

One band at a time, as ``golden_model/experts/slp_run.py`` runs it (the rules are there):

* **Y-sort**: PL triangle words (PL order), one a cycle: band test on the first / last line, linked
  at the tail of the bucket of its first line in the band (head, tail, count per line, a next
  pointer per triangle); its set-up (the three edges' start points and reciprocal-ROM increments)
  is stored by PL index.
* per line: **leave test + ASL update**, one cycle per segment of the previous ASL: it leaves after
  its last line, or stays and gets its new x_L, x_R (the edge accumulators of ``slp.py``: one
  multiply per edge, ``((x0 << 16) + ((yc - y0) inc >> 6)) >> 16``); **L-sort**: bubble sort of the
  survivors on (x_L, PL index), whole passes until one exchanges nothing, one compare a cycle with
  the larger element carried in a register, one cycle to close each pass; **X-merge**: the line's
  bucket walked (ASL update of each entering segment), merge-sorted bottom up (one move a cycle, one
  cycle to set up a level), then merged into the survivors (one move a cycle; survivors first on
  equal keys, as ``slp_run.merge``);
* **block lists**: one walk of the new ASL: its ASL word (the whole ASB: x_L, x_R, and z_L, i_L
  from the left edge's accumulators, the line's edge slopes, the set-up values), then the leading
  pointer of every range
  whose start it is the first to reach and its entry in the bucket list of every later range it
  reaches (``slp_run.block_lists``; ranges widened by ``guard`` pixels each side), one cycle per
  test; then the end-of-line word.

Input (``i``, :func:`slp_in_layout`): a ``BAND`` word (``r0`` = first line, ``r1`` = end line), the
``P + 1`` range bounds (``BOUND``, in ``xa``), the PL triangles (``TRI``), then ``GO``.
Output (``o``, :func:`slp_out_layout`): per line the ASL words (``pos``, ``t``) with the lead and
bucket words (range ``p``, ``pos``, ``t``) as the walk finds them, then ``EOL`` (``y``).
Cycles: ``golden_model/experts/slp_cycles.py`` (every term named there).
"""

from __future__ import annotations

from contextlib import contextmanager

from amaranth import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import (
    ACC_EXTRA,
    ADDR_BITS,
    INC_BITS,
    RGB_BITS,
    WORD,
    X_END_BITS,
    X_FRAC,
    X_INT,
    XD_BITS,
    XP_BITS,
    XS_BITS,
    Z_BITS,
)
from rasterhw.hdl.experts.mul16 import sm_mul

__all__ = ["ExpertsSlp", "slp_in_layout", "slp_out_layout", "IN_KIND", "MUL_OPS"]

IN_KIND = {"band": 0, "bound": 1, "tri": 2, "go": 3}
#: (the paper's datapath) what the one multiplier computes, by ``msel``
MUL_OPS = {"x_long": 0, "x_short": 1, "z_left": 2, "i_left": 3}


def slp_in_layout() -> data.StructLayout:
    return data.StructLayout({
        "kind": unsigned(2),
        "t": unsigned(ADDR_BITS),      # PL index
        "r0": unsigned(X_INT),         # first line (BAND: band start)
        "r1": unsigned(X_INT),         # last line (BAND: band end, exclusive)
        "ll": unsigned(1),             # the long edge a->c is the left edge
        "xa": signed(XS_BITS),         # vertex a: the unsigned Q10.6 of formats.py, signed (BOUND: the bound, pixels)
        "ya": signed(XS_BITS),
        "xb": signed(XS_BITS),         # vertex b
        "yb": signed(XS_BITS),
        "inc_ac": signed(INC_BITS),    # edge increments per line, Q.22 (slp.rom_div)
        "inc_ab": signed(INC_BITS),
        "inc_bc": signed(INC_BITS),
        "za": unsigned(Z_BITS),        # z at a and b, Q16.0, and the edges' z increments
        "zb": unsigned(Z_BITS),
        "zinc_ac": signed(INC_BITS),
        "zinc_ab": signed(INC_BITS),
        "zinc_bc": signed(INC_BITS),
        "ia": unsigned(WORD),          # intensity at a and b, and the edges' increments
        "ib": unsigned(WORD),
        "iinc_ac": signed(INC_BITS),
        "iinc_ab": signed(INC_BITS),
        "iinc_bc": signed(INC_BITS),
        "dzdx": signed(WORD),          # eq. (3), passed into the ASB
        "didx": signed(WORD),
        "hue": unsigned(RGB_BITS),
        "poly": unsigned(ADDR_BITS),
        "s_ac": signed(WORD),          # A.J.: each edge's dx/dy and dy/dx, sQ7.8
        "s_ab": signed(WORD),
        "s_bc": signed(WORD),
        "q_ac": signed(WORD),
        "q_ab": signed(WORD),
        "q_bc": signed(WORD),
    })


def slp_out_layout() -> data.StructLayout:
    from rasterhw.hdl.experts.pxp_span import asb_layout
    return data.StructLayout({
        "kind": unsigned(2),           # 0 ASL word, 1 leading pointer, 2 bucket entry, 3 end of line
        "p": unsigned(6),              # range
        "pos": unsigned(9),            # ASL position
        "t": unsigned(ADDR_BITS),
        "y": unsigned(X_INT),
        "asb": asb_layout(),           # ASL word: the ASB as it goes into the DMM/P
    })


class _S(enum.Enum, shape=5):
    IN = 0        # take input words (band, bounds, PL triangles, go)
    CLEAR = 1     # clear the buckets of the band
    LSTART = 2
    LEAVE = 3
    BINIT = 4
    BSTEP = 5
    BEND = 6
    ESTART = 7
    EWALK = 8
    MLEVEL = 9
    MMOVE = 10
    FSETUP = 11
    FMOVE = 12
    WSEG = 13
    WQ = 14
    WK = 15
    EOL = 16


class ExpertsSlp(wiring.Component):
    """One SLP's list work over one band: PL in, per line the ASL and its block lists out.

    Parameters
    ----------
    width : int
        Frame width (1..1024).
    tris : int
        PL triangles it can hold (2..4095).
    lines : int
        Band lines it can hold (1..1024).
    asl : int
        Segments an ASL may hold (2..511).
    guard : int
        Pixels each side of a range its block lists cover (1 with A.J. (c)).
    acc_extra : int
        Fraction bits of the edge accumulators beyond the 16-bit word (``formats.Datapath.acc_extra``):
        16 (ours, the default) or 0 (the paper's 16-bit datapath).

    Members
    -------
    i : In(stream.Signature(slp_in_layout()))
    o : Out(stream.Signature(slp_out_layout()))
    line_cycles : Out(16)   cycles of the last line (start to its end-of-line word)
    overflow : Out(1)       sticky: a line's ASL was longer than ``asl`` (its lists are then wrong; the
                            golden side refuses such a band, so a run that sets it is a failed run)
    """

    def __init__(self, *, width: int = 512, tris: int = 4095, lines: int = 512, asl: int = 256, guard: int = 1,
                 acc_extra: int = ACC_EXTRA):
        for name, v, lo, hi in (("width", width, 1, 1024), ("tris", tris, 2, 4095), ("lines", lines, 1, 1024),
                                ("asl", asl, 2, 511), ("guard", guard, 0, 1)):
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise ValueError(f"{name} must be an integer in {lo}..{hi}, not {v!r}")
        if acc_extra not in (0, ACC_EXTRA) or isinstance(acc_extra, bool):
            raise ValueError(f"acc_extra must be 0 or {ACC_EXTRA}, not {acc_extra!r}")
        self._w, self._tris, self._lines, self._asl, self._guard = width, tris, lines, asl, guard
        self._ex = acc_extra
        super().__init__({
            "i": In(stream.Signature(slp_in_layout())),
            "o": Out(stream.Signature(slp_out_layout())),
            "line_cycles": Out(16),
            "overflow": Out(1),
        })

    def _multipliers(self, m, tv, yc, xs):
        """Ours: x of the three edges, z and i of the left edge, each with its own multiplier, in
        the cycle that needs them. Returns x_L/x_R (``xs``), z_L and i_L."""
        def edge(x0, yy0, inc, name):
            v = Signal(signed(80), name=name)
            m.d.comb += v.eq(((x0 << self._ex) + (((yc - yy0) * inc) >> X_FRAC)) >> self._ex)
            return v
        lng = edge(tv.xa, tv.ya, tv.inc_ac, "x_long")
        sht = Signal(signed(80))
        up = edge(tv.xa, tv.ya, tv.inc_ab, "x_ab")
        lo_ = edge(tv.xb, tv.yb, tv.inc_bc, "x_bc")
        m.d.comb += sht.eq(Mux(yc < tv.yb, up, lo_))
        newx = Signal(xs)
        m.d.comb += [newx.xl.eq(Mux(tv.ll, lng, sht)), newx.xr.eq(Mux(tv.ll, sht, lng))]

        # the rest of the ASL update, for the ASB written at the walk: z_L, i_L of the left edge
        # (two multiplies each, the edge chosen as for x)
        def left(a_a, a_b, i_ac, i_ab, i_bc, name):
            lg = edge(a_a, tv.ya, i_ac, f"{name}_long")
            sh = Mux(yc < tv.yb, edge(a_a, tv.ya, i_ab, f"{name}_ab"), edge(a_b, tv.yb, i_bc, f"{name}_bc"))
            v = Signal(signed(80), name=f"{name}_left")
            m.d.comb += v.eq(Mux(tv.ll, lg, sh))
            return v
        return (newx, left(tv.za, tv.zb, tv.zinc_ac, tv.zinc_ab, tv.zinc_bc, "z"),
                left(tv.ia, tv.ib, tv.iinc_ac, tv.iinc_ab, tv.iinc_bc, "i"))

    @staticmethod
    @contextmanager
    def _first_multiply(m, mul, ph, first, op0="x_long", op1="x_short", hold=False):
        """The paper's datapath (``mul`` not empty): while ``first``, a cycle that only multiplies
        (``op0``, kept in ``xlong`` or, for ``z_left``, ``zreg``); then the step's own cycle, with
        ``op1`` on the multiplier, which resets the phase (``hold``: the step resets it itself, when
        its word is taken). Ours: the step alone."""
        if not mul:
            yield
            return
        m.d.comb += mul["msel"].eq(Mux(ph, MUL_OPS[op1], MUL_OPS[op0]))
        with m.If(first):
            keep = mul["zreg"] if op0 == "z_left" else mul["xlong"]
            m.d.sync += [keep.eq(mul["res"]), ph.eq(1)]
        with m.Else():
            if not hold:
                m.d.sync += ph.eq(0)
            yield

    @staticmethod
    def _one_multiplier(m, tv, yc, xs):
        """The paper's datapath: one 16 x 16 unsigned multiplier, its operands chosen by ``msel``
        (:data:`MUL_OPS`), ``res = a0 + ((yc - y0) * inc >> 6)`` in the cycle it is chosen (the
        edge accumulator's start value, :func:`slp_cycles._acc` with no extra bits). ``yc - y0`` is
        0..65504 (``y0`` is the edge's upper vertex, at or above the line's centre) and the
        increment a saturated 16-bit word (:func:`mul16.sm_mul`, sign and magnitude). The
        FSM keeps x of the long edge in ``xlong`` (first cycle) and z_L in ``zreg``."""
        msel = Signal(2)
        upper = Signal()
        a0, y0_ = Signal(signed(XD_BITS)), Signal(signed(XD_BITS))
        inc = Signal(signed(WORD))
        m.d.comb += upper.eq(yc < tv.yb)

        def pick(a_a, a_b, i_ac, i_ab, i_bc, lng):
            """operands of the long edge (``lng``), else of the short edge on this line."""
            m.d.comb += [a0.eq(Mux(lng | upper, a_a, a_b)), y0_.eq(Mux(lng | upper, tv.ya, tv.yb)),
                         inc.eq(Mux(lng, i_ac[:WORD], Mux(upper, i_ab[:WORD], i_bc[:WORD])).as_signed())]
        with m.Switch(msel):
            with m.Case(MUL_OPS["x_long"]):
                pick(tv.xa, tv.xb, tv.inc_ac, tv.inc_ab, tv.inc_bc, 1)
            with m.Case(MUL_OPS["x_short"]):
                pick(tv.xa, tv.xb, tv.inc_ac, tv.inc_ab, tv.inc_bc, 0)
            with m.Case(MUL_OPS["z_left"]):
                pick(tv.za, tv.zb, tv.zinc_ac, tv.zinc_ab, tv.zinc_bc, tv.ll)
            with m.Case(MUL_OPS["i_left"]):
                pick(tv.ia, tv.ib, tv.iinc_ac, tv.iinc_ab, tv.iinc_bc, tv.ll)
        dy = Signal(WORD)
        res = Signal(signed(36))
        m.d.comb += [dy.eq(yc - y0_), res.eq(a0 + (sm_mul(m, dy, inc, "slp_mul") >> X_FRAC))]
        xlong = Signal(signed(XD_BITS))
        zreg = Signal(Z_BITS)
        newx = Signal(xs)
        m.d.comb += [newx.xl.eq(Mux(tv.ll, xlong, res)), newx.xr.eq(Mux(tv.ll, res, xlong))]
        return {"msel": msel, "res": res, "xlong": xlong, "zreg": zreg, "newx": newx}

    def elaborate(self, platform):
        m = Module()
        W, G = self._w, self._guard
        tl = data.StructLayout({k: v for k, v in slp_in_layout().members.items() if k not in ("kind", "t", "r0")})
        tb = ADDR_BITS
        lb = max((self._lines - 1).bit_length(), 1)
        ab = max((self._asl - 1).bit_length(), 1)
        cw = ab + 1
        xs = data.StructLayout({"xl": signed(XD_BITS), "xr": signed(XD_BITS)})

        def mem(name, shape, depth, reads):
            mm = Memory(shape=shape, depth=depth, init=[])
            m.submodules[name] = mm
            w = mm.write_port()
            m.d.comb += w.en.eq(0)
            return w, [mm.read_port(domain="comb") for _ in range(reads)]

        ttw, (ttr,) = mem("tt", tl, self._tris, 1)
        hdw, (hdr,) = mem("bhead", unsigned(tb), self._lines, 1)
        tlw, (tlr,) = mem("btail", unsigned(tb), self._lines, 1)
        cnw, (cnr,) = mem("bcnt", unsigned(tb + 1), self._lines, 1)
        nxw, (nxr,) = mem("bnext", unsigned(tb), self._tris, 1)
        kyw, (ky0, ky1) = mem("keys", xs, self._tris, 2)
        aw, (ar,) = mem("A", unsigned(tb), self._asl, 1)
        bw, (br,) = mem("B", unsigned(tb), self._asl, 1)
        ew, (er0, er1) = mem("E", unsigned(tb), self._asl, 2)
        fw, (fr0, fr1) = mem("F", unsigned(tb), self._asl, 2)
        ndw, (nd0, nd1) = mem("bnd", unsigned(X_END_BITS), 64, 2)

        state = Signal(_S)
        y0 = Signal(X_INT)
        y1 = Signal(X_INT)
        y = Signal(X_INT)
        nb = Signal(7)           # bounds taken (P + 1)
        clr = Signal(lb + 1)
        m_ = Signal(cw)          # previous ASL length
        ns = Signal(cw)          # survivors
        ne = Signal(cw)          # entering
        i = Signal(cw)
        node = Signal(tb)
        cur = Signal(tb)         # bubble: the carried element
        swapped = Signal()
        wdt = Signal(cw + 1)     # merge sort: run width
        src_f = Signal()         # merge sort: the sorted runs are in F (else E)
        li, le, ri, re, o = (Signal(cw + 1, name=n) for n in ("li", "le", "ri", "re", "o"))
        s0 = Signal(cw + 1)      # merge sort: start of the pair being merged
        q = Signal(7)
        k = Signal(7)
        pos = Signal(cw)
        cyc = Signal(16)
        P = Signal(7)
        m.d.comb += P.eq(nb - 1)
        m.d.sync += cyc.eq(cyc + 1)

        p = self.i.payload
        o_ = self.o.payload
        m.d.comb += [self.i.ready.eq(0), self.o.valid.eq(0)]

        # ASL update: x_L, x_R of triangle ``tt`` entry on line y (one multiply per edge)
        yc = Signal(signed(XD_BITS))
        m.d.comb += yc.eq((y << X_FRAC) + (1 << (X_FRAC - 1)))
        tv = Signal(tl)
        m.d.comb += tv.eq(ttr.data)

        one = self._ex == 0      # the paper's datapath: one 16 x 16 multiplier, shared in time
        ph = Signal()            # (paper) the multiply phase of a segment's ASL update and ASL word
        mul: dict = {}
        if one:
            mul = self._one_multiplier(m, tv, yc, xs)
            newx, zl_, il_ = mul["newx"], mul["zreg"], mul["res"]
        else:
            newx, zl_, il_ = self._multipliers(m, tv, yc, xs)
        s_sh, q_sh = Signal(signed(WORD)), Signal(signed(WORD))
        m.d.comb += [s_sh.eq(Mux(yc < tv.yb, tv.s_ab, tv.s_bc)), q_sh.eq(Mux(yc < tv.yb, tv.q_ab, tv.q_bc))]

        def less(ka, ta, kb, tb_):
            """(x_L, PL index) of a before b."""
            return (ka.xl < kb.xl) | ((ka.xl == kb.xl) & (ta < tb_))

        # ---------------------------------------------------------------- input: band, bounds, PL
        bidx = Signal(lb + 1)
        m.d.comb += bidx.eq(Mux(p.r0 > y0, p.r0, y0) - y0)
        with m.Switch(state):
            with m.Case(_S.IN):
                m.d.comb += self.i.ready.eq(1)
                with m.If(self.i.valid):
                    with m.Switch(p.kind):
                        with m.Case(IN_KIND["band"]):
                            m.d.sync += [y0.eq(p.r0), y1.eq(p.r1), nb.eq(0), clr.eq(0), state.eq(_S.CLEAR)]
                        with m.Case(IN_KIND["bound"]):
                            m.d.comb += [ndw.addr.eq(nb), ndw.data.eq(p.xa), ndw.en.eq(1)]
                            m.d.sync += nb.eq(nb + 1)
                        with m.Case(IN_KIND["tri"]):
                            m.d.comb += [ttw.addr.eq(p.t), ttw.en.eq(1)]
                            for f in tl.members:
                                m.d.comb += getattr(ttw.data, f).eq(getattr(p, f))
                            with m.If((p.r1 >= y0) & (p.r0 < y1)):
                                # Y-sort: link at the tail of the bucket of its first line in the band
                                m.d.comb += [cnr.addr.eq(bidx), tlr.addr.eq(bidx),
                                             cnw.addr.eq(bidx), cnw.data.eq(cnr.data + 1), cnw.en.eq(1),
                                             tlw.addr.eq(bidx), tlw.data.eq(p.t), tlw.en.eq(1)]
                                with m.If(cnr.data == 0):
                                    m.d.comb += [hdw.addr.eq(bidx), hdw.data.eq(p.t), hdw.en.eq(1)]
                                with m.Else():
                                    m.d.comb += [nxw.addr.eq(tlr.data), nxw.data.eq(p.t), nxw.en.eq(1)]
                        with m.Case(IN_KIND["go"]):
                            m.d.sync += [y.eq(y0), m_.eq(0), state.eq(_S.LSTART)]
            with m.Case(_S.CLEAR):
                m.d.comb += [cnw.addr.eq(clr), cnw.data.eq(0), cnw.en.eq(1)]
                m.d.sync += clr.eq(clr + 1)
                with m.If(clr + 1 >= y1 - y0):
                    m.d.sync += state.eq(_S.IN)

            # ------------------------------------------------------------ per line
            with m.Case(_S.LSTART):
                m.d.sync += [cyc.eq(1), i.eq(0), ns.eq(0), ne.eq(0), q.eq(0), pos.eq(0),
                             state.eq(Mux(m_ == 0, _S.ESTART, _S.LEAVE))]
            with m.Case(_S.LEAVE):
                # leave test + ASL update of the previous ASL's segment i
                m.d.comb += [ar.addr.eq(i), ttr.addr.eq(ar.data)]
                with self._first_multiply(m, mul, ph, (tv.r1 >= y) & ~ph):
                    with m.If(tv.r1 >= y):
                        m.d.comb += [bw.addr.eq(ns), bw.data.eq(ar.data), bw.en.eq(1),
                                     kyw.addr.eq(ar.data), kyw.data.eq(newx), kyw.en.eq(1)]
                        m.d.sync += ns.eq(ns + 1)
                    m.d.sync += i.eq(i + 1)
                    with m.If(i + 1 >= m_):
                        nsn = ns + (tv.r1 >= y)
                        m.d.sync += state.eq(Mux(nsn >= 2, _S.BINIT, _S.ESTART))
            with m.Case(_S.BINIT):
                m.d.comb += br.addr.eq(0)
                m.d.sync += [cur.eq(br.data), i.eq(0), swapped.eq(0), state.eq(_S.BSTEP)]
            with m.Case(_S.BSTEP):
                # compare B[i+1] with the carried element; the smaller is written at i
                m.d.comb += [br.addr.eq(i + 1), ky0.addr.eq(br.data), ky1.addr.eq(cur), bw.addr.eq(i), bw.en.eq(1)]
                kn, kc = Signal(xs), Signal(xs)
                m.d.comb += [kn.eq(ky0.data), kc.eq(ky1.data)]
                with m.If(less(kn, br.data, kc, cur)):
                    m.d.comb += bw.data.eq(br.data)
                    m.d.sync += swapped.eq(1)
                with m.Else():
                    m.d.comb += bw.data.eq(cur)
                    m.d.sync += cur.eq(br.data)
                m.d.sync += i.eq(i + 1)
                with m.If(i + 2 >= ns):
                    m.d.sync += state.eq(_S.BEND)
            with m.Case(_S.BEND):
                m.d.comb += [bw.addr.eq(ns - 1), bw.data.eq(cur), bw.en.eq(1)]
                m.d.sync += state.eq(Mux(swapped, _S.BINIT, _S.ESTART))
            with m.Case(_S.ESTART):
                m.d.comb += [cnr.addr.eq(y - y0), hdr.addr.eq(y - y0)]
                m.d.sync += [node.eq(hdr.data), ne.eq(cnr.data), i.eq(0),
                             state.eq(Mux(cnr.data == 0, _S.FSETUP, _S.EWALK))]
            with m.Case(_S.EWALK):
                # the line's bucket: ASL update of each entering segment, into E
                m.d.comb += [ttr.addr.eq(node), nxr.addr.eq(node)]
                with self._first_multiply(m, mul, ph, ~ph):
                    m.d.comb += [ew.addr.eq(i), ew.data.eq(node), ew.en.eq(1),
                                 kyw.addr.eq(node), kyw.data.eq(newx), kyw.en.eq(1)]
                    m.d.sync += [node.eq(nxr.data), i.eq(i + 1)]
                    with m.If(i + 1 >= ne):
                        m.d.sync += [wdt.eq(1), src_f.eq(0), state.eq(Mux(ne >= 2, _S.MLEVEL, _S.FSETUP))]
            with m.Case(_S.MLEVEL):
                m.d.sync += [s0.eq(0), li.eq(0), le.eq(Mux(wdt < ne, wdt, ne)), ri.eq(Mux(wdt < ne, wdt, ne)),
                             re.eq(Mux(2 * wdt < ne, 2 * wdt, ne)), o.eq(0), state.eq(_S.MMOVE)]
            with m.Case(_S.MMOVE):
                # merge the pair [li, le) + [ri, re) of the source into the destination
                ta, tb_ = Signal(tb), Signal(tb)
                m.d.comb += [er0.addr.eq(li), er1.addr.eq(ri), fr0.addr.eq(li), fr1.addr.eq(ri),
                             ta.eq(Mux(src_f, fr0.data, er0.data)), tb_.eq(Mux(src_f, fr1.data, er1.data)),
                             ky0.addr.eq(ta), ky1.addr.eq(tb_)]
                take_r = Signal()
                m.d.comb += take_r.eq((li >= le) | ((ri < re) & less(ky1.data, tb_, ky0.data, ta)))
                val = Mux(take_r, tb_, ta)
                with m.If(src_f):
                    m.d.comb += [ew.addr.eq(o), ew.data.eq(val), ew.en.eq(1)]
                with m.Else():
                    m.d.comb += [fw.addr.eq(o), fw.data.eq(val), fw.en.eq(1)]
                nli = Mux(take_r, li, li + 1)
                nri = Mux(take_r, ri + 1, ri)
                m.d.sync += [li.eq(nli), ri.eq(nri), o.eq(o + 1)]
                with m.If((nli >= le) & (nri >= re)):
                    ns0 = s0 + 2 * wdt
                    m.d.sync += [s0.eq(ns0), li.eq(ns0), le.eq(Mux(ns0 + wdt < ne, ns0 + wdt, ne)),
                                 ri.eq(Mux(ns0 + wdt < ne, ns0 + wdt, ne)),
                                 re.eq(Mux(ns0 + 2 * wdt < ne, ns0 + 2 * wdt, ne))]
                with m.If(o + 1 >= ne):
                    m.d.sync += [wdt.eq(2 * wdt), src_f.eq(~src_f),
                                 state.eq(Mux(2 * wdt < ne, _S.MLEVEL, _S.FSETUP))]
            with m.Case(_S.FSETUP):
                m.d.sync += [li.eq(0), le.eq(ns), ri.eq(0), re.eq(ne), o.eq(0), m_.eq(ns + ne),
                             state.eq(Mux(ns + ne == 0, _S.EOL, _S.FMOVE))]
                with m.If(ns + ne > self._asl):
                    m.d.sync += self.overflow.eq(1)
            with m.Case(_S.FMOVE):
                # survivors (B) and entering (E or F) into the new ASL (A), survivors first on ties
                ta, tb_ = Signal(tb), Signal(tb)
                m.d.comb += [br.addr.eq(li), er1.addr.eq(ri), fr1.addr.eq(ri),
                             ta.eq(br.data), tb_.eq(Mux(src_f, fr1.data, er1.data)),
                             ky0.addr.eq(ta), ky1.addr.eq(tb_)]
                take_r = Signal()
                m.d.comb += take_r.eq((li >= le) | ((ri < re) & less(ky1.data, tb_, ky0.data, ta)))
                m.d.comb += [aw.addr.eq(o), aw.data.eq(Mux(take_r, tb_, ta)), aw.en.eq(1)]
                m.d.sync += [li.eq(Mux(take_r, li, li + 1)), ri.eq(Mux(take_r, ri + 1, ri)), o.eq(o + 1)]
                with m.If(o + 1 >= ns + ne):
                    m.d.sync += [m_.eq(ns + ne), pos.eq(0), state.eq(_S.WSEG)]

            # ------------------------------------------------------------ block lists
            with m.Case(_S.WSEG):
                m.d.comb += [ar.addr.eq(pos), ky0.addr.eq(ar.data), ttr.addr.eq(ar.data)]
                # (paper) z_L first, then i_L as the word goes out
                with self._first_multiply(m, mul, ph, ~ph, "z_left", "i_left", hold=True):
                    m.d.comb += [self.o.valid.eq(1), o_.kind.eq(0), o_.pos.eq(pos), o_.t.eq(ar.data), o_.y.eq(y),
                                 o_.asb.xl.eq(ky0.data.xl), o_.asb.xr.eq(ky0.data.xr), o_.asb.zl.eq(zl_),
                                 o_.asb.il.eq(il_), o_.asb.dzdx.eq(tv.dzdx), o_.asb.didx.eq(tv.didx),
                                 o_.asb.hue.eq(tv.hue), o_.asb.addr.eq(ar.data), o_.asb.poly.eq(tv.poly),
                                 o_.asb.sl.eq(Mux(tv.ll, tv.s_ac, s_sh)), o_.asb.ql.eq(Mux(tv.ll, tv.q_ac, q_sh)),
                                 o_.asb.sr.eq(Mux(tv.ll, s_sh, tv.s_ac)), o_.asb.qr.eq(Mux(tv.ll, q_sh, tv.q_ac))]
                    c0, c1 = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                    m.d.comb += [c0.eq((ky0.data.xl + 31) >> X_FRAC), c1.eq(((ky0.data.xr + 31) >> X_FRAC) - 1)]
                    with m.If(self.o.ready):
                        if mul:
                            m.d.sync += ph.eq(0)
                        a_ = Mux(c0 < 0, 0, c0)
                        e_ = Mux(c1 > W - 1, W - 1, c1)
                        with m.If(e_ < a_):
                            m.d.sync += pos.eq(pos + 1)
                            with m.If(pos + 1 >= m_):
                                m.d.sync += state.eq(_S.EOL)
                        with m.Else():
                            m.d.sync += state.eq(_S.WQ)
            with m.Case(_S.WQ, _S.WK):
                m.d.comb += [ar.addr.eq(pos), ky0.addr.eq(ar.data)]
                c0, c1 = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                m.d.comb += [c0.eq((ky0.data.xl + 31) >> X_FRAC), c1.eq(((ky0.data.xr + 31) >> X_FRAC) - 1)]
                a_, e_ = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                m.d.comb += [a_.eq(Mux(c0 < 0, 0, c0)), e_.eq(Mux(c1 > W - 1, W - 1, c1))]
                r = Signal(7)
                m.d.comb += [r.eq(Mux(state == _S.WQ, q, k)), nd0.addr.eq(r), nd1.addr.eq(r + 1)]
                glo, ghi = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                m.d.comb += [glo.eq(Mux(nd0.data >= G, nd0.data - G, 0)),
                             ghi.eq(Mux(nd1.data + G <= W, nd1.data + G, W))]
                live = (ghi > glo) & (nd1.data > nd0.data)
                m.d.comb += [o_.p.eq(r), o_.pos.eq(pos), o_.t.eq(ar.data), o_.y.eq(y)]
                with m.If(state == _S.WQ):
                    with m.If((q < P) & (a_ >= glo)):
                        emit = live & (a_ < ghi)
                        m.d.comb += [self.o.valid.eq(emit), o_.kind.eq(1)]
                        with m.If(~emit | self.o.ready):
                            m.d.sync += q.eq(q + 1)
                    with m.Else():
                        m.d.sync += [k.eq(q), state.eq(_S.WK)]
                with m.Else():
                    with m.If((k < P) & (glo <= e_)):
                        m.d.comb += [self.o.valid.eq(live), o_.kind.eq(2)]
                        with m.If(~live | self.o.ready):
                            m.d.sync += k.eq(k + 1)
                    with m.Else():
                        m.d.sync += [pos.eq(pos + 1), state.eq(Mux(pos + 1 >= m_, _S.EOL, _S.WSEG))]
            with m.Case(_S.EOL):
                m.d.comb += [self.o.valid.eq(1), o_.kind.eq(3), o_.y.eq(y)]
                with m.If(self.o.ready):
                    m.d.sync += [self.line_cycles.eq(cyc + 1), y.eq(y + 1),
                                 state.eq(Mux(y + 1 >= y1, _S.IN, _S.LSTART))]
        return m
