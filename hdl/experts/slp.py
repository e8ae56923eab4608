"""EXPERTS scan line processor (SLP): Y-sort, ASL update, L-sort, X-merge, block lists, the ASBs for the DMM/P.

Paper (seed 000, section 4): the SLP "すべての稜線を、y_{min} ... をキーとしてバケットソートする" (Y-sort),
per line "1スキャン・ライン内に現われるセグメントを、その左稜線のxs座標値をキーとして、マージソートする"
(X-merge) and "進入、退出するセグメントと ... リストとをバブルソートする" (L-sort), updates the ASL and
builds the block boundary bucket list and block leading segment pointer for its PXPs (section 3).

**One processor, its steps in sequence.** The paper's SLP is one processor with an ALU, a
multiplier and a reciprocal ROM ("SLPには、加減算およびシフト演算を行なうALU ... の他に、乗算器、および
逆数表(ROMによる)を装備した", seed 000, 3.2) that runs the steps the paper names one after another:
their costs add up to one sum, ``Q_s = (4Fr + 3.46 Fr sqrt(Fr) + 893 sqrt(Fr)) / S_n`` for "i)～iii)をSLP
に" (section 4), where the SLP and the PXPs, which *are* joined by queues, overlap and take the larger:
"パイプライン方式でSLP、PXPの処理を時間的に重ね合わせた場合の、総合的な処理量" ``Q_par = max(Q_s, Q_p)``
(section 4). The paper's queues are between processors only: host, SLP and PXP "各処理段階を非同期的に
動作させ、いわゆるパイプライン処理を実行する" (3.1) through the double message memories ("DMM/Sはホスト
計算機とSLP間のPLの授受、DMM/PはSLPと各PXP間のASL等の授受", 3.2). So each step the paper names is a
sub-component here (a class that emits its datapath and its states into the one FSM: :class:`_YSort`,
:class:`_AslUpdate`, :class:`_LSort`, :class:`_XMerge`, :class:`_BlockLists`) over the memories and
registers they share (:class:`_Band`), and they are not joined by streams: a stream between two steps
of one sequential processor would let them overlap, which changes the per-line cycles
``golden_model/experts/slp_cycles.py`` holds (a sum of every step's cycles). The block's own streams
are the paper's queues: ``i`` (the PL, from the DMM/S) and ``o`` (the ASL and its block lists, to the
DMM/P).

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
#: ``(x + _ROUND) >> X_FRAC``: the first pixel whose centre (``j + 1/2``) is at or right of the Q10.6 ``x``
_ROUND = (1 << (X_FRAC - 1)) - 1
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
    # i) Y-sort (:class:`_YSort`)
    IN = 0        # take input words (band, bounds, PL triangles, go)
    CLEAR = 1     # clear the buckets of the band
    # the ASL update of the previous line's segments (:class:`_AslUpdate`)
    LSTART = 2
    LEAVE = 3
    # iii) L-sort (:class:`_LSort`)
    BINIT = 4
    BSTEP = 5
    BEND = 6
    # ii) X-merge (:class:`_XMerge`)
    ESTART = 7
    EWALK = 8
    MLEVEL = 9
    MMOVE = 10
    FSETUP = 11
    FMOVE = 12
    # the block lists and the ASL words out (:class:`_BlockLists`)
    WSEG = 13
    WQ = 14
    WK = 15
    EOL = 16


def _before(ka, ta, kb, tb_):
    """(x_L, PL index) of a before b: the sort key of the L-sort and the X-merge ("その左稜線のxs座標値
    をキーとして", seed 000 section 4, ii); the PL index breaks ties as ``slp_run`` does)."""
    return (ka.xl < kb.xl) | ((ka.xl == kb.xl) & (ta < tb_))


class _Band:
    """The SLP's local memory and registers over one band, which every step reads and writes.

    The paper's SLP is one processor ("SLPには、加減算およびシフト演算を行なうALU ... の他に、乗算器、
    および逆数表(ROMによる)を装備した", seed 000, 3.2) whose memory is its own ("DMMははじめとして各
    プロセッサの局所メモリ、内部レジスタ・ファイル等を1語16ビットで構成する", 3.2): the steps below are
    that processor's steps, run one after another over these memories, so they share them rather than
    pass words to each other.

    Memories: ``tt`` the triangle words by PL index; ``bhead``, ``btail``, ``bcnt``, ``bnext`` the
    Y-sort's buckets; ``keys`` each triangle's x_L, x_R on the current line; ``A`` the ASL, ``B`` the
    survivors, ``E`` and ``F`` the entering segments (the merge sort's two buffers); ``bnd`` the range
    bounds.
    """

    def __init__(self, m, slp: ExpertsSlp):
        self.tl = data.StructLayout({k: v for k, v in slp_in_layout().members.items() if k not in ("kind", "t", "r0")})
        self.tb = tb = ADDR_BITS
        self.lb = lb = max((slp._lines - 1).bit_length(), 1)
        self.ab = ab = max((slp._asl - 1).bit_length(), 1)
        self.cw = cw = ab + 1
        self.xs = data.StructLayout({"xl": signed(XD_BITS), "xr": signed(XD_BITS)})

        def mem(name, shape, depth, reads):
            mm = Memory(shape=shape, depth=depth, init=[])
            m.submodules[name] = mm
            w = mm.write_port()
            m.d.comb += w.en.eq(0)
            return w, [mm.read_port(domain="comb") for _ in range(reads)]

        self.ttw, (self.ttr,) = mem("tt", self.tl, slp._tris, 1)
        self.hdw, (self.hdr,) = mem("bhead", unsigned(tb), slp._lines, 1)
        self.tlw, (self.tlr,) = mem("btail", unsigned(tb), slp._lines, 1)
        self.cnw, (self.cnr,) = mem("bcnt", unsigned(tb + 1), slp._lines, 1)
        self.nxw, (self.nxr,) = mem("bnext", unsigned(tb), slp._tris, 1)
        self.kyw, (self.ky0, self.ky1) = mem("keys", self.xs, slp._tris, 2)
        self.aw, (self.ar,) = mem("A", unsigned(tb), slp._asl, 1)
        self.bw, (self.br,) = mem("B", unsigned(tb), slp._asl, 1)
        self.ew, (self.er0, self.er1) = mem("E", unsigned(tb), slp._asl, 2)
        self.fw, (self.fr0, self.fr1) = mem("F", unsigned(tb), slp._asl, 2)
        self.ndw, (self.nd0, self.nd1) = mem("bnd", unsigned(X_END_BITS), 64, 2)

        self.state = Signal(_S)
        self.y0 = Signal(X_INT)
        self.y1 = Signal(X_INT)
        self.y = Signal(X_INT)
        self.nb = Signal(7)           # bounds taken (P + 1)
        self.clr = Signal(lb + 1)
        self.m_ = Signal(cw)          # previous ASL length
        self.ns = Signal(cw)          # survivors
        self.ne = Signal(cw)          # entering
        self.i = Signal(cw)
        self.node = Signal(tb)
        self.cur = Signal(tb)         # bubble: the carried element
        self.swapped = Signal()
        self.wdt = Signal(cw + 1)     # merge sort: run width
        self.src_f = Signal()         # merge sort: the sorted runs are in F (else E)
        self.li, self.le, self.ri, self.re, self.o = (Signal(cw + 1, name=n) for n in ("li", "le", "ri", "re", "o"))
        self.s0 = Signal(cw + 1)      # merge sort: start of the pair being merged
        self.q = Signal(7)
        self.k = Signal(7)
        self.pos = Signal(cw)
        self.cyc = Signal(16)
        self.P = Signal(7)
        m.d.comb += self.P.eq(self.nb - 1)
        m.d.sync += self.cyc.eq(self.cyc + 1)


class _YSort:
    """i) **Y-sort**: "表示面に含まれるすべての稜線を、y_{min} (頂点のy座標で最小の方の値)をキーとして
    バケットソートする《Y-sort》" (seed 000, section 4, i).

    States ``IN`` and ``CLEAR``: the input words (band, range bounds, PL triangles, go), one a cycle;
    each triangle of the band is linked at the tail of the bucket of its first line in the band (head,
    tail, count per line, a next pointer per triangle), its set-up stored by PL index. This is also
    the SLP's clipping to its band ("一種のクリッピング(clipping)処理をSLPが分担したことになり", 3.2).
    """

    def __init__(self, m, slp: ExpertsSlp, b: _Band):
        self.m, self.slp, self.b = m, slp, b
        p = slp.i.payload
        bidx = Signal(b.lb + 1)
        m.d.comb += bidx.eq(Mux(p.r0 > b.y0, p.r0, b.y0) - b.y0)
        self.bidx = bidx

    def states(self):
        m, b, p, bidx = self.m, self.b, self.slp.i.payload, self.bidx
        y0, y1, nb, clr, state = b.y0, b.y1, b.nb, b.clr, b.state
        cnr, cnw, tlr, tlw, hdw, nxw = b.cnr, b.cnw, b.tlr, b.tlw, b.hdw, b.nxw
        with m.Case(_S.IN):
            m.d.comb += self.slp.i.ready.eq(1)
            with m.If(self.slp.i.valid):
                with m.Switch(p.kind):
                    with m.Case(IN_KIND["band"]):
                        m.d.sync += [y0.eq(p.r0), y1.eq(p.r1), nb.eq(0), clr.eq(0), state.eq(_S.CLEAR)]
                    with m.Case(IN_KIND["bound"]):
                        m.d.comb += [b.ndw.addr.eq(nb), b.ndw.data.eq(p.xa), b.ndw.en.eq(1)]
                        m.d.sync += nb.eq(nb + 1)
                    with m.Case(IN_KIND["tri"]):
                        m.d.comb += [b.ttw.addr.eq(p.t), b.ttw.en.eq(1)]
                        for f in b.tl.members:
                            m.d.comb += getattr(b.ttw.data, f).eq(getattr(p, f))
                        with m.If((p.r1 >= y0) & (p.r0 < y1)):
                            # link at the tail of the bucket of its first line in the band
                            m.d.comb += [cnr.addr.eq(bidx), tlr.addr.eq(bidx),
                                         cnw.addr.eq(bidx), cnw.data.eq(cnr.data + 1), cnw.en.eq(1),
                                         tlw.addr.eq(bidx), tlw.data.eq(p.t), tlw.en.eq(1)]
                            with m.If(cnr.data == 0):
                                m.d.comb += [hdw.addr.eq(bidx), hdw.data.eq(p.t), hdw.en.eq(1)]
                            with m.Else():
                                m.d.comb += [nxw.addr.eq(tlr.data), nxw.data.eq(p.t), nxw.en.eq(1)]
                    with m.Case(IN_KIND["go"]):
                        m.d.sync += [b.y.eq(y0), b.m_.eq(0), state.eq(_S.LSTART)]
        with m.Case(_S.CLEAR):
            m.d.comb += [cnw.addr.eq(clr), cnw.data.eq(0), cnw.en.eq(1)]
            m.d.sync += clr.eq(clr + 1)
            with m.If(clr + 1 >= y1 - y0):
                m.d.sync += state.eq(_S.IN)


class _AslUpdate:
    """The **ASL update**: "スキャン・ラインを次に1度に進める度にASLを更新する処理" (seed 000, 3.1 a)),
    by scan-line coherence: "かの一定の増分値を加えるだけのインクリメンタル (incremental) な計算だけで
    更新が行なえる" (2.2).

    Its datapath is the edge accumulators (``((x0 << 16) + ((yc - y0) inc >> 6)) >> 16``, one multiply
    per edge): ours, one multiplier per edge and per attribute (:meth:`multipliers`); the paper's,
    "乗算器" (3.2), one 16 x 16 multiplier shared in time (:meth:`one_multiplier`). The X-merge uses it
    for each entering segment and the block lists for z_L, i_L of each ASL word.

    States ``LSTART`` and ``LEAVE``: per line, the leave test of each segment of the previous ASL
    (it leaves after its last line: the "退出するセグメント" of the L-sort, section 4, iii), and the
    survivors' new x_L, x_R into ``keys``, the survivors into ``B``.
    """

    def __init__(self, m, slp: ExpertsSlp, b: _Band):
        self.m, self.slp, self.b = m, slp, b
        # x_L, x_R of triangle ``tt`` entry on line y (one multiply per edge)
        yc = Signal(signed(XD_BITS))
        m.d.comb += yc.eq((b.y << X_FRAC) + (1 << (X_FRAC - 1)))
        tv = Signal(b.tl)
        m.d.comb += tv.eq(b.ttr.data)

        one = slp._ex == 0      # the paper's datapath: one 16 x 16 multiplier, shared in time
        ph = Signal()            # (paper) the multiply phase of a segment's ASL update and ASL word
        mul: dict = {}
        if one:
            mul = self.one_multiplier(m, tv, yc, b.xs)
            newx, zl_, il_ = mul["newx"], mul["zreg"], mul["res"]
        else:
            newx, zl_, il_ = self.multipliers(m, tv, yc, b.xs)
        self.yc, self.tv, self.ph, self.mul, self.newx, self.zl_, self.il_ = yc, tv, ph, mul, newx, zl_, il_

    def multipliers(self, m, tv, yc, xs):
        """Ours: x of the three edges, z and i of the left edge, each with its own multiplier, in
        the cycle that needs them. Returns x_L/x_R (``xs``), z_L and i_L."""
        def edge(x0, yy0, inc, name):
            v = Signal(signed(80), name=name)
            m.d.comb += v.eq(((x0 << self.slp._ex) + (((yc - yy0) * inc) >> X_FRAC)) >> self.slp._ex)
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
    def one_multiplier(m, tv, yc, xs):
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

    @contextmanager
    def first_multiply(self, first, op0="x_long", op1="x_short", hold=False):
        """The paper's datapath (one multiplier): while ``first``, a cycle that only multiplies
        (``op0``, kept in ``xlong`` or, for ``z_left``, ``zreg``); then the step's own cycle, with
        ``op1`` on the multiplier, which resets the phase (``hold``: the step resets it itself, when
        its word is taken). Ours: the step alone."""
        m, mul, ph = self.m, self.mul, self.ph
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

    def states(self):
        m, b, tv, y = self.m, self.b, self.tv, self.b.y
        i, ns, state = b.i, b.ns, b.state
        with m.Case(_S.LSTART):
            m.d.sync += [b.cyc.eq(1), i.eq(0), ns.eq(0), b.ne.eq(0), b.q.eq(0), b.pos.eq(0),
                         state.eq(Mux(b.m_ == 0, _S.ESTART, _S.LEAVE))]
        with m.Case(_S.LEAVE):
            # leave test + ASL update of the previous ASL's segment i
            m.d.comb += [b.ar.addr.eq(i), b.ttr.addr.eq(b.ar.data)]
            with self.first_multiply((tv.r1 >= y) & ~self.ph):
                with m.If(tv.r1 >= y):
                    m.d.comb += [b.bw.addr.eq(ns), b.bw.data.eq(b.ar.data), b.bw.en.eq(1),
                                 b.kyw.addr.eq(b.ar.data), b.kyw.data.eq(self.newx), b.kyw.en.eq(1)]
                    m.d.sync += ns.eq(ns + 1)
                m.d.sync += i.eq(i + 1)
                with m.If(i + 1 >= b.m_):
                    nsn = ns + (tv.r1 >= y)
                    m.d.sync += state.eq(Mux(nsn >= 2, _S.BINIT, _S.ESTART))


class _LSort:
    """iii) **L-sort**: "スキャン・ラインの更新に伴い進入、退出するセグメントと ii) で作成したセグメント
    リストとをバブルソートする《L-sort》" (seed 000, section 4, iii).

    States ``BINIT``, ``BSTEP``, ``BEND``: bubble sort of the survivors (``B``) on (x_L, PL index),
    whole passes until one exchanges nothing, one compare a cycle with the larger element carried in a
    register, one cycle to close each pass. The entering segments join them in the X-merge's last
    merge.
    """

    def __init__(self, m, b: _Band):
        self.m, self.b = m, b

    def states(self):
        m, b = self.m, self.b
        i, cur, br, bw, state = b.i, b.cur, b.br, b.bw, b.state
        with m.Case(_S.BINIT):
            m.d.comb += br.addr.eq(0)
            m.d.sync += [cur.eq(br.data), i.eq(0), b.swapped.eq(0), state.eq(_S.BSTEP)]
        with m.Case(_S.BSTEP):
            # compare B[i+1] with the carried element; the smaller is written at i
            m.d.comb += [br.addr.eq(i + 1), b.ky0.addr.eq(br.data), b.ky1.addr.eq(cur), bw.addr.eq(i), bw.en.eq(1)]
            kn, kc = Signal(b.xs), Signal(b.xs)
            m.d.comb += [kn.eq(b.ky0.data), kc.eq(b.ky1.data)]
            with m.If(_before(kn, br.data, kc, cur)):
                m.d.comb += bw.data.eq(br.data)
                m.d.sync += b.swapped.eq(1)
            with m.Else():
                m.d.comb += bw.data.eq(cur)
                m.d.sync += cur.eq(br.data)
            m.d.sync += i.eq(i + 1)
            with m.If(i + 2 >= b.ns):
                m.d.sync += state.eq(_S.BEND)
        with m.Case(_S.BEND):
            m.d.comb += [bw.addr.eq(b.ns - 1), bw.data.eq(cur), bw.en.eq(1)]
            m.d.sync += state.eq(Mux(b.swapped, _S.BINIT, _S.ESTART))


class _XMerge:
    """ii) **X-merge**: "1スキャン・ライン内に現われるセグメントを、その左稜線のxs座標値をキーとして、
    マージソートする《X-merge》" (seed 000, section 4, ii).

    States ``ESTART``, ``EWALK``: the line's bucket walked, the ASL update (:class:`_AslUpdate`) of
    each entering segment into ``E``; ``MLEVEL``, ``MMOVE``: merge-sorted bottom up between ``E`` and
    ``F`` (one move a cycle, one cycle to set up a level); ``FSETUP``, ``FMOVE``: merged into the
    survivors (one move a cycle; survivors first on equal keys, as ``slp_run.merge``), the new ASL
    into ``A``.
    """

    def __init__(self, m, slp: ExpertsSlp, b: _Band, upd: _AslUpdate):
        self.m, self.slp, self.b, self.upd = m, slp, b, upd

    def states(self):
        m, b, upd = self.m, self.b, self.upd
        tb = b.tb
        i, ns, ne, node, state, src_f, wdt = b.i, b.ns, b.ne, b.node, b.state, b.src_f, b.wdt
        li, le, ri, re, o, s0 = b.li, b.le, b.ri, b.re, b.o, b.s0
        ky0, ky1 = b.ky0, b.ky1
        with m.Case(_S.ESTART):
            m.d.comb += [b.cnr.addr.eq(b.y - b.y0), b.hdr.addr.eq(b.y - b.y0)]
            m.d.sync += [node.eq(b.hdr.data), ne.eq(b.cnr.data), i.eq(0),
                         state.eq(Mux(b.cnr.data == 0, _S.FSETUP, _S.EWALK))]
        with m.Case(_S.EWALK):
            # the line's bucket: ASL update of each entering segment, into E
            m.d.comb += [b.ttr.addr.eq(node), b.nxr.addr.eq(node)]
            with upd.first_multiply(~upd.ph):
                m.d.comb += [b.ew.addr.eq(i), b.ew.data.eq(node), b.ew.en.eq(1),
                             b.kyw.addr.eq(node), b.kyw.data.eq(upd.newx), b.kyw.en.eq(1)]
                m.d.sync += [node.eq(b.nxr.data), i.eq(i + 1)]
                with m.If(i + 1 >= ne):
                    m.d.sync += [wdt.eq(1), src_f.eq(0), state.eq(Mux(ne >= 2, _S.MLEVEL, _S.FSETUP))]
        with m.Case(_S.MLEVEL):
            m.d.sync += [s0.eq(0), li.eq(0), le.eq(Mux(wdt < ne, wdt, ne)), ri.eq(Mux(wdt < ne, wdt, ne)),
                         re.eq(Mux(2 * wdt < ne, 2 * wdt, ne)), o.eq(0), state.eq(_S.MMOVE)]
        with m.Case(_S.MMOVE):
            # merge the pair [li, le) + [ri, re) of the source into the destination
            ta, tb_ = Signal(tb), Signal(tb)
            m.d.comb += [b.er0.addr.eq(li), b.er1.addr.eq(ri), b.fr0.addr.eq(li), b.fr1.addr.eq(ri),
                         ta.eq(Mux(src_f, b.fr0.data, b.er0.data)), tb_.eq(Mux(src_f, b.fr1.data, b.er1.data)),
                         ky0.addr.eq(ta), ky1.addr.eq(tb_)]
            take_r = Signal()
            m.d.comb += take_r.eq((li >= le) | ((ri < re) & _before(ky1.data, tb_, ky0.data, ta)))
            val = Mux(take_r, tb_, ta)
            with m.If(src_f):
                m.d.comb += [b.ew.addr.eq(o), b.ew.data.eq(val), b.ew.en.eq(1)]
            with m.Else():
                m.d.comb += [b.fw.addr.eq(o), b.fw.data.eq(val), b.fw.en.eq(1)]
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
            m.d.sync += [li.eq(0), le.eq(ns), ri.eq(0), re.eq(ne), o.eq(0), b.m_.eq(ns + ne),
                         state.eq(Mux(ns + ne == 0, _S.EOL, _S.FMOVE))]
            with m.If(ns + ne > self.slp._asl):
                m.d.sync += self.slp.overflow.eq(1)
        with m.Case(_S.FMOVE):
            # survivors (B) and entering (E or F) into the new ASL (A), survivors first on ties
            ta, tb_ = Signal(tb), Signal(tb)
            m.d.comb += [b.br.addr.eq(li), b.er1.addr.eq(ri), b.fr1.addr.eq(ri),
                         ta.eq(b.br.data), tb_.eq(Mux(src_f, b.fr1.data, b.er1.data)),
                         ky0.addr.eq(ta), ky1.addr.eq(tb_)]
            take_r = Signal()
            m.d.comb += take_r.eq((li >= le) | ((ri < re) & _before(ky1.data, tb_, ky0.data, ta)))
            m.d.comb += [b.aw.addr.eq(o), b.aw.data.eq(Mux(take_r, tb_, ta)), b.aw.en.eq(1)]
            m.d.sync += [li.eq(Mux(take_r, li, li + 1)), ri.eq(Mux(take_r, ri + 1, ri)), o.eq(o + 1)]
            with m.If(o + 1 >= ns + ne):
                m.d.sync += [b.m_.eq(ns + ne), b.pos.eq(0), state.eq(_S.WSEG)]


class _BlockLists:
    """The **block lists** and the ASL words out: "図3.2に示すBlock Boundary Bucket List、および
    Block Leading Segment PointerとASLの附加的な情報をもつASLと共にPXPへ送出する。これらは、SLPにおける
    ASL作成・更新処理の際に容易に生成できる" (seed 000, 3.2, fig. 3.2).

    States ``WSEG``, ``WQ``, ``WK``, ``EOL``: one walk of the new ASL: its ASL word (the whole ASB:
    x_L, x_R, and z_L, i_L from the left edge's accumulators, the line's edge slopes, the set-up
    values), then the leading pointer of every range whose start it is the first to reach and its
    entry in the bucket list of every later range it reaches (``slp_run.block_lists``; ranges widened
    by ``guard`` pixels each side), one cycle per test; then the end-of-line word. The output stream
    ``o`` is where the paper's SLP hands over to its PXPs (through the DMM/P, "DMM/PはSLPと各PXP間の
    ASL等の授受", 3.2).
    """

    def __init__(self, m, slp: ExpertsSlp, b: _Band, upd: _AslUpdate):
        self.m, self.slp, self.b, self.upd = m, slp, b, upd
        tv, yc = upd.tv, upd.yc
        # the A.J. slopes of the short edge on this line
        s_sh, q_sh = Signal(signed(WORD)), Signal(signed(WORD))
        m.d.comb += [s_sh.eq(Mux(yc < tv.yb, tv.s_ab, tv.s_bc)), q_sh.eq(Mux(yc < tv.yb, tv.q_ab, tv.q_bc))]
        self.s_sh, self.q_sh = s_sh, q_sh

    def states(self):
        m, slp, b, upd = self.m, self.slp, self.b, self.upd
        W, G = slp._w, slp._guard
        o_, tv, s_sh, q_sh, mul = slp.o.payload, upd.tv, self.s_sh, self.q_sh, upd.mul
        pos, y, q, k, state, ar, ky0, nd0, nd1 = b.pos, b.y, b.q, b.k, b.state, b.ar, b.ky0, b.nd0, b.nd1
        with m.Case(_S.WSEG):
            m.d.comb += [ar.addr.eq(pos), ky0.addr.eq(ar.data), b.ttr.addr.eq(ar.data)]
            # (paper) z_L first, then i_L as the word goes out
            with upd.first_multiply(~upd.ph, "z_left", "i_left", hold=True):
                m.d.comb += [slp.o.valid.eq(1), o_.kind.eq(0), o_.pos.eq(pos), o_.t.eq(ar.data), o_.y.eq(y),
                             o_.asb.xl.eq(ky0.data.xl), o_.asb.xr.eq(ky0.data.xr), o_.asb.zl.eq(upd.zl_),
                             o_.asb.il.eq(upd.il_), o_.asb.dzdx.eq(tv.dzdx), o_.asb.didx.eq(tv.didx),
                             o_.asb.hue.eq(tv.hue), o_.asb.addr.eq(ar.data), o_.asb.poly.eq(tv.poly),
                             o_.asb.sl.eq(Mux(tv.ll, tv.s_ac, s_sh)), o_.asb.ql.eq(Mux(tv.ll, tv.q_ac, q_sh)),
                             o_.asb.sr.eq(Mux(tv.ll, s_sh, tv.s_ac)), o_.asb.qr.eq(Mux(tv.ll, q_sh, tv.q_ac))]
                c0, c1 = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                m.d.comb += [c0.eq((ky0.data.xl + _ROUND) >> X_FRAC), c1.eq(((ky0.data.xr + _ROUND) >> X_FRAC) - 1)]
                with m.If(slp.o.ready):
                    if mul:
                        m.d.sync += upd.ph.eq(0)
                    a_ = Mux(c0 < 0, 0, c0)
                    e_ = Mux(c1 > W - 1, W - 1, c1)
                    with m.If(e_ < a_):
                        m.d.sync += pos.eq(pos + 1)
                        with m.If(pos + 1 >= b.m_):
                            m.d.sync += state.eq(_S.EOL)
                    with m.Else():
                        m.d.sync += state.eq(_S.WQ)
        with m.Case(_S.WQ, _S.WK):
            m.d.comb += [ar.addr.eq(pos), ky0.addr.eq(ar.data)]
            c0, c1 = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
            m.d.comb += [c0.eq((ky0.data.xl + _ROUND) >> X_FRAC), c1.eq(((ky0.data.xr + _ROUND) >> X_FRAC) - 1)]
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
                with m.If((q < b.P) & (a_ >= glo)):
                    emit = live & (a_ < ghi)
                    m.d.comb += [slp.o.valid.eq(emit), o_.kind.eq(1)]
                    with m.If(~emit | slp.o.ready):
                        m.d.sync += q.eq(q + 1)
                with m.Else():
                    m.d.sync += [k.eq(q), state.eq(_S.WK)]
            with m.Else():
                with m.If((k < b.P) & (glo <= e_)):
                    m.d.comb += [slp.o.valid.eq(live), o_.kind.eq(2)]
                    with m.If(~live | slp.o.ready):
                        m.d.sync += k.eq(k + 1)
                with m.Else():
                    m.d.sync += [pos.eq(pos + 1), state.eq(Mux(pos + 1 >= b.m_, _S.EOL, _S.WSEG))]
        with m.Case(_S.EOL):
            m.d.comb += [slp.o.valid.eq(1), o_.kind.eq(3), o_.y.eq(y)]
            with m.If(slp.o.ready):
                m.d.sync += [slp.line_cycles.eq(b.cyc + 1), y.eq(y + 1),
                             state.eq(Mux(y + 1 >= b.y1, _S.IN, _S.LSTART))]


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

    def elaborate(self, platform):
        m = Module()
        b = _Band(m, self)
        m.d.comb += [self.i.ready.eq(0), self.o.valid.eq(0)]
        # the datapaths outside the FSM, in this order (the netlist's statement order)
        upd = _AslUpdate(m, self, b)
        walk = _BlockLists(m, self, b, upd)
        ysort = _YSort(m, self, b)
        # one FSM: the steps' states, each step after the one before it on the same memories
        with m.Switch(b.state):
            ysort.states()
            upd.states()
            _LSort(m, b).states()
            _XMerge(m, self, b, upd).states()
            walk.states()
        return m
