"""EXPERTS span PXP (ours, after the paper's steps): DMM/P bank in, span cull and depth search per span, S.S., A.J. (c), DSLB.

Paper (seed 000, section 4): the PXP's stages are "iv) スキャン・ラインをスパンに分割し、そのスパン内に
現われる範囲のセグメントを抽出する《span cull》" and "v) iv)で抽出したセグメントに応じてデプス・サーチを
行ない、可視セグメントを決定する《depth search》"; visibility is decided per segment ("セグメントという
「広がり」を持った単位で可視/不可視を判定する"), then shaded uniformly along it. Section 3: the SLP writes
the ASL into the DMM/P ("DMM/PはSLPと各PXP間のASL等の授受において、上位プロセッサによる書込みと下位
プロセッサによる読み出しと並行して同時に行なう"), with the block boundary bucket list and the block
leading segment pointer ("PXPでの初期処理によるオーバヘッドを軽減するために ... ASL の附加的な情報").

This block holds its own DMM/P (two banks; the writer fills one while the PXP reads the other):

* **writer** (``i``, :func:`dmm_layout` words): per line, the line's whole ASL in ASL order (``list = 0``,
  stored at the next ASL position), then this PXP's block boundary bucket list (``list = 1``,
  ``ptr`` = an ASL position), then the ``last`` token whose ``ptr`` is the block leading segment
  pointer (``NO_PTR``: none). The range ``lo``/``hi`` is sampled with the token. A bank is written
  only when free (released when the DSLB drain has finished that line: the drain's A.J. reads the
  visible segments' edges from it); a line longer than ``depth`` sets ``overflow`` and stalls ``i``.
* **span cull** (per span, starting at ``x = glo``): one cycle per segment of the active list
  (in place: those ending before ``x`` leave, the others stay and give the nearest end), then one
  cycle per candidate entering at ``x`` (the bucket list first, then the ASL from the leading
  pointer while the first pixel is before ``ghi``; a segment with no pixel is skipped in a cycle),
  and one cycle that sets the span's right end ``r = min(nearest end, next start, ghi) - 1``.
* **depth search** (``k >= 2`` segments present): pass A, one cycle per segment: z at the span's two
  end pixels (two multiplies) and the nearest at the left pixel (16-bit key, ties to the lower ASB
  address); pass B (spans wider than a pixel), one cycle per segment: the guarded end-depth test of
  ``golden_model/experts/span.py`` (S stays nearest at every pixel). If a test fails the span is
  halved at ``(l + r + 1) >> 1``, the right half's end pushed on a small stack, and the left half
  searched; ``k = 0`` is background, ``k = 1`` needs no search.
* **S.S. and DSLB write**: one cycle per pixel of a decided (sub)span, the intensity by the
  multiplier at that pixel (equal to stepping), the word ``{ASB address, pixel, ASL position}``.
* **drain** (double-banked DSLB, ``drain.py``): ``2 R`` cycles; with A.J. (c) 2 a guarded pixel, 3
  at a segment's first, plus one at the frame's right edge, the blend reading the visible
  segment's edges from the DMM/P bank by its ASL position. At ``datapath="paper"`` the blend is on
  the PXP's one multiplier (``aj.aj_boundary_shared``: 4 or 5 multiplies a blended pixel, one a
  cycle); the drain has it first and the resolve side holds meanwhile (:meth:`ExpertsPxpSpan._hold`).

**One processor, its steps in sequence.** The paper's PXP is one processor with a multiplier ("PXP
においても ... SLP同様、乗算器を装備している", 3.2) that takes the two stages "iv) v)をPXPに" (section 4)
and, once its initial processing is done, runs on alone to its range's last pixel ("初期処理が終了
した後の処理は、2章で述べたSLAと同じであり、自らの担当範囲の終点となる画素まで、他のPXPとの通信なしに独立
に動作できる", 3.2). Its queues are between processors only: the DMM/P from the SLP ("上位プロセッサ
による書込みと下位プロセッサによる読み出しと並行して同時に行なう") and the DSLB to the frame buffer. So
each step is a sub-component of the resolve side (a class that emits its datapath and its states
into the one FSM) over the registers they share (:class:`_Resolve`): the initial processing
(:class:`_Initial`), the span cull (:class:`_SpanCull`), the depth search (:class:`_DepthSearch`),
S.S. and the DSLB write (:class:`_ShadeWrite`), the hand-over (:func:`hand_over`), with the
multiplier datapath they use (:class:`_Multiply`). They are not joined by streams: a stream
between two steps of one sequential processor would let them overlap, which changes the per-line
cycles ``golden_model/experts/span_cycles.py`` holds (a sum of every step's cycles). The block's
own streams are the paper's queues: ``i`` (the DMM/P's writer) and ``o`` (the DSLB's drain).

At ``datapath="paper"`` the running z and i are **two 16-bit words** (at 512 x 512 ``|z|, |i| < 2**25``,
docs/experts.md "z and i in two words"): one 16-bit adder takes them a word a cycle, the low word
first with its carry kept (``zlr`` z at the left end, ``zpl`` the right end's low word, ``ilo`` i's
low word), the guarded tests subtract the low words in one cycle (borrows and flags kept,
:class:`GuardedWords`) and the high words in the next; the key is the high word's test and wires
(:func:`key_words`), the pixel's intensity the high word's sign against the low word
(:func:`i_words`). Pass A and pass B take 4 cycles a segment, the write 2 a drawn pixel
(``span_cycles.multiword``).

Cycles: ``golden_model/experts/span_cycles.py`` (every term named there). Pixels: the golden bit
model's. The resolve side reads the DMM/P bank, the active list and the stack asynchronously
(one access per cycle each).
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import Out
from rasterhw.golden_model.experts.formats import (
    ADDR_BITS,
    DZ_FRAC,
    WORD,
    X_END_BITS,
    X_FRAC,
    X_INT,
    XP_BITS,
    Z_BITS,
    Formats,
)
from rasterhw.hdl.experts.aj import MUL_IN
from rasterhw.hdl.experts.drain import Drain, check_pxp_params, pxp_members
from rasterhw.hdl.experts.mul16 import sm_mul
from rasterhw.hdl.experts.pxp import RUN_BITS, asb_fields
from rasterhw.hdl.params import params

__all__ = ["ExpertsPxpSpan", "asb_layout", "dmm_layout", "candidate", "dmm_p", "resolve_regs", "seg_ends", "write_pixel", "take_bank", "zrun_at", "z_key", "guarded_test",
           "intensity_at", "PTR_BITS", "NO_PTR", "word_adder", "GuardedWords", "Early", "Always", "i_words",
           "key_words", "hand_over", "take_line"]

NONE = (1 << ADDR_BITS) - 1     # ASB address / polygon number of the background
PTR_BITS = 9                    # ASL position in a DMM/P bank
NO_PTR = (1 << PTR_BITS) - 1    # leading pointer: no segment starts in the range


def dmm_layout() -> data.StructLayout:
    """One DMM/P word as the SLP writes it: an ASB, a bucket-list entry or the end-of-line token."""
    return data.StructLayout({
        "last": unsigned(1),          # end of the line; ptr = block leading segment pointer
        "list": unsigned(1),          # block boundary bucket list entry; ptr = its ASL position
        "ptr": unsigned(PTR_BITS),
        **asb_fields(),
    })


def asb_layout() -> data.StructLayout:
    """The ASB fields of a DMM/P word (without ``last``, ``list``, ``ptr``)."""
    return data.StructLayout(asb_fields())


def dmm_p(m: Module, comp, asb, D: int) -> dict:
    """The DMM/P writer of a span PXP ``comp`` (two banks of ``D`` ASBs and bucket entries), added to
    ``m``: the words of ``comp.i`` (module docstring) into the bank being written. Returns the
    memory ``dmm``, the resolve side's read ports ``srd`` (ASBs) and ``brd`` (bucket list), the banks'
    ``full`` flags and ``clr_full`` (the drain releases a bank), and per bank its ASB count ``bn``,
    bucket count ``bnb``, leading pointer ``blead`` and range ``blo``/``bhi``."""
    pw = (D - 1).bit_length()
    cw = D.bit_length()
    m.submodules.dmm = dmm = Memory(shape=asb, depth=2 << pw, init=[])
    dwr = dmm.write_port()
    srd = dmm.read_port(domain="comb")          # resolve side
    m.submodules.bkt = bkt = Memory(shape=unsigned(PTR_BITS), depth=2 << pw, init=[])
    bwr = bkt.write_port()
    brd = bkt.read_port(domain="comb")
    wbank = Signal()
    wn = Signal(cw)
    wnb = Signal(cw)
    full = Signal(2)
    bn = [Signal(cw, name=f"n{b}") for b in range(2)]
    bnb = [Signal(cw, name=f"nb{b}") for b in range(2)]
    blead = [Signal(PTR_BITS, name=f"lead{b}") for b in range(2)]
    blo = [Signal(X_INT, name=f"lo{b}") for b in range(2)]
    bhi = [Signal(X_END_BITS, name=f"hi{b}") for b in range(2)]
    set_full = Signal(2)
    clr_full = Signal(2)
    wfull = Signal()
    m.d.comb += wfull.eq(full.bit_select(wbank, 1))
    p = comp.i.payload
    fits = Signal()
    m.d.comb += fits.eq(p.last | Mux(p.list, wnb < D, wn < D))
    m.d.comb += [comp.i.ready.eq(~wfull & ~comp.overflow & fits),
                 dwr.en.eq(0), bwr.en.eq(0),
                 dwr.addr.eq((wbank << pw) | wn[:pw]), bwr.addr.eq((wbank << pw) | wnb[:pw]),
                 bwr.data.eq(p.ptr)]
    for name in asb.members:
        m.d.comb += getattr(dwr.data, name).eq(getattr(p, name))
    with m.If(comp.i.valid & ~wfull & ~fits):
        m.d.sync += comp.overflow.eq(1)
    with m.If(comp.i.valid & comp.i.ready):
        with m.If(p.last):
            m.d.sync += [wn.eq(0), wnb.eq(0), wbank.eq(~wbank)]
            for b in range(2):
                with m.If(wbank == b):
                    m.d.comb += set_full.eq(1 << b)
                    m.d.sync += [bn[b].eq(wn), bnb[b].eq(wnb), blead[b].eq(p.ptr),
                                 blo[b].eq(comp.lo), bhi[b].eq(comp.hi)]
        with m.Elif(p.list):
            m.d.comb += bwr.en.eq(1)
            m.d.sync += wnb.eq(wnb + 1)
        with m.Else():
            m.d.comb += dwr.en.eq(1)
            m.d.sync += wn.eq(wn + 1)
    m.d.sync += full.eq((full | set_full) & ~clr_full)
    return {"dmm": dmm, "srd": srd, "brd": brd, "full": full, "clr_full": clr_full, "bn": bn, "bnb": bnb,
            "blead": blead, "blo": blo, "bhi": bhi}


def take_bank(m: Module, dm: dict, rb, W: int, aj: bool) -> dict:
    """Bank ``rb`` of :func:`dmm_p` as the resolve side takes it: its range ``lo``/``hi``, the
    guarded range ``glo``/``ghi`` (one guard pixel each side with A.J., within the frame), the ASB
    count ``n``, bucket count ``nb`` and leading pointer ``lead``."""
    lo_b, hi_b = Signal(X_INT), Signal(X_END_BITS)
    glo_b, ghi_b = Signal(X_END_BITS), Signal(X_END_BITS)
    m.d.comb += [lo_b.eq(Mux(rb, dm["blo"][1], dm["blo"][0])), hi_b.eq(Mux(rb, dm["bhi"][1], dm["bhi"][0]))]
    if aj:
        m.d.comb += [glo_b.eq(Mux(lo_b > 0, lo_b - 1, 0)), ghi_b.eq(Mux(hi_b < W, hi_b + 1, hi_b))]
    else:
        m.d.comb += [glo_b.eq(lo_b), ghi_b.eq(hi_b)]
    return {"lo": lo_b, "hi": hi_b, "glo": glo_b, "ghi": ghi_b, "lead": Mux(rb, dm["blead"][1], dm["blead"][0]),
            "n": Mux(rb, dm["bn"][1], dm["bn"][0]), "nb": Mux(rb, dm["bnb"][1], dm["bnb"][0])}


def zrun_at(m: Module, seg, col):
    """A multiplier: the running z (Q16.4) of ASB ``seg`` at pixel ``col`` (``span_cycles._zrun``)."""
    d = Signal(signed(20), name="d_z")
    z = Signal(signed(RUN_BITS), name="zrun")
    m.d.comb += [d.eq((col << X_FRAC) + (1 << (X_FRAC - 1)) - seg.xl),
                 z.eq((seg.zl << DZ_FRAC) + ((d * seg.dzdx) >> X_FRAC))]
    return z


def seg_ends(m: Module, seg, glo, ghi) -> tuple[Signal, Signal, Signal]:
    """ASB ``seg``'s first pixel ``c0`` (``(xl + 31) >> 6``, the top-left rule) and its first and
    last pixel ``a``, ``e`` in the guarded range ``[glo, ghi)`` (``e < a``: none there)."""
    c0, c1 = Signal(signed(XP_BITS), name="c0"), Signal(signed(XP_BITS), name="c1")
    a, e = Signal(signed(XP_BITS), name="a"), Signal(signed(XP_BITS), name="e")
    m.d.comb += [c0.eq((seg.xl + 31) >> X_FRAC), c1.eq(((seg.xr + 31) >> X_FRAC) - 1),
                 a.eq(Mux(c0 > glo, c0, glo)), e.eq(Mux(c1 < ghi - 1, c1, ghi - 1))]
    return c0, a, e


def candidate(m: Module, *, raddr, cand, in_bkt, brd, bi, pp, n, c0, ghi):
    """The entering candidate read this cycle (``raddr``): the next bucket list entry, else the ASL
    position ``pp`` of the walk from the leading pointer while its first pixel ``c0`` is before
    ``ghi`` (``cand``: there is one). Returns ``take()``: the sync statements that move past it."""
    with m.If(in_bkt):
        m.d.comb += raddr.eq(brd.data)
    with m.Else():
        m.d.comb += raddr.eq(pp)
    m.d.comb += cand.eq(in_bkt | ((pp < n) & (c0 < ghi)))

    def take():
        with m.If(in_bkt):
            m.d.sync += bi.eq(bi + 1)
        with m.Else():
            m.d.sync += pp.eq(pp + 1)
    return take


def z_key(m: Module, zrun) -> Signal:
    """The 16-bit compare key of a running z: ``zrun >> DZ_FRAC`` clamped to ``0 .. 2**Z_BITS - 1``."""
    zk = Signal(signed(RUN_BITS), name="zk")
    key = Signal(Z_BITS, name="key")
    m.d.comb += [zk.eq(zrun >> DZ_FRAC), key.eq(Mux(zk < 0, 0, Mux(zk > (1 << Z_BITS) - 1, (1 << Z_BITS) - 1, zk)))]
    return key


def guarded_test(m: Module, zsl, zsr, zbl, zbr, s_lower) -> Signal:
    """The guarded end-depth test of ``golden_model/experts/span.py`` (``_stays_nearest``, bit
    model): S (running z ``zsl``/``zsr`` at the two end pixels) nearer than B (``zbl``/``zbr``) at
    every pixel between; ``s_lower``: S has the lower ASB address (ties go to S)."""
    g = 1 << DZ_FRAC
    zmax_run = ((1 << Z_BITS) - 1) << DZ_FRAC
    lower, higher, good = Signal(name="lower"), Signal(name="higher"), Signal(name="good_t")
    m.d.comb += [lower.eq((zsl <= zbl) & (zsr <= zbr)),
                 higher.eq((zsl + g <= zbl) & (zsr + g <= zbr) & (zbl >= g) & (zbr >= g)
                           & (zsl < zmax_run) & (zsr < zmax_run)),
                 good.eq(Mux(s_lower, lower, higher))]
    return good


def intensity_at(m: Module, seg, col, fmt: Formats) -> Signal:
    """S.S.: the intensity of ASB ``seg`` at pixel ``col`` by the multiplier, clamped (Q.i_frac)."""
    di = Signal(signed(20), name="di")
    m.d.comb += di.eq((col << X_FRAC) + (1 << (X_FRAC - 1)) - seg.xl)
    return clamp_i(m, seg.il + ((di * seg.didx) >> X_FRAC), fmt)


def clamp_i(m: Module, run, fmt: Formats) -> Signal:
    """A running intensity ``run`` (Q.i_frac) clamped to ``0 .. i_max`` as the pixel takes it."""
    irun = Signal(signed(RUN_BITS), name="irun")
    imax = fmt.i_max << fmt.i_frac
    ic = Signal(WORD, name="ic")
    m.d.comb += [irun.eq(run), ic.eq(Mux(irun < 0, 0, Mux(irun > imax, imax, irun)))]
    return ic


def i_words(m: Module, hi, lo, fmt: Formats) -> Signal:
    """(paper) The pixel's intensity from a two-word ``i = hi * 2**16 + lo`` (``hi`` signed, this
    cycle's high word; ``lo`` the low word kept), clamped to ``0 .. i_max`` (Q.i_frac) as
    :func:`clamp_i` does: a negative high word gives 0, a positive one the top, else the low word
    against the top (one-word tests)."""
    imax = fmt.i_max << fmt.i_frac
    h = Signal(signed(WORD), name="i_hi")
    ic = Signal(WORD, name="ic_w")
    m.d.comb += [h.eq(hi), ic.eq(Mux(h < 0, 0, Mux((h > 0) | (lo > imax), imax, lo)))]
    return ic


def key_words(m: Module, z) -> Signal:
    """(paper) :func:`z_key` of a two-word running z (``signed(32)``): the sign, and the high word's
    bits above Q16.4, pick 0 or the top; else the key is the Q16.4 integer bits (wires)."""
    key = Signal(Z_BITS, name="key_w")
    top = Z_BITS + DZ_FRAC
    m.d.comb += key.eq(Mux(z[2 * WORD - 1], 0, Mux(z[top:2 * WORD] != 0, (1 << Z_BITS) - 1, z[DZ_FRAC:top])))
    return key


def word_adder(m: Module, fr: dict, *, seg, col, write, hi_word, zc) -> Signal:
    """(paper) The resolve side's half of the PXP's one 16 x 16 multiplier (:meth:`ExpertsPxpSpan.frame`'s
    ``mul``) and its one 16-bit adder, added to ``m``: the product ``d * dz/dx`` (``d * di/dx`` where
    ``write()``) of ASB ``seg`` at pixel ``col`` (``d = 64 col + 32 - xL``, the drain's A.J. blend
    having the multiplier first, ``drain.mreq``), and the adder's 17-bit sum ``z_L * 16 + (product
    >> 6)`` (``i_L + (product >> 6)``) a word a cycle: the low word, or where ``hi_word`` the high
    word with the low word's carry ``zc`` (the product's words are its wires). Returns the sum."""
    d = Signal(MUL_IN, name="d")
    m.d.comb += d.eq((col << X_FRAC) + (1 << (X_FRAC - 1)) - seg.xl)
    # the drain's A.J. blend has the multiplier first (drain.mreq); the resolve side then holds
    mul, dr = fr["mul"], fr["drain"]
    req = dr.mreq if dr.mreq is not None else 0
    m.d.comb += [mul["a"].eq(Mux(req, dr.mul_a if dr.mul_a is not None else 0, d)),
                 mul["b"].eq(Mux(req, dr.mul_b if dr.mul_b is not None else 0,
                                 Mux(write(), seg.didx, seg.dzdx)))]
    prod = mul["p"]
    p_hi = Signal(signed(WORD), name="p_hi")
    m.d.comb += p_hi.eq(prod[X_FRAC + WORD:].as_signed())
    wa, wb, zadd = Signal(WORD, name="wa"), Signal(WORD, name="wb"), Signal(WORD + 1, name="zadd")
    m.d.comb += [wa.eq(Mux(write(), Mux(hi_word, 0, seg.il),
                           Mux(hi_word, seg.zl[WORD - DZ_FRAC:], seg.zl << DZ_FRAC))),
                 wb.eq(Mux(hi_word, p_hi, prod[X_FRAC:X_FRAC + WORD])),
                 zadd.eq(wa + wb + (hi_word & zc))]
    return zadd


class GuardedWords:
    """(paper) :func:`guarded_test` on two-word z, a word a cycle: every test ``Y - X >= c``
    (``c`` 0, 16 or 1) subtracts the low words in pass B's third cycle (:meth:`low`: the borrow and
    whether the low difference reaches ``c``, kept) and the high words with that borrow in its
    fourth (:meth:`high`): ``Y - X >= c`` iff the high difference is positive, or zero with the low
    flag (exact: the two-word values are below 2**25 in magnitude, so no difference wraps).
    ``zw``: the adder's word this cycle (z at sr: its low word in the third cycle, its high in the
    fourth); ``zlr``: z at sl, both words kept."""

    G = 1 << DZ_FRAC
    ZMAX = ((1 << Z_BITS) - 1) << DZ_FRAC      # Q16.4 of the farthest key

    def __init__(self, m: Module, szl, szr, zlr, zw):
        self.m, self.szl, self.szr, self.zlr, self.zw = m, szl, szr, zlr, zw
        # (Y low, X low, c) of the six tests, and their kept borrows and flags
        zmax_lo = self.ZMAX & ((1 << WORD) - 1)
        self.tests = {"dl": (zlr[:WORD], szl[:WORD], self.G), "dr": (zw, szr[:WORD], self.G),
                      "gl": (zlr[:WORD], 0, self.G), "gr": (zw, 0, self.G),
                      "ml": (zmax_lo, szl[:WORD], 1), "mr": (zmax_lo, szr[:WORD], 1)}
        self.b = {k: Signal(name=f"gw_b_{k}") for k in self.tests}
        self.f = {k: Signal(name=f"gw_f_{k}") for k in self.tests}

    def low(self) -> list:
        """The low words' subtractions (sync statements of the third cycle)."""
        out = []
        for k, (y, x, c) in self.tests.items():
            t = Signal(signed(WORD + 2), name=f"gw_lo_{k}")
            self.m.d.comb += t.eq(y - x)
            out += [self.b[k].eq(t < 0), self.f[k].eq(t[:WORD] >= c)]
        return out

    def high(self, s_lower) -> Signal:
        """The high words' subtractions with the kept borrows, and the test (``s_lower``: ties to S)."""
        m = self.m
        zmax_hi = self.ZMAX >> WORD
        hy = {"dl": self.zlr[WORD:], "dr": self.zw, "gl": self.zlr[WORD:], "gr": self.zw, "ml": zmax_hi, "mr": zmax_hi}
        hx = {"dl": self.szl[WORD:], "dr": self.szr[WORD:], "gl": 0, "gr": 0, "ml": self.szl[WORD:], "mr": self.szr[WORD:]}
        ok = {}
        for k in self.tests:
            h = Signal(signed(WORD + 2), name=f"gw_hi_{k}")
            y, x = hy[k], hx[k]
            m.d.comb += h.eq((y.as_signed() if hasattr(y, "as_signed") else y)
                             - (x.as_signed() if hasattr(x, "as_signed") else x) - self.b[k])
            ok[k] = (h > 0) | ((h == 0) & self.f[k]), h >= 0
        good = Signal(name="good_w")
        lower = ok["dl"][1] & ok["dr"][1]
        higher = ok["dl"][0] & ok["dr"][0] & ok["gl"][0] & ok["gr"][0] & ok["ml"][0] & ok["mr"][0]
        m.d.comb += good.eq(Mux(s_lower, lower, higher))
        return good


class Early:
    """``with Early(m, cond, early, last):`` where ``cond`` holds, ``early()`` adds the step's
    early cycle (its statements advance the phase); else the body runs, with ``last`` (sync)."""

    def __init__(self, m: Module, cond, early, last: list):
        self.m, self.cond, self.early, self.last = m, cond, early, last

    def __enter__(self):
        with self.m.If(self.cond):
            self.early()
        self._else = self.m.Else()
        self._else.__enter__()
        self.m.d.sync += self.last
        return self

    def __exit__(self, *exc):
        return self._else.__exit__(*exc)


class Always:
    """A context that adds nothing: the step's own cycle is its only one."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def write_pixel(m: Module, fr: dict, rb, col, bg, seg, ic, slot) -> None:
    """DSLB write of pixel ``col`` in bank ``rb`` this cycle: background where ``bg``, else ASB
    ``seg``'s hue with the intensity ``ic`` (Q.i_frac) and the segment's ``slot`` (for A.J.)."""
    wr, word, fmt = fr["wr"], fr["word"], fr["fmt"]
    m.d.comb += [wr.addr.eq((rb << fr["ab"]) | col), wr.en.eq(1)]
    with m.If(bg):
        m.d.comb += wr.data.eq(word.const({"addr": NONE, "pix": 0, "slot": 0}))
    with m.Else():
        m.d.comb += [wr.data.addr.eq(seg.addr), wr.data.pix.eq((seg.hue << fmt.intensity_bits) | (ic >> fmt.i_frac)),
                     wr.data.slot.eq(slot)]


#: what :func:`resolve_regs` returns, in its order
RESOLVE_REGS = ("rb", "glo", "ghi", "lo", "hi", "n", "nb", "i", "j", "bi", "pp", "S", "skey", "saddr", "cyc", "raddr",
                "seg", "c0", "a", "e", "awr", "ard", "in_bkt", "cand")


def resolve_regs(m: Module, fr: dict) -> tuple:
    """The resolve side's registers and reads both span PXPs declare alike, added to ``m``
    (returned in the order of :data:`RESOLVE_REGS`): the
    bank being resolved ``rb``, the guarded range ``glo``/``ghi`` and range ``lo``/``hi``, the
    bank's ASB and bucket counts ``n``/``nb``, the active list (memory ``act``: write port ``awr``
    at ``j``, read port ``ard`` at ``i``), the next bucket entry ``bi`` and walk position ``pp``, the
    nearest segment ``S`` with its key ``skey`` and address ``saddr``, the finish-time counter
    ``cyc``; the segment read this cycle (``raddr`` -> ``seg``, one DMM/P access) with its ends
    ``c0``/``a``/``e`` (:func:`seg_ends`; ``raddr`` is ``ard``'s entry unless a later statement
    says otherwise; ``cyc`` counts every cycle unless one says otherwise), and the bucket read (``in_bkt``, ``brd`` at ``bi``)
    with the candidate flag ``cand``."""
    cw, pw, D = fr["cw"], fr["pw"], fr["D"]
    r = {"rb": Signal(name="rb"), "glo": Signal(X_END_BITS, name="glo"), "ghi": Signal(X_END_BITS, name="ghi"),
         "lo": Signal(X_INT, name="lo"), "hi": Signal(X_END_BITS, name="hi"), "n": Signal(cw, name="n"),
         "nb": Signal(cw, name="nb"), "i": Signal(cw, name="i"), "j": Signal(cw, name="j"),
         "bi": Signal(cw, name="bi"), "pp": Signal(PTR_BITS + 1, name="pp"), "S": Signal(pw, name="S"),
         "skey": Signal(Z_BITS, name="skey"), "saddr": Signal(ADDR_BITS, name="saddr"),
         "cyc": Signal(16, name="cyc"), "raddr": Signal(pw, name="raddr"), "seg": Signal(fr["asb"], name="seg"),
         "in_bkt": Signal(name="in_bkt"), "cand": Signal(name="cand")}
    m.submodules.act = act = Memory(shape=unsigned(pw), depth=D, init=[])
    r["awr"], r["ard"] = act.write_port(), act.read_port(domain="comb")
    m.d.comb += [r["awr"].en.eq(0), r["ard"].addr.eq(r["i"]), r["awr"].addr.eq(r["j"]),
                 fr["srd"].addr.eq((r["rb"] << pw) | r["raddr"]), r["seg"].eq(fr["srd"].data),
                 r["in_bkt"].eq(r["bi"] < r["nb"]), fr["brd"].addr.eq((r["rb"] << pw) | r["bi"][:pw])]
    r["c0"], r["a"], r["e"] = seg_ends(m, r["seg"], r["glo"], r["ghi"])
    # every cycle counts; the segment read is the active list's entry unless a state reads another
    m.d.sync += r["cyc"].eq(r["cyc"] + 1)
    m.d.comb += r["raddr"].eq(r["ard"].data)
    return tuple(r[k] for k in RESOLVE_REGS)


class _R(enum.Enum, shape=3):
    IDLE = 0      # wait for a full DMM/P bank; start the line
    CULL = 1      # span cull: one active segment per cycle
    ENTER = 2     # span cull: one entering candidate per cycle, then the span's right end
    PASSA = 3     # depth search: z at both ends, nearest at the left pixel
    PASSB = 4     # depth search: guarded end-depth tests
    WRITE = 5     # S.S. and DSLB write, one pixel per cycle
    HAND = 6      # hand the DSLB bank to the drain


class _Resolve:
    """The resolve side's registers and memories over one line, which every step reads and writes.

    The paper's PXP is one processor with its own local memory ("DMMははじめとして各プロセッサの局所
    メモリ、内部レジスタ・ファイル等を1語16ビットで構成する", seed 000, 3.2): the steps below are that
    processor's steps, run one after another over these registers, so they share them rather than
    pass words to each other.

    ``state`` (:class:`_R`); the registers both span PXPs declare alike (:func:`resolve_regs`, an
    attribute each, named as in :data:`RESOLVE_REGS`); this block's own: the span's left pixel ``x``,
    the segments present ``k``, the nearest end + 1 ``minend``, the first active entry ``one``, the
    (sub)span ``sl``..``sr`` searched or written, the nearest's z at its two ends ``szl``/``szr``
    (``paper``: two 16-bit words each), a failed test ``bad``, the span written is background
    ``wbg``; the stack of right ends (memory ``stk``, 16 entries: ``kwr`` at ``sp``, ``krd`` at
    ``sp - 1``; the depth search pushes, the write pops) and (``paper``) the step's cycle ``ph``.
    """

    def __init__(self, m: Module, pxp: ExpertsPxpSpan, fr: dict):
        self.paper = pxp._datapath == "paper"
        self.state = Signal(_R, name="state")
        for key, reg in zip(RESOLVE_REGS, resolve_regs(m, fr), strict=True):
            setattr(self, key, reg)
        pw, cw = fr["pw"], fr["cw"]
        self.x = Signal(X_END_BITS, name="x")
        self.k = Signal(cw, name="k")
        self.minend = Signal(XP_BITS, name="minend")
        self.one = Signal(pw, name="one")
        self.sl = Signal(X_END_BITS, name="sl")
        self.sr = Signal(X_END_BITS, name="sr")
        zw = 2 * WORD if self.paper else RUN_BITS  # (paper) two 16-bit words: |z| < 2**25 at 512 x 512 (docs/experts.md)
        self.szl = Signal(signed(zw), name="szl")
        self.szr = Signal(signed(zw), name="szr")
        self.bad = Signal(name="bad")
        self.wbg = Signal(name="wbg")
        self.sp = Signal(5, name="sp")
        m.submodules.stk = stk = Memory(shape=unsigned(X_END_BITS), depth=16, init=[])
        self.kwr = stk.write_port()
        self.krd = stk.read_port(domain="comb")
        m.d.comb += [self.kwr.en.eq(0), self.krd.addr.eq(self.sp - 1), self.kwr.addr.eq(self.sp)]
        # (paper) the step's cycle: pass A / B 0, 1 z at sl (low word, high word), 2, 3 z at sr; write 0, 1
        self.ph = Signal(2, name="ph")


class _Multiply:
    """The PXP's multiplier: "PXPにおいても、担当の画面領域の初期処理、及び、A.J.における画素データ値の
    混合計算など、乗算が多数出現するため、SLP同様、乗算器を装備している" (seed 000, 3.2).

    What it gives the steps: ``zl``, ``zr`` the running z of the segment read (``seg``) at ``sl`` and
    ``sr``, ``key`` the compare key of ``zl`` and ``ic`` the intensity at ``sl``. Ours (the paper
    gives no count): a multiplier each for z at the two ends (:func:`zrun_at`) and one for i
    (:func:`intensity_at`), all in one cycle. The paper's datapath: its one 16 x 16 multiplier and
    one 16-bit adder (:func:`word_adder`), z at ``sl`` (kept in ``zlr``), then at ``sr``, each in
    two words a word a cycle (:meth:`four_cycles`, the guarded tests' words in ``tests``,
    :class:`GuardedWords`), i at ``sl`` in two (:meth:`write_cycles`).
    """

    def __init__(self, m: Module, fr: dict, r: _Resolve):
        self.m, self.r = m, r
        if r.paper:
            # one multiplier: z at sl (kept in zlr), then z at sr; i at sl when writing. z and i are two
            # 16-bit words, added, subtracted and compared a word a cycle, low word first (carry / borrow kept)
            zlr = Signal(signed(2 * WORD))
            zpl = Signal(WORD)          # z at sr, low word
            zc = Signal()             # the low word's carry
            ilo = Signal(WORD)        # i at sl, low word
            zadd = word_adder(m, fr, seg=r.seg, col=Mux(r.ph[1], r.sr, r.sl), write=lambda: r.state == _R.WRITE,
                              hi_word=r.ph[0], zc=zc)
            zr_ = Signal(signed(2 * WORD), name="zr_w")
            m.d.comb += zr_.eq(Cat(zpl, zadd[:WORD]))
            self.zl, self.zr = zlr, zr_
            self.ic = i_words(m, zadd[:WORD], ilo, fr["fmt"])
            self.key = key_words(m, zlr)
            self.tests = GuardedWords(m, r.szl, r.szr, zlr, zadd[:WORD])
            self.zlr, self.zpl, self.zc, self.ilo, self.zadd = zlr, zpl, zc, ilo, zadd
        else:
            # the multipliers: running z (Q16.4) at pixels sl and sr, i at sl
            self.zl = zrun_at(m, r.seg, r.sl)
            self.zr = zrun_at(m, r.seg, r.sr)
            self.ic = intensity_at(m, r.seg, r.sl, fr["fmt"])
            self.key = z_key(m, self.zl)
            self.tests = None

    def four_cycles(self):
        """(paper) a pass's three first cycles on a segment: z at sl's low and high word into
        ``zlr``, z at sr's low word into ``zpl`` with the guarded tests' low words; the body runs
        in the fourth (z at sr's high word)."""
        if not self.r.paper:
            return Always()
        m, ph, zadd = self.m, self.r.ph, self.zadd

        def early():
            m.d.sync += ph.eq(ph + 1)
            with m.Switch(ph):
                with m.Case(0):
                    m.d.sync += [self.zlr[:WORD].eq(zadd[:WORD]), self.zc.eq(zadd[WORD])]
                with m.Case(1):
                    m.d.sync += self.zlr[WORD:].eq(zadd[:WORD])
                with m.Case(2):
                    m.d.sync += [self.zpl.eq(zadd[:WORD]), self.zc.eq(zadd[WORD]), *self.tests.low()]
        return Early(m, ph != 3, early, [ph.eq(0)])

    def write_cycles(self):
        """(paper) a drawn pixel's first cycle adds i's low word (``ilo``); the body (the write)
        runs in the second, with i's high word; a background pixel takes one."""
        if not self.r.paper:
            return Always()
        m, ph, zadd = self.m, self.r.ph, self.zadd

        def early():
            m.d.sync += [ph.eq(1), self.ilo.eq(zadd[:WORD]), self.zc.eq(zadd[WORD])]
        return Early(m, ~self.r.wbg & (ph == 0), early, [ph.eq(0)])


class _Initial:
    """The PXP's **initial processing** of a line ("初期処理", seed 000, 3.2), state ``IDLE``: the
    PXP first decides the visible segment at its range's first pixel ("自らが担当する部分スキャン・
    ライン上の最初の画素(左端の画素)における可視セグメントをまず決定する"), clipping the ASL to its range
    ("担当範囲よりも左側の部分に存在しているセグメントをASLから除去する"), helped by the SLP's lists
    ("PXPでの初期処理によるオーバヘッドを軽減するために、図3.2に示すBlock Boundary Bucket List、および
    Block Leading Segment Pointer").

    Ours (:func:`take_line`, both span PXPs'): one cycle takes a full DMM/P bank (:func:`take_bank`):
    its range, the guarded range, the counts, and the ASL walk's start at the leading pointer (none:
    past the last ASB); the first span's cull (:class:`_SpanCull`, ``ENTER``) then reads the bucket list (the segments that start
    left of the range and reach into it) and the ASL from the leading pointer.
    """

    def __init__(self, m: Module, fr: dict, r: _Resolve):
        self.m, self.fr, self.r = m, fr, r

    def states(self):
        r = self.r
        with self.m.Case(_R.IDLE):
            take_line(self.m, self.fr, r, r.x, lambda tb: [r.i.eq(0), r.j.eq(0), r.k.eq(0), r.bi.eq(0),
                                                           r.minend.eq(tb["ghi"])], hand=_R.HAND, enter=_R.ENTER)


def take_line(m: Module, fr: dict, r, start, clear, *, hand, enter) -> None:
    """Both span PXPs' ``IDLE``: count from 1 and, once bank ``r.rb`` is full, take its line
    (:func:`take_bank`): the range and guarded range, the counts, the ASL walk from the leading
    pointer (none: past the last ASB), the first span at ``start`` (the guarded range's first
    pixel); ``clear(tb)``: the block's own registers set for the line; then ``enter``, or ``hand``
    for an empty range."""
    m.d.sync += r.cyc.eq(1)
    tb = take_bank(m, fr, r.rb, fr["W"], fr["aj"])
    lo_b, hi_b, glo_b, ghi_b, lead, n_b = tb["lo"], tb["hi"], tb["glo"], tb["ghi"], tb["lead"], tb["n"]
    with m.If(fr["full"].bit_select(r.rb, 1)):
        m.d.sync += [r.lo.eq(lo_b), r.hi.eq(hi_b), r.glo.eq(glo_b), r.ghi.eq(ghi_b), start.eq(glo_b),
                     r.n.eq(n_b), r.nb.eq(tb["nb"]), r.pp.eq(Mux(lead == NO_PTR, n_b, lead)), *clear(tb),
                     r.state.eq(Mux(ghi_b <= glo_b, hand, enter))]


class _SpanCull:
    """iv) **span cull**: "スキャン・ラインをスパンに分割し、そのスパン内に現われる範囲のセグメントを抽出する
    《span cull》" (seed 000, section 4, iv).

    States ``CULL`` and ``ENTER`` (the paper names the step, not its cycles; these are ours, every
    term in ``span_cycles``): one cycle per segment of the active list (in place: those ending
    before ``x`` leave, the others stay and give the nearest end), then one cycle per candidate
    entering at ``x`` (:func:`candidate`: the bucket list first, then the ASL from the leading
    pointer; one with no pixel in the range is skipped in a cycle), and one cycle that sets the
    span's right end ``min(nearest end, next start, ghi) - 1``: a depth search if two or more
    segments are present, else the write.
    """

    def __init__(self, m: Module, fr: dict, r: _Resolve):
        self.m, self.fr, self.r = m, fr, r

    def next_span(self, xn):
        """Start the span cull at pixel ``xn`` (the line's end: hand over)."""
        r = self.r
        return [r.x.eq(xn), r.i.eq(0), r.j.eq(0), r.minend.eq(r.ghi),
                r.state.eq(Mux(xn >= r.ghi, _R.HAND, Mux(r.k == 0, _R.ENTER, _R.CULL)))]

    def keep_active(self):
        """The segment read (``raddr``) is present in the span: onto the active list."""
        m, r = self.m, self.r
        m.d.comb += [r.awr.en.eq(1), r.awr.data.eq(r.raddr)]
        m.d.sync += r.j.eq(r.j + 1)
        with m.If(r.j == 0):
            m.d.sync += r.one.eq(r.raddr)
        with m.If(r.e + 1 < r.minend):
            m.d.sync += r.minend.eq(r.e + 1)

    def states(self):
        m, r = self.m, self.r
        i, j, e, a, cand = r.i, r.j, r.e, r.a, r.cand
        with m.Case(_R.CULL):
            with m.If(e >= r.x):
                self.keep_active()
            m.d.sync += i.eq(i + 1)
            with m.If(i + 1 >= r.k):
                m.d.sync += r.state.eq(_R.ENTER)
        with m.Case(_R.ENTER):
            take = candidate(m, raddr=r.raddr, cand=cand, in_bkt=r.in_bkt, brd=self.fr["brd"], bi=r.bi, pp=r.pp,
                             n=r.n, c0=r.c0, ghi=r.ghi)
            with m.If(cand & (e < a)):
                take()              # no pixel in the range: skipped
            with m.Elif(cand & (a == r.x)):
                self.keep_active()
                take()
            with m.Else():
                # the span's right end: the nearest end, the next start, the range's end
                nxt = Signal(XP_BITS)
                m.d.comb += nxt.eq(Mux(cand & (a < r.minend), a, r.minend))
                m.d.sync += [r.k.eq(j), r.sl.eq(r.x), r.sr.eq(nxt - 1), r.sp.eq(0), i.eq(0)]
                with m.If(j >= 2):
                    m.d.sync += r.state.eq(_R.PASSA)
                with m.Else():
                    m.d.sync += [r.wbg.eq(j == 0), r.S.eq(r.one), r.state.eq(_R.WRITE)]


class _DepthSearch:
    """v) **depth search**: "iv)で抽出したセグメントに応じてデプス・サーチを行ない、可視セグメントを決定する
    《depth search》" (seed 000, section 4, v), on the rules of ``golden_model/experts/span.py``.

    States ``PASSA`` and ``PASSB`` (ours, as the span cull's): pass A, one step per segment present:
    z at the (sub)span's two end pixels and the nearest at the left pixel (``nearer``: 16-bit key,
    ties to the lower ASB address); pass B (spans wider than a pixel), one step per segment: the
    guarded end-depth test (``good``: S stays nearest at every pixel). If a test fails the span is
    halved at ``mid = (sl + sr + 1) >> 1``, the right half's end pushed on the stack and the left
    half searched. A step is a cycle (ours) or four (the paper's datapath,
    :meth:`_Multiply.four_cycles`).
    """

    def __init__(self, m: Module, r: _Resolve, mul: _Multiply):
        self.m, self.r, self.mul = m, r, mul
        self.nearer = nearer = Signal(name="nearer")
        m.d.comb += nearer.eq((r.i == 0) | (mul.key < r.skey) | ((mul.key == r.skey) & (r.seg.addr < r.saddr)))
        # the guarded test (span.py): S nearer than this segment B at every pixel of [sl, sr]
        self.good = good = Signal(name="good")
        s_low = r.saddr < r.seg.addr
        m.d.comb += good.eq((r.raddr == r.S) | (mul.tests.high(s_low) if r.paper
                                                else guarded_test(m, r.szl, r.szr, mul.zl, mul.zr, s_low)))
        self.mid = mid = Signal(X_END_BITS, name="mid")
        m.d.comb += mid.eq((r.sl + r.sr + 1) >> 1)

    def states(self):
        m, r, mul = self.m, self.r, self.mul
        i, good, bad = r.i, self.good, r.bad
        with m.Case(_R.PASSA), mul.four_cycles():
            with m.If(self.nearer):
                m.d.sync += [r.S.eq(r.raddr), r.skey.eq(mul.key), r.saddr.eq(r.seg.addr), r.szl.eq(mul.zl),
                             r.szr.eq(mul.zr)]
            m.d.sync += i.eq(i + 1)
            with m.If(i + 1 >= r.k):
                m.d.sync += i.eq(0)
                with m.If(r.sl == r.sr):
                    m.d.sync += [r.wbg.eq(0), r.state.eq(_R.WRITE)]
                with m.Else():
                    m.d.sync += [bad.eq(0), r.state.eq(_R.PASSB)]
        with m.Case(_R.PASSB), mul.four_cycles():
            m.d.sync += [i.eq(i + 1), bad.eq(bad | ~good)]
            with m.If(i + 1 >= r.k):
                m.d.sync += i.eq(0)
                with m.If(bad | ~good):
                    # the end depths do not settle it: halve, search the left half first
                    m.d.comb += [r.kwr.en.eq(1), r.kwr.data.eq(r.sr)]
                    m.d.sync += [r.sp.eq(r.sp + 1), r.sr.eq(self.mid - 1), r.state.eq(_R.PASSA)]
                with m.Else():
                    m.d.sync += [r.wbg.eq(0), r.state.eq(_R.WRITE)]


class _ShadeWrite:
    """**S.S. and the DSLB write** of a decided (sub)span, state ``WRITE``: "HSEによって可視セグメントが
    決定した後、直ちに(1)式によつてS.S.を開始する事ができる" (seed 000, 2.3), uniform along the visible
    segment ("一旦可視セグメントが決定されればその中では一様な計算で各画素の値を決める", 2.2).

    One pixel a cycle (ours; two a drawn pixel at the paper's datapath,
    :meth:`_Multiply.write_cycles`): the intensity by the multiplier at that pixel (equal to
    stepping), the DSLB word ``{ASB address, pixel, ASL position}`` (:func:`write_pixel`). At the
    (sub)span's end: the next half off the stack, else the next span's cull.
    """

    def __init__(self, m: Module, fr: dict, r: _Resolve, mul: _Multiply, cull: _SpanCull):
        self.m, self.fr, self.r, self.mul, self.cull = m, fr, r, mul, cull

    def states(self):
        m, r = self.m, self.r
        with m.Case(_R.WRITE):
            m.d.comb += r.raddr.eq(r.S)
            with self.mul.write_cycles():
                write_pixel(m, self.fr, r.rb, r.sl, r.wbg, r.seg, self.mul.ic, r.S)
                m.d.sync += r.sl.eq(r.sl + 1)
                with m.If(r.sl == r.sr):
                    with m.If(r.sp != 0):
                        m.d.sync += [r.sr.eq(r.krd.data), r.sp.eq(r.sp - 1), r.i.eq(0), r.state.eq(_R.PASSA)]
                    with m.Else():
                        m.d.sync += self.cull.next_span(r.sr + 1)


def hand_over(m: Module, pxp, drain, r, idle) -> None:
    """The line's end (both span PXPs' ``HAND``): the DSLB bank written goes to the drain once it is
    free ("DSLBもDMM同様、2重系の構成とい、PXPによる書き込みと、FBへの転送のための読み出しとを並行して
    同時にに行なうことができる", seed 000, 3.2, the seed's OCR); the resolve side turns to the other
    bank (``r.state`` to ``idle``) and the finish-time counter ``line_cycles`` takes the line's
    cycles. ``r``: the resolve side's registers (``rb``, ``lo``, ``hi``, ``glo``, ``ghi``, ``cyc``,
    ``state``)."""
    with m.If(~drain.dbusy):
        m.d.sync += [*drain.hand(bank=r.rb, lo=r.lo, hi=r.hi, glo=r.glo, ghi=r.ghi), r.rb.eq(~r.rb),
                     r.state.eq(idle),
                     pxp.line_cycles.eq(r.cyc + 1), pxp.lines.eq(pxp.lines + 1)]



@params("width", "aj", "depth", "datapath")
class ExpertsPxpSpan(wiring.Component):
    """One span PXP with its DMM/P: DMM/P words in, the range's pixel words out, line by line.

    Parameters
    ----------
    width : int
        Frame width (1..1024): depth of the DSLB.
    intensity_bits : int
        Intensity field width (1..7); the pixel word is ``3 * 3 + intensity_bits`` bits.
    aj : str
        ``"none"`` or ``"c"`` (anti-jagging, method (c)).
    depth : int
        ASBs per DMM/P bank (2..511).
    datapath : str
        ``"ours"`` (a multiplier each for z at a span's two ends and for i, and the A.J. blend's
        own; 40-bit z registers) or ``"paper"`` (one 16 x 16 multiplier, :func:`mul16.sm_mul`: z at
        the left end, then at the right, ``span_cycles.one_multiplier``, each in two 16-bit words a
        word a cycle, ``span_cycles.multiword``: pass A and pass B 4 cycles a segment, the write 2
        a drawn pixel; with A.J. the drain's blend shares the multiplier, ``span_cycles.paper_drain``
        and ``schedule(mul=)``).

    Members
    -------
    i : In(stream.Signature(dmm_layout()))
    o : Out(stream.Signature(unsigned(9 + intensity_bits)))
    lo, hi : In(X_INT), In(X_END_BITS)
        The range ``[lo, hi)`` of the line being written, sampled with its ``last`` token.
    line_cycles : Out(16)
        Finish-time counter: cycles of the last line from its first resolve cycle to its hand-over
        to the drain (waits for the drain included).
    lines : Out(16)
        Lines handed over.
    overflow : Out(1)
        Sticky: a line had more than ``depth`` ASBs or bucket entries; ``i`` is stalled for good.
    """

    #: the block has the paper's datapath (``datapath="paper"``: one shared multiplier)
    PAPER_DATAPATH = True

    def __init__(self, *, width: int = 512, intensity_bits: int = 7, aj: str = "none", depth: int = 256,
                 datapath: str = "ours"):
        check_pxp_params(width=width, aj=aj)
        if isinstance(depth, bool) or not isinstance(depth, int) or not 2 <= depth <= NO_PTR:
            raise ValueError(f"depth must be an integer in 2..{NO_PTR}, not {depth!r}")
        if datapath not in ("ours", "paper") or (datapath == "paper" and not self.PAPER_DATAPATH):
            raise ValueError(f"datapath must be ours{' or paper' if self.PAPER_DATAPATH else ''}, not {datapath!r}")
        self._datapath = datapath
        self._fmt = Formats(intensity_bits)
        self._width = width
        self._aj = aj
        self._depth = depth
        super().__init__({**pxp_members(dmm_layout(), self._fmt.pixel_bits), "overflow": Out(1)})

    def frame(self, m: Module) -> dict:
        """What both span PXPs share, added to ``m``: the DMM/P (:func:`dmm_p`), the double-banked
        DSLB (its write port ``wr``, words ``word``, bank bit ``ab``) and the drain (``drain``: the
        A.J. (c) entry read at a segment's boundary pixels only), plus the widths ``pw`` (ASL
        position), ``cw`` (counts) and the block's parameters."""
        fmt, W, D, aj = self._fmt, self._width, self._depth, self._aj == "c"
        pb, ib = fmt.pixel_bits, fmt.intensity_bits
        asb = asb_layout()
        pw = (D - 1).bit_length()                   # ASL position bits within a bank
        cw = D.bit_length()                         # counts 0..D
        ab = (W - 1).bit_length()                   # DSLB bank bit position
        dm = dmm_p(m, self, asb, D)
        word = data.StructLayout({"addr": unsigned(ADDR_BITS), "pix": unsigned(pb), "slot": unsigned(pw)})
        m.submodules.dslb = dslb = Memory(shape=word, depth=2 << ab, init=[])
        wr = dslb.write_port()
        drd = dslb.read_port(transparent_for=())
        m.d.comb += wr.en.eq(0)
        trd = dm["dmm"].read_port(transparent_for=()) if aj else None    # the visible segment's edges
        clr_full = dm["clr_full"]
        mul = None
        if self._datapath == "paper":
            # the PXP's one 16 x 16 multiplier, shared by the resolve side and the drain's A.J. blend
            mul = {"a": Signal(MUL_IN, name="mul_a"), "b": Signal(MUL_IN, name="mul_b")}
            mul["p"] = sm_mul(m, mul["a"], mul["b"], "pxp_mul")
        drain = Drain(m, o=self.o, drd=drd, word=word, bank_bit=ab, width=W, ib=ib, aj=aj,
                      trd=trd, ent=asb, ent_bank_bit=pw, boundary_only=True,
                      done_comb=lambda d: [clr_full.eq(Mux(d.dbank, 0b10, 0b01))],
                      prod=mul["p"] if mul else None)
        return {**dm, "fmt": fmt, "W": W, "D": D, "aj": aj, "ib": ib, "asb": asb, "pw": pw, "cw": cw, "ab": ab,
                "word": word, "wr": wr, "drain": drain, "mul": mul}

    def _hold(self, m: Module, state, drain, idle=_R.IDLE, hand=_R.HAND):
        """(paper, A.J.) The arbitration of the one multiplier: while the drain's blend holds it
        (``drain.mreq``), every resolve step but taking a bank (``idle``) and handing one over
        (``hand``; the coherent PXP passes its own states) holds; else a context that adds nothing."""
        if drain.mreq is None:
            return Always()
        return m.If(~drain.mreq | (state == idle) | (state == hand))

    def elaborate(self, platform):
        m = Module()
        fr = self.frame(m)
        # the resolve side's registers and datapaths outside the FSM, in this order (the netlist's
        # statement order)
        r = _Resolve(m, self, fr)
        mul = _Multiply(m, fr, r)
        search = _DepthSearch(m, r, mul)
        cull = _SpanCull(m, fr, r)
        # one FSM: the steps' states, each step after the one before it on the same registers
        with self._hold(m, r.state, fr["drain"]), m.Switch(r.state):
            _Initial(m, fr, r).states()
            cull.states()
            search.states()
            _ShadeWrite(m, fr, r, mul, cull).states()
            with m.Case(_R.HAND):
                hand_over(m, self, fr["drain"], r, _R.IDLE)
        return m
