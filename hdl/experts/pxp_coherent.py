"""EXPERTS coherent span PXP (ours): span cull once per segment, depth search only where the visible segment can change.

Paper (seed 000, section 4): the PXP's work is "iv) ... 《span cull》" and "v) ... 《depth search》",
priced at one span cull operation per segment per line and a number of depth searches per line that
grows as sqrt(Fr); section 2.2: "一旦可視セグメントが決定されればその中では一様な計算で各画素の値を
決めることができる (span coherence)" (Watkins [8]). The steps below are ours (the paper gives the terms,
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
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal, signed
from amaranth.lib import enum
from rasterhw.golden_model.experts.formats import WORD, X_END_BITS, XP_BITS
from rasterhw.hdl.experts.pxp_span import (
    NO_PTR,
    Always,
    Early,
    ExpertsPxpSpan,
    GuardedWords,
    candidate,
    guarded_test,
    i_words,
    intensity_at,
    key_words,
    resolve_regs,
    take_bank,
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
        fmt, W, aj, asb, pw, cw, drain = fr["fmt"], fr["W"], fr["aj"], fr["asb"], fr["pw"], fr["cw"], fr["drain"]
        brd, full = fr["brd"], fr["full"]
        vrd = fr["dmm"].read_port(domain="comb")    # the visible segment S

        state = Signal(_R)
        (rb, glo, ghi, lo, hi, n, nb, i, j, bi, pp, S, skey, saddr, cyc, raddr, seg, c0, a, e, awr, ard, in_bkt,
         cand) = resolve_regs(m, fr)
        na = Signal(cw)           # entries on the active list
        sl = Signal(X_END_BITS)           # the span's left pixel x; in WRITE the write cursor
        sr = Signal(X_END_BITS)           # PASSB: the span searched ends at sr; WRITE: the last pixel written
        ns = Signal(XP_BITS)           # the next start (or ghi)
        vu = Signal(XP_BITS)           # S is nearest up to pixel vu
        vok = Signal()            # a segment is visible (S)
        fail = Signal()           # an entering segment failed its test against S
        send = Signal(signed(XP_BITS))  # S's last pixel in the guarded range

        vseg = Signal(asb)
        m.d.comb += [vrd.addr.eq((rb << pw) | S), vseg.eq(vrd.data)]

        # the test's right end: min(vu (ENTER) / sr (PASSB), the segment's last pixel)
        rt = Signal(XP_BITS)
        rbx = Signal(XP_BITS)
        m.d.comb += [rt.eq(Mux(state == _R.PASSB, sr, vu)), rbx.eq(Mux(e < rt, e, rt))]
        paper = self._datapath == "paper"
        if paper:
            ph = Signal(3)            # the cycle within a step
            pe = Signal(3)            # its phase (class docstring): ENTER from 0, PASSB from 2, PASSA from 4
            m.d.comb += pe.eq(ph + Mux(state == _R.PASSB, 2, Mux(state == _R.PASSA, 4, 0)))
            mseg = Signal(fr["asb"])  # the multiplier's segment: the visible one (and the write's), else the entry
            m.d.comb += mseg.eq(Mux(~pe[2], vseg.as_value(), seg.as_value()))
            szl, szr, zlr = Signal(signed(2 * WORD)), Signal(signed(2 * WORD)), Signal(signed(2 * WORD))
            zpl = Signal(WORD)          # the entry's z at rbx, low word
            zc = Signal()             # the low word's carry
            ilo = Signal(WORD)          # i at sl, low word
            zadd = word_adder(m, fr, seg=mseg, col=Mux(pe[1], rbx, sl), write=lambda: state == _R.WRITE,
                              hi_word=pe[0], zc=zc)
            tests = GuardedWords(m, szl, szr, zlr, zadd[:WORD])
            zx = Signal(signed(2 * WORD))   # PASSA: the entry's z at sl, this cycle's high word
            m.d.comb += zx.eq(Cat(zlr[:WORD], zadd[:WORD]))
            key = key_words(m, zx)
            good = Signal()
            m.d.comb += good.eq(tests.high(vseg.addr < seg.addr))
            ic = i_words(m, zadd[:WORD], ilo, fmt)

            def phases(cond):
                """The step's early cycles where ``cond`` (each stores its word, ``ph`` advances);
                else its own cycle, ``ph`` back to 0."""
                def early():
                    m.d.sync += ph.eq(ph + 1)
                    with m.Switch(pe):
                        for k, reg in enumerate((szl, szr, zlr)):
                            with m.Case(2 * k):
                                m.d.sync += [reg[:WORD].eq(zadd[:WORD]), zc.eq(zadd[WORD])]
                            with m.Case(2 * k + 1):
                                m.d.sync += reg[WORD:].eq(zadd[:WORD])
                        with m.Case(6):
                            m.d.sync += [zpl.eq(zadd[:WORD]), zc.eq(zadd[WORD]), *tests.low()]
                return Early(m, cond, early, [ph.eq(0)])
        else:
            zl_ = zrun_at(m, seg, sl)
            zr_ = zrun_at(m, seg, rbx)
            zsl = zrun_at(m, vseg, sl)
            zsr = zrun_at(m, vseg, rbx)
            good = Signal()
            m.d.comb += good.eq(guarded_test(m, zsl, zsr, zl_, zr_, vseg.addr < seg.addr))
            key = z_key(m, zl_)

            def phases(cond):
                return Always()
        nearer = Signal()
        m.d.comb += nearer.eq((j == 0) | (key < skey) | ((key == skey) & (seg.addr < saddr)))
        mid = Signal(X_END_BITS)
        m.d.comb += mid.eq((sl + sr + 1) >> 1)
        if not paper:
            ic = intensity_at(m, vseg, sl, fmt)


        def write(last):
            """Decided: write ``[sl, last]``."""
            return [sr.eq(last), state.eq(_R.WRITE)]

        def decided(r):
            """S is nearest over ``[sl, r]``: write up to ``min(r, ns - 1)``."""
            return [vok.eq(1), vu.eq(r), *write(Mux(r < ns - 1, r, ns - 1))]

        with self._hold(m, state, drain, _R.IDLE, _R.HAND), m.Switch(state):
            with m.Case(_R.IDLE):
                m.d.sync += cyc.eq(1)
                tb = take_bank(m, fr, rb, W, aj)
                with m.If(full.bit_select(rb, 1)):
                    m.d.sync += [lo.eq(tb["lo"]), hi.eq(tb["hi"]), glo.eq(tb["glo"]), ghi.eq(tb["ghi"]),
                                 sl.eq(tb["glo"]), n.eq(tb["n"]), nb.eq(tb["nb"]),
                                 pp.eq(Mux(tb["lead"] == NO_PTR, tb["n"], tb["lead"])),
                                 na.eq(0), bi.eq(0), vok.eq(0), fail.eq(0),
                                 state.eq(Mux(tb["ghi"] <= tb["glo"], _R.HAND, _R.ENTER))]
            with m.Case(_R.ENTER):
                take = candidate(m, raddr=raddr, cand=cand, in_bkt=in_bkt, brd=brd, bi=bi, pp=pp, n=n,
                                 c0=c0, ghi=ghi)
                # (paper) an entering segment tested against the visible one: 8 cycles
                etest = cand & (a == sl) & (a <= e) & vok & (vu >= sl)
                with phases(etest & (ph != 7) if paper else None):
                    with m.If(cand & ((e < a) | (a == sl))):
                        with m.If(a <= e):
                            m.d.comb += [awr.en.eq(1), awr.addr.eq(na), awr.data.eq(raddr)]
                            m.d.sync += na.eq(na + 1)
                            with m.If(vok & (vu >= sl) & ~good):
                                m.d.sync += fail.eq(1)
                        take()
                    with m.Else():
                        nxt = Signal(XP_BITS)
                        m.d.comb += nxt.eq(Mux(cand, a, ghi))
                        m.d.sync += [ns.eq(nxt), i.eq(0), j.eq(0), fail.eq(0)]
                        with m.If(fail | ~vok | (sl > vu)):
                            with m.If(na == 0):
                                m.d.sync += [vok.eq(0), vu.eq(nxt - 1), *write(nxt - 1)]
                            with m.Else():
                                m.d.sync += state.eq(_R.PASSA)
                        with m.Else():
                            m.d.sync += write(Mux(vu < nxt - 1, vu, nxt - 1))
            with m.Case(_R.PASSA), phases((e >= sl) & (ph == 0) if paper else None):
                kept = Signal(cw)
                se = Signal(signed(XP_BITS))
                m.d.comb += [kept.eq(j), se.eq(send)]
                with m.If(e >= sl):
                    m.d.comb += [awr.en.eq(1), awr.data.eq(raddr), kept.eq(j + 1)]
                    m.d.sync += j.eq(j + 1)
                    with m.If(nearer):
                        m.d.comb += se.eq(e)
                        m.d.sync += [S.eq(raddr), skey.eq(key), saddr.eq(seg.addr), send.eq(e)]
                        if paper:
                            m.d.sync += szl.eq(zx)
                m.d.sync += i.eq(i + 1)
                with m.If(i + 1 >= na):
                    m.d.sync += [na.eq(kept), i.eq(0)]
                    with m.If(kept == 0):
                        m.d.sync += [vok.eq(0), vu.eq(ns - 1), *write(ns - 1)]
                    with m.Elif((kept >= 2) & (se > sl)):
                        m.d.sync += [sr.eq(se), state.eq(_R.PASSB)]
                    with m.Else():
                        m.d.sync += decided(se)
            with m.Case(_R.PASSB), phases(ph != 5 if paper else None):
                with m.If(good | (raddr == S)):
                    m.d.sync += i.eq(i + 1)
                    with m.If(i + 1 >= na):
                        m.d.sync += decided(sr)
                with m.Else():
                    m.d.sync += sr.eq(mid - 1)
                    with m.If(mid - 1 == sl):
                        m.d.sync += decided(sl)
            with m.Case(_R.WRITE):
                if paper:       # a drawn pixel: i's low word first (ilo), the write with its high word
                    def ilow():
                        m.d.sync += [ph.eq(1), ilo.eq(zadd[:WORD]), zc.eq(zadd[WORD])]
                    wctx = Early(m, vok & (ph == 0), ilow, [ph.eq(0)])
                else:
                    wctx = Always()
                with wctx:
                    write_pixel(m, fr, rb, sl, ~vok, vseg, ic, S)
                    m.d.sync += sl.eq(sl + 1)
                    with m.If(sl == sr):
                        m.d.sync += state.eq(Mux(sl + 1 >= ghi, _R.HAND, _R.ENTER))
            with m.Case(_R.HAND):
                with m.If(~drain.dbusy):
                    m.d.sync += [*drain.hand(bank=rb, lo=lo, hi=hi, glo=glo, ghi=ghi), rb.eq(~rb), state.eq(_R.IDLE),
                                 self.line_cycles.eq(cyc + 1), self.lines.eq(self.lines + 1)]
        return m
