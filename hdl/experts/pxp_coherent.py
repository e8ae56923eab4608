"""EXPERTS coherent span PXP (ours): span cull once per segment, depth search only where the visible segment can change.

Paper (seed 000, section 4): the PXP's work is "iv) ... 《span cull》" and "v) ... 《depth search》",
priced at one span cull operation per segment per line and a number of depth searches per line that
grows as sqrt(Fr); section 2.2: "一旦可視セグメントが決定されればその中では一様な計算で各画素の値を
決める ... ことができる (この性質を span coherence と呼ぶ)" (Watkins [8]; the seed has its figure 2.3
between the two pieces). The steps below are ours (the paper gives the terms,
not the steps); every term is counted in ``golden_model/experts/coherent.py``, which this block is
cycle-exact against.

The DMM/P, the DSLB and its drain are the span PXP's (``pxp_span.py``: ``dmm_p``, ``take_bank``,
``drain.Drain``); the same DMM/P words in, the same pixel words out. The resolve side keeps the
visible segment ``S`` (``vok``: one is visible) and the last pixel ``vu`` it has been shown nearest to:

* **ENTER** (per span, from ``x = sl``): one cycle per candidate entering at ``x`` (the bucket list
  first, then the ASL from the leading pointer; one with no pixel in the range is skipped in a
  cycle). An entering segment goes onto the active list and is tested against ``S`` over
  ``[x, min(vu, its last pixel)]`` (the guarded end-depth test; four multiplies); a failed test
  asks for a depth search. One more cycle sets the next start ``ns``; then a depth search if a test
  failed, no segment is visible or ``x > vu``, else the write.
* **PASSA** (depth search, one cycle per active entry): an entry that ended before ``x`` leaves
  the list (compacted in place); for the others z at ``x`` and the nearest ``S`` at ``x`` (16-bit key,
  ties to the lower ASB address). ``r = S``'s last pixel. None present: background up to ``ns - 1``.
* **PASSB** (two or more present and ``r > x``), one cycle per test: ``S`` against the entry over
  ``[x, min(r, its last pixel)]``; a pass moves to the next entry, a failure halves ``r`` to
  ``((x + r + 1) >> 1) - 1`` and tests the same entry again (the entries before it passed over the
  longer span, so over the shorter one too); ``r = x`` ends the search. Then ``vu = r``.
* **WRITE**: S.S. and the DSLB word, one pixel per cycle over ``[x, min(vu, ns - 1)]``.

As in the span PXP (``pxp_span.py``, whose docstring gives the paper's words), each step is a
sub-component of the resolve side, emitting its datapath and its states into the one FSM over the
registers they share (:class:`_Visible`): the initial processing (:class:`_Initial`, ``IDLE``),
the span cull's entering (:class:`_Enter`), the depth search with the span cull's drop
(:class:`_DepthSearch`), S.S. and the DSLB write (:class:`_ShadeWrite`) and the hand-over
(``pxp_span.hand_over``), with the multiplier datapath (:class:`_Multiply`). They are not joined by
streams: the PXP is one sequential processor, and its per-line cycles (``coherent.py``) are the
sum of its steps' cycles, which a stream between them would let overlap.
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal, signed
from amaranth.lib import enum
from rasterhw.golden_model.experts.formats import WORD, X_END_BITS, XP_BITS
from rasterhw.hdl.experts.pxp_span import (
    RESOLVE_REGS,
    Always,
    Early,
    ExpertsPxpSpan,
    GuardedWords,
    candidate,
    guarded_test,
    hand_over,
    i_words,
    intensity_at,
    key_words,
    resolve_regs,
    take_line,
    word_adder,
    write_pixel,
    z_key,
    zrun_at,
)
from rasterhw.hdl.params import params

__all__ = ["ExpertsPxpCoherent"]

class _R(enum.Enum, shape=3):
    IDLE = 0      # wait for a full DMM/P bank; start the line
    ENTER = 1     # span cull: one entering candidate per cycle (tested against S), then the next start
    PASSA = 2     # depth search: drop ended entries, nearest at x
    PASSB = 3     # depth search: guarded tests, halving on a failure
    WRITE = 4     # S.S. and DSLB write, one pixel per cycle
    HAND = 5      # hand the DSLB bank to the drain


class _Visible:
    """The resolve side's registers over one line, which every step reads and writes (as the span
    PXP's, ``pxp_span._Resolve``: one processor's steps over its own registers, "DMMははじめとして
    各プロセッサの局所メモリ、内部レジスタ・ファイル等を1語16ビットで構成する", seed 000, 3.2).

    ``state`` (:class:`_R`); the registers both span PXPs declare alike (``pxp_span.resolve_regs``,
    an attribute each); this block's own: entries on the active list ``na``, the span's left pixel
    ``sl`` (in ``WRITE`` the write cursor), ``sr`` (``PASSB``: the span searched ends there;
    ``WRITE``: the last pixel written), the next start ``ns``, the visible segment ``S`` read on its
    own DMM/P port (``vrd`` -> ``vseg``; ``vok``: one is visible) and the last pixel ``vu`` it is
    nearest to, its last pixel ``send``, an entering segment failed its test ``fail``; the test's
    right end ``rbx = min(rt, e)``, ``rt`` being ``vu`` (``ENTER``) or ``sr`` (``PASSB``).
    """

    def __init__(self, m: Module, pxp: ExpertsPxpCoherent, fr: dict):
        cw, pw = fr["cw"], fr["pw"]
        self.paper = pxp._datapath == "paper"
        self.vrd = vrd = fr["dmm"].read_port(domain="comb")    # the visible segment S
        self.state = state = Signal(_R, name="state")
        for key, reg in zip(RESOLVE_REGS, resolve_regs(m, fr), strict=True):
            setattr(self, key, reg)
        self.na = Signal(cw, name="na")
        self.sl = Signal(X_END_BITS, name="sl")
        self.sr = Signal(X_END_BITS, name="sr")
        self.ns = Signal(XP_BITS, name="ns")
        self.vu = Signal(XP_BITS, name="vu")
        self.vok = Signal(name="vok")
        self.fail = Signal(name="fail")
        self.send = Signal(signed(XP_BITS), name="send")
        self.vseg = Signal(fr["asb"], name="vseg")
        m.d.comb += [vrd.addr.eq((self.rb << pw) | self.S), self.vseg.eq(vrd.data)]
        # the test's right end: min(vu (ENTER) / sr (PASSB), the segment's last pixel)
        self.rt = rt = Signal(XP_BITS, name="rt")
        self.rbx = rbx = Signal(XP_BITS, name="rbx")
        m.d.comb += [rt.eq(Mux(state == _R.PASSB, self.sr, self.vu)), rbx.eq(Mux(self.e < rt, self.e, rt))]

    def write(self, last):
        """Decided: write ``[sl, last]``."""
        return [self.sr.eq(last), self.state.eq(_R.WRITE)]

    def decided(self, r):
        """S is nearest over ``[sl, r]``: write up to ``min(r, ns - 1)``."""
        return [self.vok.eq(1), self.vu.eq(r), *self.write(Mux(r < self.ns - 1, r, self.ns - 1))]


class _Multiply:
    """The PXP's multiplier ("PXPにおいても、担当の画面領域の初期処理、及び、A.J.における画素データ値の
    混合計算など、乗算が多数出現するため、SLP同様、乗算器を装備している", seed 000, 3.2) and the guarded
    test it feeds: ``good`` (the visible segment stays nearest against the entry read, ``seg``, over
    ``[sl, rbx]``), ``key`` (the entry's compare key at ``sl``) and (the paper's datapath) ``ic``.

    Ours: four z multipliers (the entry and the visible segment, each at ``sl`` and ``rbx``). The
    paper's datapath: the span PXP's one multiplier and 16-bit adder (``pxp_span.word_adder``), one
    product a cycle in the order of the phase ``pe`` (the class docstring of
    :class:`ExpertsPxpCoherent`), each step's early cycles added by :meth:`phases`; i at ``sl`` in
    two words for the write.
    """

    def __init__(self, m: Module, fr: dict, v: _Visible):
        self.m, self.v = m, v
        state, sl, seg, vseg, rbx = v.state, v.sl, v.seg, v.vseg, v.rbx
        if v.paper:
            ph = Signal(3)            # the cycle within a step
            pe = Signal(3)            # its phase (class docstring): ENTER from 0, PASSB from 2, PASSA from 4
            m.d.comb += pe.eq(ph + Mux(state == _R.PASSB, 2, Mux(state == _R.PASSA, 4, 0)))
            mseg = Signal(fr["asb"])  # the multiplier's segment: the visible one (and the write's), else the entry
            m.d.comb += mseg.eq(Mux(~pe[2], vseg.as_value(), seg.as_value()))
            # z in two words: the visible segment's at sl and at rbx, the entry's at sl (left unnamed, as
            # they were in the netlist before this block was split: no wire renamed)
            szl, szr, zlr = (Signal(signed(2 * WORD)) for _ in range(3))
            zpl = Signal(WORD)          # the entry's z at rbx, low word
            zc = Signal()             # the low word's carry
            ilo = Signal(WORD)          # i at sl, low word
            zadd = word_adder(m, fr, seg=mseg, col=Mux(pe[1], rbx, sl), write=lambda: state == _R.WRITE,
                              hi_word=pe[0], zc=zc)
            tests = GuardedWords(m, szl, szr, zlr, zadd[:WORD])
            zx = Signal(signed(2 * WORD))   # PASSA: the entry's z at sl, this cycle's high word
            m.d.comb += zx.eq(Cat(zlr[:WORD], zadd[:WORD]))
            self.key = key_words(m, zx)
            good = Signal()
            m.d.comb += good.eq(tests.high(vseg.addr < seg.addr))
            self.ic = i_words(m, zadd[:WORD], ilo, fr["fmt"])
            self.ph, self.pe, self.szl, self.szr, self.zlr, self.zpl, self.zc = ph, pe, szl, szr, zlr, zpl, zc
            self.ilo, self.zadd, self.tests, self.zx = ilo, zadd, tests, zx
        else:
            zl_ = zrun_at(m, seg, sl)
            zr_ = zrun_at(m, seg, rbx)
            zsl = zrun_at(m, vseg, sl)
            zsr = zrun_at(m, vseg, rbx)
            good = Signal()
            m.d.comb += good.eq(guarded_test(m, zsl, zsr, zl_, zr_, vseg.addr < seg.addr))
            self.key = z_key(m, zl_)
            self.ic = None              # ours: the write's own multiplier (_ShadeWrite)
        self.good = good

    def phases(self, cond):
        """(paper) The step's early cycles where ``cond`` (each stores its word, ``ph`` advances);
        else its own cycle, ``ph`` back to 0. Ours: a context that adds nothing."""
        if not self.v.paper:
            return Always()
        m, ph, zadd, zc = self.m, self.ph, self.zadd, self.zc

        def early():
            m.d.sync += ph.eq(ph + 1)
            with m.Switch(self.pe):
                for k, reg in enumerate((self.szl, self.szr, self.zlr)):
                    with m.Case(2 * k):
                        m.d.sync += [reg[:WORD].eq(zadd[:WORD]), zc.eq(zadd[WORD])]
                    with m.Case(2 * k + 1):
                        m.d.sync += reg[WORD:].eq(zadd[:WORD])
                with m.Case(6):
                    m.d.sync += [self.zpl.eq(zadd[:WORD]), zc.eq(zadd[WORD]), *self.tests.low()]
        return Early(m, cond, early, [ph.eq(0)])


class _Initial:
    """The PXP's **initial processing** of a line ("初期処理", seed 000, 3.2), state ``IDLE``: as the
    span PXP's (``pxp_span._Initial``, ``pxp_span.take_line``), one cycle takes a full DMM/P bank; the first ``ENTER`` then
    reads the bucket list and the ASL from the leading pointer ("PXPでの初期処理によるオーバヘッドを
    軽減するために、図3.2に示すBlock Boundary Bucket List、およびBlock Leading Segment Pointer"). No
    segment is visible yet (``vok`` 0), so the first span searches.
    """

    def __init__(self, m: Module, fr: dict, v: _Visible):
        self.m, self.fr, self.v = m, fr, v

    def states(self):
        v = self.v
        with self.m.Case(_R.IDLE):
            take_line(self.m, self.fr, v, v.sl, lambda tb: [v.na.eq(0), v.bi.eq(0), v.vok.eq(0), v.fail.eq(0)],
                      hand=_R.HAND, enter=_R.ENTER)


class _Enter:
    """iv) **span cull**, its entering half: "スキャン・ラインをスパンに分割し、そのスパン内に現われる範囲
    のセグメントを抽出する《span cull》" (seed 000, section 4, iv); the leaving half is the drop in
    :class:`_DepthSearch` (``coherent.TERMS``: span cull = enter + drop).

    State ``ENTER`` (ours): one cycle per candidate entering at ``sl`` (``pxp_span.candidate``; one
    with no pixel in the range is skipped in a cycle); an entering segment goes onto the active list
    and is tested against the visible one over ``[sl, min(vu, its last pixel)]`` (``good``, eight
    cycles at the paper's datapath); a failed test asks for a depth search. One more cycle sets the
    next start ``ns``: then a depth search if a test failed, none is visible or ``sl > vu``, else
    the write (span coherence: "一旦可視セグメントが決定されればその中では一様な計算で各画素の値を決める",
    2.2).
    """

    def __init__(self, m: Module, fr: dict, v: _Visible, mul: _Multiply):
        self.m, self.fr, self.v, self.mul = m, fr, v, mul

    def states(self):
        m, v, mul = self.m, self.v, self.mul
        sl, na, cand, a, e, vok, vu = v.sl, v.na, v.cand, v.a, v.e, v.vok, v.vu
        with m.Case(_R.ENTER):
            take = candidate(m, raddr=v.raddr, cand=cand, in_bkt=v.in_bkt, brd=self.fr["brd"], bi=v.bi, pp=v.pp,
                             n=v.n, c0=v.c0, ghi=v.ghi)
            # (paper) an entering segment tested against the visible one: 8 cycles
            etest = cand & (a == sl) & (a <= e) & vok & (vu >= sl)
            with mul.phases(etest & (mul.ph != 7) if v.paper else None):
                with m.If(cand & ((e < a) | (a == sl))):
                    with m.If(a <= e):
                        m.d.comb += [v.awr.en.eq(1), v.awr.addr.eq(na), v.awr.data.eq(v.raddr)]
                        m.d.sync += na.eq(na + 1)
                        with m.If(vok & (vu >= sl) & ~mul.good):
                            m.d.sync += v.fail.eq(1)
                    take()
                with m.Else():
                    nxt = Signal(XP_BITS)
                    m.d.comb += nxt.eq(Mux(cand, a, v.ghi))
                    m.d.sync += [v.ns.eq(nxt), v.i.eq(0), v.j.eq(0), v.fail.eq(0)]
                    with m.If(v.fail | ~vok | (sl > vu)):
                        with m.If(na == 0):
                            m.d.sync += [vok.eq(0), vu.eq(nxt - 1), *v.write(nxt - 1)]
                        with m.Else():
                            m.d.sync += v.state.eq(_R.PASSA)
                    with m.Else():
                        m.d.sync += v.write(Mux(vu < nxt - 1, vu, nxt - 1))


class _DepthSearch:
    """v) **depth search**: "iv)で抽出したセグメントに応じてデプス・サーチを行ない、可視セグメントを決定する
    《depth search》" (seed 000, section 4, v), only where the visible segment can change.

    States ``PASSA`` and ``PASSB`` (ours): pass A, one cycle per active entry: an entry that ended
    before ``sl`` leaves the list (compacted in place: the span cull's drop), for the others z at
    ``sl`` and the nearest (``nearer``: 16-bit key, ties to the lower ASB address); none present:
    background up to ``ns - 1``. Pass B (two or more present and the nearest reaches past ``sl``),
    one cycle per test: the nearest against the entry over ``[sl, min(sr, its last pixel)]``; a
    pass moves to the next entry, a failure halves ``sr`` to ``mid - 1`` and tests the same entry
    again; ``sr = sl`` ends the search.
    """

    def __init__(self, m: Module, fr: dict, v: _Visible, mul: _Multiply):
        self.m, self.v, self.mul, self.cw = m, v, mul, fr["cw"]
        self.nearer = nearer = Signal(name="nearer")
        m.d.comb += nearer.eq((v.j == 0) | (mul.key < v.skey) | ((mul.key == v.skey) & (v.seg.addr < v.saddr)))
        self.mid = mid = Signal(X_END_BITS, name="mid")
        m.d.comb += mid.eq((v.sl + v.sr + 1) >> 1)

    def states(self):
        m, v, mul = self.m, self.v, self.mul
        i, j, sl, sr, e, send, na = v.i, v.j, v.sl, v.sr, v.e, v.send, v.na
        paper = v.paper
        with m.Case(_R.PASSA), mul.phases((e >= sl) & (mul.ph == 0) if paper else None):
            kept = Signal(self.cw)
            se = Signal(signed(XP_BITS))
            m.d.comb += [kept.eq(j), se.eq(send)]
            with m.If(e >= sl):
                m.d.comb += [v.awr.en.eq(1), v.awr.data.eq(v.raddr), kept.eq(j + 1)]
                m.d.sync += j.eq(j + 1)
                with m.If(self.nearer):
                    m.d.comb += se.eq(e)
                    m.d.sync += [v.S.eq(v.raddr), v.skey.eq(mul.key), v.saddr.eq(v.seg.addr), send.eq(e)]
                    if paper:
                        m.d.sync += mul.szl.eq(mul.zx)
            m.d.sync += i.eq(i + 1)
            with m.If(i + 1 >= na):
                m.d.sync += [na.eq(kept), i.eq(0)]
                with m.If(kept == 0):
                    m.d.sync += [v.vok.eq(0), v.vu.eq(v.ns - 1), *v.write(v.ns - 1)]
                with m.Elif((kept >= 2) & (se > sl)):
                    m.d.sync += [sr.eq(se), v.state.eq(_R.PASSB)]
                with m.Else():
                    m.d.sync += v.decided(se)
        with m.Case(_R.PASSB), mul.phases(mul.ph != 5 if paper else None):
            with m.If(mul.good | (v.raddr == v.S)):
                m.d.sync += i.eq(i + 1)
                with m.If(i + 1 >= na):
                    m.d.sync += v.decided(sr)
            with m.Else():
                m.d.sync += sr.eq(self.mid - 1)
                with m.If(self.mid - 1 == sl):
                    m.d.sync += v.decided(sl)


class _ShadeWrite:
    """**S.S. and the DSLB write**, state ``WRITE``: "HSEによって可視セグメントが決定した後、直ちに(1)式
    によつてS.S.を開始する事ができる" (seed 000, 2.3). One pixel a cycle over ``[sl, sr]`` (a drawn pixel
    two at the paper's datapath: i's low word first, ``ilo``, the write with its high word), the
    visible segment's intensity by the multiplier at that pixel (ours: its own, made here), the
    DSLB word as the span PXP's (``pxp_span.write_pixel``); then the next span's entering, or the
    hand-over at the range's end.
    """

    def __init__(self, m: Module, fr: dict, v: _Visible, mul: _Multiply):
        self.m, self.fr, self.v, self.mul = m, fr, v, mul
        self.ic = mul.ic if v.paper else intensity_at(m, v.vseg, v.sl, fr["fmt"])

    def states(self):
        m, v, mul = self.m, self.v, self.mul
        with m.Case(_R.WRITE):
            if v.paper:       # a drawn pixel: i's low word first (ilo), the write with its high word
                def ilow():
                    m.d.sync += [mul.ph.eq(1), mul.ilo.eq(mul.zadd[:WORD]), mul.zc.eq(mul.zadd[WORD])]
                wctx = Early(m, v.vok & (mul.ph == 0), ilow, [mul.ph.eq(0)])
            else:
                wctx = Always()
            with wctx:
                write_pixel(m, self.fr, v.rb, v.sl, ~v.vok, v.vseg, self.ic, v.S)
                m.d.sync += v.sl.eq(v.sl + 1)
                with m.If(v.sl == v.sr):
                    m.d.sync += v.state.eq(Mux(v.sl + 1 >= v.ghi, _R.HAND, _R.ENTER))


@params("width", "aj", "depth", "datapath")
class ExpertsPxpCoherent(ExpertsPxpSpan):
    """One coherent span PXP with its DMM/P: DMM/P words in, the range's pixel words out, line by
    line. Parameters (``width``, ``intensity_bits``, ``aj``, ``depth``, ``datapath``), ports (``i``,
    ``o``, ``lo``, ``hi``, ``line_cycles``, ``lines``, ``overflow``), DMM/P, DSLB and drain:
    :class:`hdl.experts.pxp_span.ExpertsPxpSpan`'s (``frame``); the resolve side is this block's.

    ``datapath="paper"``: the span PXP's one 16 x 16 multiplier and 16-bit adder
    (``pxp_span.word_adder``; the drain's A.J. blend has the multiplier first and the resolve side
    holds, ``ExpertsPxpSpan._hold``), z and i in two words a word a cycle, the guarded tests a word a
    cycle (``pxp_span.GuardedWords``). One product a cycle, in the order of the phase ``pe`` (each
    step's first phase below; ``ph`` counts from 0 within the step):

    * ``pe`` 0, 1: the visible segment's z at ``sl`` (``szl``; ENTER's test only: in a depth search
      it is the nearest's, kept from pass A), low word then high;
    * ``pe`` 2, 3: the visible segment's z at the test's right pixel ``rbx`` (``szr``);
    * ``pe`` 4, 5: the entry's z at ``sl`` (``zlr``; pass A ends here: the key and the nearest, with
      ``szl`` taken if it is nearer);
    * ``pe`` 6, 7: the entry's z at ``rbx``: its low word with the six tests' low words, its high
      word with their high words and the test's outcome (the step's own cycle).

    ENTER's test starts at ``pe`` 0 (8 cycles), pass B's at 2 (6 cycles), pass A's on a present
    entry at 4 (2 cycles; an entry dropped takes 1), the write of a drawn pixel 2 (i's low word,
    then the high word and the write; background 1). Counted in ``coherent.paper_resolve``."""

    #: the block has the paper's datapath (``datapath="paper"``: one shared multiplier)
    PAPER_DATAPATH = True

    def __init__(self, *, width: int = 512, intensity_bits: int = 7, aj: str = "none", depth: int = 256,
                 datapath: str = "ours"):
        super().__init__(width=width, intensity_bits=intensity_bits, aj=aj, depth=depth, datapath=datapath)

    def elaborate(self, platform):
        m = Module()
        fr = self.frame(m)
        # the resolve side's registers and datapaths outside the FSM, in this order (the netlist's
        # statement order)
        v = _Visible(m, self, fr)
        mul = _Multiply(m, fr, v)
        search = _DepthSearch(m, fr, v, mul)
        write = _ShadeWrite(m, fr, v, mul)
        # one FSM: the steps' states, each step after the one before it on the same registers
        with self._hold(m, v.state, fr["drain"], _R.IDLE, _R.HAND), m.Switch(v.state):
            _Initial(m, fr, v).states()
            _Enter(m, fr, v, mul).states()
            search.states()
            write.states()
            with m.Case(_R.HAND):
                hand_over(m, self, fr["drain"], v, _R.IDLE)
        return m
