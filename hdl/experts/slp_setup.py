"""EXPERTS SLP set-up (ASL creation): PL triangles in, the triangle words of the SLP's list work out.

Paper (seed 000, 3.2): "SLPにおけるASL作成の処理は、以後のインクリメンタルな計算のための各種の増分値の
計算を含んだりするため、乗除算の高速化を行なう必要がある。そこでSLPには ... ALU ... の他に、乗算器、
および逆数表(ROMによる)を装備した". One multiplier (one product a cycle) and a reciprocal ROM of
``2**15`` 16-bit words (the size is ours; ``golden_model/experts/slp_setup.py`` says why), run as
``golden_model/experts/slp_setup.py`` runs them (every step and every cycle is named there):

* a ``BAND`` word sets the band (``r0`` .. ``r1``, exclusive);
* a PL triangle (``TRI``): vertices sorted on y (stable), first and last line, band test in the
  cycle it is taken; out of the band, the word with ``t``, ``r0``, ``r1`` only; in the band, six
  multiplies for eq. (3)'s denominator and the z and i numerators, then seven reciprocals (each
  edge's ``dY`` and ``dX``, the denominator: ROM word + 1, one multiply for the remainder, one ALU
  cycle per correction, one to finish) each followed by its multiply-and-rounds (``formats.rom_div``:
  ``(|num| R << shift + 2**(S-1)) >> S`` with the sign), then the word out.

**One sequencer, its steps in turn.** The set-up is the first part of the paper's SLP, one
processor (its ALU, "乗算器、および逆数表(ROMによる)", 3.2), so its steps are sub-components (methods
that emit their states and datapath into the one sequencer, over the registers they share,
:class:`_Triangle`), not stages joined by streams: take a PL word (vertex sort and the band test, the
SLP's clipping: :meth:`ExpertsSlpSetup._take`), eq. (3)'s products (:meth:`~ExpertsSlpSetup._product`),
the reciprocals (:meth:`~ExpertsSlpSetup._reciprocal`), the increments
(:meth:`~ExpertsSlpSetup._multiply_round`), in the order :meth:`~ExpertsSlpSetup._program` lists, then
the word out (:meth:`~ExpertsSlpSetup._word_out`). A stream between them would let one triangle's
steps overlap the next's and change the cycles ``golden_model/experts/slp_setup.py`` holds (one step
after another). The stream ``o`` to the list work (``hdl/experts/slp.py``) is ours: the paper's SLP
does both in one processor, and the frame's SLP cycles are the set-up's plus the list work's
(``docs/experts.md``, "SLP (set-up + list work)").

Output: ``hdl/experts/slp.py``'s input word (:func:`~rasterhw.hdl.experts.slp.slp_in_layout`,
kind ``TRI``), as ``slp_cycles.tri_words`` gives it.
"""

from __future__ import annotations

from amaranth import Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import (
    ACC_EXTRA,
    ADDR_BITS,
    DZ_FRAC,
    RGB_BITS,
    SLOPE_FRAC,
    WORD,
    X_FRAC,
    X_INT,
    XD_BITS,
    XP_BITS,
    XS_BITS,
    Z_BITS,
)
from rasterhw.golden_model.experts.slp_setup import EDGES, ROM_INDEX_BITS, rom_table

__all__ = ["ExpertsSlpSetup", "pl_layout", "PL_KIND", "LIMBS"]

PL_KIND = {"band": 0, "tri": 1}
#: the paper's datapath: 16-bit limbs of each step's two operands (``slp_setup.MULTIWORD`` counts the
#: cycles): eq. (3)'s products and an edge's multiply-and-rounds are 16 x 16 (vertex x, y, z, i are
#: 16-bit words, so their differences and R are 16-bit magnitudes); an edge's reciprocal remainder
#: ``|d| (ROM + 1)`` has a 17-bit factor (ROM + 1 <= 2**16); the denominator and eq. (3)'s
#: numerators are up to 34 bits (three limbs)
LIMBS = {"mul": (1, 1), "recip": (1, 2), "recip_den": (3, 2), "md": (1, 1), "md_plane": (3, 1)}


def pl_layout() -> data.StructLayout:
    f = {"kind": unsigned(1), "t": unsigned(ADDR_BITS), "r0": unsigned(X_INT), "r1": unsigned(X_INT)}
    for j in range(3):
        f.update({f"x{j}": signed(XS_BITS), f"y{j}": signed(XS_BITS), f"z{j}": unsigned(Z_BITS),
                  f"i{j}": unsigned(WORD)})
    f.update({"hue": unsigned(RGB_BITS), "poly": unsigned(ADDR_BITS)})
    return data.StructLayout(f)


class ExpertsSlpSetup(wiring.Component):
    """The SLP's set-up unit: one multiplier, the reciprocal ROM, a sequencer.

    Parameters
    ----------
    height : int
        Frame height (the last line a triangle may reach), 1..1024.
    acc_extra : int
        Fraction bits of the edge increments beyond the 16-bit word (``formats.Datapath.acc_extra``):
        16 (ours, the default) or 0 (the paper's 16-bit datapath: each increment saturated to 16 bits).

    Members
    -------
    i : In(stream.Signature(pl_layout()))
    o : Out(stream.Signature(slp_in_layout()))
    """

    def __init__(self, *, height: int = 512, acc_extra: int = ACC_EXTRA):
        if isinstance(height, bool) or not isinstance(height, int) or not 1 <= height <= 1024:
            raise ValueError(f"height must be an integer in 1..1024, not {height!r}")
        if acc_extra not in (0, ACC_EXTRA) or isinstance(acc_extra, bool):
            raise ValueError(f"acc_extra must be 0 or {ACC_EXTRA}, not {acc_extra!r}")
        self._h, self._ex = height, acc_extra
        from rasterhw.hdl.experts.slp import slp_in_layout
        super().__init__({"i": In(stream.Signature(pl_layout())), "o": Out(stream.Signature(slp_in_layout()))})

    def _multiplier(self, m, ma, mb, prod):
        """``prod = ma * mb``. Ours: one 40 x 20 multiplier, one product a cycle. The paper's
        (``acc_extra`` 0): one 16 x 16 multiplier (:func:`mul16.sm_mul`'s sign and magnitude), a
        product of ``(na, nb)`` 16-bit limbs (:data:`LIMBS`) in ``na * nb`` cycles, one partial
        product a cycle added into a multi-word accumulator, the step's own work in the last. Returns
        ``limbs(na, nb)``, the context a step's sync work goes in."""
        from contextlib import contextmanager
        if self._ex != 0:
            m.d.comb += prod.eq(ma * mb)

            @contextmanager
            def one_cycle(na, nb):
                yield
            return one_cycle
        aa, ab_ = Signal(3 * WORD, name="mag_a"), Signal(2 * WORD, name="mag_b")
        neg = Signal(name="neg")
        ia, ib = Signal(2, name="limb_a"), Signal(1, name="limb_b")
        la, lb = Signal(WORD, name="word_a"), Signal(WORD, name="word_b")
        part = Signal(2 * WORD, name="part")
        place = Signal(4 * WORD, name="place")
        pacc, pfull = Signal(4 * WORD, name="pacc"), Signal(4 * WORD, name="pfull")
        lc = Signal(3, name="lc")
        m.d.comb += [aa.eq(Mux(ma < 0, -ma, ma)), ab_.eq(Mux(mb < 0, -mb, mb)), neg.eq((ma < 0) ^ (mb < 0)),
                     la.eq(aa.word_select(ia, WORD)), lb.eq(ab_.word_select(ib, WORD)), part.eq(la * lb),
                     place.eq(Mux(ia + ib == 0, part, Mux(ia + ib == 1, part << WORD,
                                                          Mux(ia + ib == 2, part << 2 * WORD, part << 3 * WORD)))),
                     pfull.eq(pacc + place), prod.eq(Mux(neg, -pfull, pfull))]

        @contextmanager
        def multiword(na, nb):
            n = na * nb
            if n == 1:
                yield
                return
            m.d.comb += [ia.eq(lc >> 1 if nb == 2 else lc), ib.eq(lc[0] if nb == 2 else 0)]
            with m.If(lc != n - 1):
                m.d.sync += [pacc.eq(pfull), lc.eq(lc + 1)]
            with m.Else():
                m.d.sync += [pacc.eq(0), lc.eq(0)]
                yield
        return multiword

    def elaborate(self, platform):
        from rasterhw.hdl.experts.slp import IN_KIND
        m = Module()
        r = _Triangle()
        p = self.i.payload
        r.res = Signal(self.o.payload.shape())
        m.d.comb += [self.o.payload.eq(r.res), self.i.ready.eq(0), self.o.valid.eq(0)]
        rom = Memory(shape=WORD, depth=1 << ROM_INDEX_BITS, init=[int(v) for v in rom_table()])
        m.submodules.rom = rom
        r.rp = rom.read_port(domain="comb")
        self._vertices(r, p)
        self._datapath(m, r)
        r.pc = Signal(range(64))
        r.busy = Signal()
        r.out = Signal()
        prog = self._program(m, r)
        self._take(m, r, p, IN_KIND["tri"])
        self._sequencer(m, r, prog)
        self._word_out(m, r)
        return m

    @staticmethod
    def _vertices(r, p):
        """The triangle's vertices, sorted on y in the cycle the word is taken (stable: ties keep PL
        order), and the band's lines."""
        r.X = [Signal(signed(XS_BITS), name=f"X{k}") for k in range(3)]
        r.Y = [Signal(signed(XS_BITS), name=f"Y{k}") for k in range(3)]
        r.Z = [Signal(unsigned(Z_BITS), name=f"Z{k}") for k in range(3)]
        r.Iv = [Signal(unsigned(WORD), name=f"I{k}") for k in range(3)]
        py = [p.y0, p.y1, p.y2]
        before = {(a, b): (py[a] <= py[b]) if a < b else (py[a] < py[b]) for a in range(3) for b in range(3) if a != b}
        r.rank = [sum((before[(b, a)] for b in range(3) if b != a), Const(0, 2)) for a in range(3)]
        y0, y1 = Signal(X_INT), Signal(X_INT)   # locals: Amaranth names a signal after its variable
        r.y0, r.y1 = y0, y1

    def _datapath(self, m, r):
        """The one multiplier ("乗算器", seed 000, 3.2; :meth:`_multiplier`), an accumulator for
        eq. (3)'s sums (``den``, ``nz``, ``ni``), and the reciprocal's registers (``R``, ``S``, the
        divisor's sign, magnitude and zero flag, the remainder ``e``)."""
        ma, mb = Signal(signed(40)), Signal(signed(20))
        r.ma, r.mb = ma, mb
        r.prod = Signal(signed(60))
        r.limbs = self._multiplier(m, r.ma, r.mb, r.prod)
        r.acc = Signal(signed(40))
        r.den, r.nz, r.ni = (Signal(signed(40), name=n) for n in ("den", "nz", "ni"))
        r.R = Signal(unsigned(18))
        r.S = Signal(unsigned(6))
        r.dneg = Signal()
        r.dz = Signal()                       # the divisor is 0
        r.dabs = Signal(unsigned(40))
        r.e = Signal(signed(72))
        r.corr = Signal()                     # in a reciprocal's correction cycles
        r.s1 = Signal(unsigned(6))            # S - 1: the rounding bit
        m.d.comb += r.s1.eq(r.S - 1)

    def _program(self, m, r) -> list:
        """The ASL creation's increments, in the order the sequencer runs them: "SLPにおけるASL作成の処理は、
        以後のインクリメンタルな計算のための各種の増分値の計算を含んだりするため、乗除算の高速化を行なう
        必要がある" (seed 000, 3.2). Eq. (3)'s denominator and z, i numerators (six products,
        :meth:`_product`); per edge its ``dY``'s reciprocal (:meth:`_reciprocal`) and the x, z, i
        increments and the A.J. slope dx/dy (:meth:`_multiply_round`), its ``dX``'s reciprocal and
        dy/dx; the denominator's reciprocal, dz/dx and di/dx. A step is ``("mul", a, b, dst,
        first)``, ``("recip", d)`` or ``("md", num, shift, field, kind)``."""
        X, Y, Z, Iv, den, nz, ni = r.X, r.Y, r.Z, r.Iv, r.den, r.nz, r.ni

        def df(A, i, j):
            v = Signal(signed(XD_BITS), name=f"d_{A[0].name}_{i}{j}")
            m.d.comb += v.eq(A[j] - A[i])
            return v
        prog = [("mul", df(Y, 2, 1), df(X, 1, 0), den, True), ("mul", df(Y, 1, 0), df(X, 2, 1), den, False),
                ("mul", df(Y, 2, 1), df(Z, 1, 0), nz, True), ("mul", df(Y, 1, 0), df(Z, 2, 1), nz, False),
                ("mul", df(Y, 2, 1), df(Iv, 1, 0), ni, True), ("mul", df(Y, 1, 0), df(Iv, 2, 1), ni, False)]
        sh = X_FRAC + self._ex
        ik = "sat" if self._ex == 0 else "int"     # the paper's datapath: one saturated 16-bit word
        for e_, i, j in EDGES:
            dX, dY = df(X, i, j), df(Y, i, j)
            prog += [("recip", dY), ("md", dX, sh, f"inc_{e_}", ik), ("md", df(Z, i, j), sh, f"zinc_{e_}", ik),
                     ("md", df(Iv, i, j), sh, f"iinc_{e_}", ik), ("md", dX, SLOPE_FRAC, f"s_{e_}", "sat"),
                     ("recip", dX), ("md", dY, SLOPE_FRAC, f"q_{e_}", "satq")]
        prog += [("recip", den), ("md", nz, X_FRAC + DZ_FRAC, "dzdx", "sat"), ("md", ni, X_FRAC, "didx", "sat")]
        return prog

    def _take(self, m, r, p, tri_kind):
        """Take a PL word: a ``BAND`` word sets the band; a triangle's vertices are sorted on y, its
        first and last line found and tested against the band, the SLP's clipping: "各SLPは、ホスト
        計算機から送られたPLを基に、自らの担当画面領域における最初のスキャン・ラインについてのASLを生成
        する。これは、一種のクリッピング(clipping)処理をSLPが分担したことになり" (seed 000, 3.2). In the
        band, the program runs (``busy``); out of it, the word goes out at once with ``t``, ``r0``,
        ``r1`` only."""
        X, Y, Z, Iv, rank, res = r.X, r.Y, r.Z, r.Iv, r.rank, r.res
        half = 1 << (X_FRAC - 1)
        with m.If(~r.busy & ~r.out):
            m.d.comb += self.i.ready.eq(1)
            with m.If(self.i.valid):
                with m.If(p.kind == PL_KIND["band"]):
                    m.d.sync += [r.y0.eq(p.r0), r.y1.eq(p.r1)]
                with m.Else():
                    for a in range(3):
                        with m.Switch(rank[a]):
                            for k in range(3):
                                with m.Case(k):
                                    m.d.sync += [X[k].eq(getattr(p, f"x{a}")), Y[k].eq(getattr(p, f"y{a}")),
                                                 Z[k].eq(getattr(p, f"z{a}")), Iv[k].eq(getattr(p, f"i{a}"))]
                    ytop = Mux(rank[0] == 0, p.y0, Mux(rank[1] == 0, p.y1, p.y2))
                    ybot = Mux(rank[0] == 2, p.y0, Mux(rank[1] == 2, p.y1, p.y2))
                    r0v, r1v = Signal(signed(XP_BITS)), Signal(signed(XP_BITS))
                    m.d.comb += [r0v.eq((ytop + half - 1) >> X_FRAC), r1v.eq(((ybot + half - 1) >> X_FRAC) - 1)]
                    r0c = Mux(r0v < 0, 0, r0v)
                    r1c = Mux(r1v > self._h - 1, self._h - 1, r1v)
                    m.d.sync += [res.eq(0), res.kind.eq(tri_kind), res.t.eq(p.t), res.r0.eq(r0c),
                                 res.r1.eq(r1c), res.hue.eq(p.hue), res.poly.eq(p.poly), r.pc.eq(0)]
                    inb = (r1c >= r.y0) & (r0c < r.y1)
                    m.d.sync += [r.busy.eq(inb), r.out.eq(~inb)]
                    with m.If(~inb):
                        m.d.sync += [res.hue.eq(0), res.poly.eq(0)]

    def _sequencer(self, m, r, prog):
        """The program (:meth:`_program`), one step a cycle (a reciprocal's corrections stay on its
        step; the paper's datapath: a multi-word product a partial product a cycle), then the sorted
        vertices and the left-edge flag into the word (they hold from the take on)."""
        res = r.res
        with m.If(r.busy):
            with m.Switch(r.pc):
                for k, st in enumerate(prog):
                    with m.Case(k):
                        nxt = [r.pc.eq(k + 1)] if k + 1 < len(prog) else [r.busy.eq(0), r.out.eq(1)]
                        if st[0] == "mul":
                            self._product(m, r, st, nxt)
                        elif st[0] == "recip":
                            self._reciprocal(m, r, k, st[1], nxt)
                        else:
                            self._multiply_round(m, r, k, st, nxt)
            m.d.sync += [res.ll.eq(r.den > 0), res.xa.eq(r.X[0]), res.ya.eq(r.Y[0]), res.xb.eq(r.X[1]),
                         res.yb.eq(r.Y[1]), res.za.eq(r.Z[0]), res.zb.eq(r.Z[1]), res.ia.eq(r.Iv[0]),
                         res.ib.eq(r.Iv[1])]

    @staticmethod
    def _product(m, r, st, nxt):
        """One of eq. (3)'s products, "(2)式、(3)式はいずれも三角形の各頂点の輝度が与えられた時点での
        計算できる定数値である" (seed 000, 2.3): ``acc = a b`` (``first``), else ``dst = acc - a b``."""
        _, a, b, dst, first = st
        m.d.comb += [r.ma.eq(a), r.mb.eq(b)]
        with r.limbs(*LIMBS["mul"]):
            if first:
                m.d.sync += r.acc.eq(r.prod)
            else:
                m.d.sync += dst.eq(r.acc - r.prod)
            m.d.sync += nxt

    @staticmethod
    def _reciprocal(m, r, k, d, nxt):
        """The reciprocal of ``d`` from the ROM, "乗算器、および逆数表(ROMによる)を装備した" (seed 000,
        3.2): ``|d|`` normalised to its 16-bit mantissa, ROM word + 1 and the remainder (one
        multiply); then one ALU cycle per correction and one to finish (``formats.rom_div``)."""
        rp, R, e = r.rp, r.R, r.e
        ad = Signal(unsigned(40), name=f"abs_{k}")
        m.d.comb += ad.eq(Mux(d < 0, -d, d))
        with m.If(~r.corr):
            # normalise |d| to its 16-bit mantissa, ROM word + 1, remainder (one multiply)
            bl = Signal(range(41), name=f"bl_{k}")
            for b_ in range(40):
                with m.If(ad[b_]):
                    m.d.comb += bl.eq(b_ + 1)
            mant = Signal(unsigned(WORD), name=f"mant_{k}")
            shr, shl = Signal(6, name=f"shr_{k}"), Signal(6, name=f"shl_{k}")
            m.d.comb += [shr.eq(bl - WORD), shl.eq(WORD - bl),
                         mant.eq(Mux(bl > WORD, ad >> shr, ad << shl))]
            rc = Signal(unsigned(18), name=f"rc_{k}")
            m.d.comb += [rp.addr.eq(mant[:ROM_INDEX_BITS]), rc.eq(rp.data + 1),
                         r.ma.eq(ad), r.mb.eq(rc)]
            sv = Signal(unsigned(6), name=f"s_{k}")
            m.d.comb += sv.eq(WORD - 1 + bl)
            with r.limbs(*LIMBS["recip_den" if d is r.den else "recip"]):
                m.d.sync += [r.S.eq(sv), r.dneg.eq(d < 0), r.dabs.eq(ad), r.dz.eq(ad == 0), r.corr.eq(1)]
                with m.If(ad == 0):
                    m.d.sync += [R.eq(0), e.eq(0)]
                with m.Else():
                    m.d.sync += [R.eq(rc), e.eq((Const(1, 72) << sv) + (ad >> 1) - r.prod)]
        with m.Else():
            with m.If(e < 0):
                m.d.sync += [R.eq(R - 1), e.eq(e + r.dabs)]
            with m.Else():
                m.d.sync += [R.eq(Mux(R > (1 << WORD) - 1, (1 << WORD) - 1, R)), r.corr.eq(0), *nxt]

    @staticmethod
    def _multiply_round(m, r, k, st, nxt):
        """An increment, a slope or eq. (3)'s quotient: ``num`` times the last reciprocal, rounded
        (``(|num| R << shift + 2**(S-1)) >> S`` with the sign), into the word's ``field``: whole
        (``int``), saturated to 16 bits (``sat``), or, for dy/dx of a horizontal edge, the largest
        word (``satq``)."""
        _, num, shift, field, kind = st
        an = Signal(unsigned(40), name=f"an_{k}")
        m.d.comb += [an.eq(Mux(num < 0, -num, num)), r.ma.eq(an), r.mb.eq(r.R)]
        q = Signal(unsigned(72), name=f"q_{k}")
        m.d.comb += q.eq(((r.prod.as_unsigned() << shift) + (Const(1, 72) << r.s1)) >> r.S)
        v = Signal(signed(73), name=f"v_{k}")
        m.d.comb += v.eq(Mux((num < 0) ^ r.dneg, -q, q))
        tgt = getattr(r.res, field)
        with r.limbs(*LIMBS["md_plane" if num is r.nz or num is r.ni else "md"]):
            if kind == "int":
                m.d.sync += tgt.eq(v)
            elif kind == "sat":
                m.d.sync += tgt.eq(_sat16(v))
            else:
                m.d.sync += tgt.eq(Mux(r.dz, (1 << (WORD - 1)) - 1, _sat16(v)))
            m.d.sync += nxt

    def _word_out(self, m, r):
        """The word out, to the SLP's list work (``hdl/experts/slp.py``'s input word)."""
        with m.If(r.out):
            m.d.comb += self.o.valid.eq(1)
            with m.If(self.o.ready):
                m.d.sync += r.out.eq(0)


class _Triangle:
    """The set-up's registers and datapath signals, which every step reads and writes (one
    sequencer's steps in turn: see the module's docstring)."""


def _sat16(v):
    top = 1 << (WORD - 1)
    return Mux(v > top - 1, top - 1, Mux(v < -top, -top, v))
