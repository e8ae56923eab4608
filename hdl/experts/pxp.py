"""EXPERTS pixel processor (PXP) datapath: start values, z/i stepping, 16-bit depth compare, A.J. (c), DSLB.

Paper (seed 000, 3.2): the PXP takes the ASL for its part of the scan line, computes the start
values at its first pixel with its multiplier ("担当範囲の開始点における ... 初期データを計算する",
"PXPにおいても ... 乗算が多数出現するため ... 乗算器を装備"), resolves hidden surfaces, shades and
anti-jags up to its last pixel and writes its DSLB.

This block resolves depth segment by segment into a line memory kept beside the DSLB (per pixel:
z key, ASB address, pixel word, and with A.J. the segment's slot in a small segment table), which
gives exactly the golden depth search's pixels (16-bit key, ties to the lower ASB address). With
``aj="c"`` it then walks the line left to right and blends, by eq. (5) with method (c), every
boundary between two polygons where the right run's left edge starts or the left run's right edge
ends -- the golden model's rule (``golden_model/experts/pxp.py``); to see the boundaries at its
range ends it also resolves one guard pixel on each side (``[lo-1, hi+1)`` within the frame) and
outputs only ``[lo, hi)``. The DSLB is double-banked ("DSLBもDMM同様、2重系の構成とい、PXPによる
書き込みと、FBへの転送のための読み出しとを並行して同時にに行なう", the seed's OCR): the next line is cleared and
resolved in one bank while the other drains, the banks swapping by a hand-over once the drain is
free. Bit- and cycle-exact with ``golden_model.experts.pxp_cycles``. Not in this block: shadows.

In the code each step is a sub-component that emits its datapath and its states into the one FSM
over the line memory and registers they share (:class:`_Line`): the clear (``_clear``), the
segment in and its start values by the multiplier (:class:`_StartValues`), the per-pixel depth
compare (:class:`_DepthCompare`, ours) and the hand-over to the drain (``_hand_over``). They are
not joined by streams: the PXP is one sequential processor, its per-line cycles
(``pxp_cycles``) the sum of its steps'.

Input protocol: per line, the clipped ASL segments (``SEG`` payloads with ``last = 0``) in ASL
order, then one ``last = 1`` token; ``lo``/``hi`` (the range ``[lo, hi)``) are sampled when a line
starts. Output: the line's ``hi - lo`` pixel words, left to right, after its last token.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import Out
from rasterhw.golden_model.experts.formats import (
    ADDR_BITS,
    DATAPATHS,
    DZ_FRAC,
    RGB_BITS,
    SLOT_BITS,
    WORD,
    X_END_BITS,
    X_FRAC,
    X_INT,
    XP_BITS,
    Z_BITS,
    Formats,
)
from rasterhw.hdl.experts.drain import Drain, check_pxp_params, pxp_members
from rasterhw.hdl.params import params

__all__ = ["ExpertsPxp", "asb_fields", "seg_layout"]

NONE = (1 << ADDR_BITS) - 1     # ASB address / polygon number of the background
#: the running z and i registers: the widest the datapath has (never wrap, formats.py)
RUN_BITS = DATAPATHS["ours"].word_bits


def asb_fields() -> dict:
    """The ASB fields a PXP reads (both PXPs: ``seg_layout`` here, ``dmm_layout`` in ``pxp_span.py``)."""
    return {
        "xl": unsigned(WORD),         # Q10.6
        "xr": unsigned(WORD),         # Q10.6
        "zl": unsigned(Z_BITS),       # Q16.0, 0 = near
        "il": unsigned(WORD),         # Q(I).(16-I)
        "dzdx": signed(WORD),         # sQ11.4
        "didx": signed(WORD),         # sQ(I-1).(16-I)
        "hue": unsigned(RGB_BITS),
        "addr": unsigned(ADDR_BITS),  # ASB address = PL order: the tie-break
        "poly": unsigned(ADDR_BITS),  # Tags: polygon number (A.J. only between polygons)
        "sl": signed(WORD),           # left edge dx/dy, sQ7.8 (A.J.)
        "ql": signed(WORD),           # left edge dy/dx, sQ7.8
        "sr": signed(WORD),           # right edge dx/dy
        "qr": signed(WORD),           # right edge dy/dx
    }


def seg_layout() -> data.StructLayout:
    """One ASB as the PXP reads it (the fields it uses)."""
    return data.StructLayout({"last": unsigned(1), **asb_fields()})   # last: end of the line's list


class _S(enum.Enum, shape=3):
    CLEAR = 0
    SEG = 1
    START = 2
    READ = 3
    CMP = 4
    HAND = 5      # hand the bank to the drain (waits while the drain is busy; drain.py)


class _Line:
    """The PXP's line memory and registers, which every step reads and writes.

    The line memory is the DSLB with a z key per pixel (``word``: z key, ASB address, pixel word,
    A.J. slot), two banks, one resolved while the other drains ("DSLBもDMM同様、2重系の構成とい、PXPによる
    書き込みと、FBへの転送のための読み出しとを並行して同時にに行なうことができる", seed 000, 3.2, the seed's
    OCR): ``rd`` (resolve side: read-compare-write) and ``wr``, ``drd`` (the drain), bank bit ``ab``;
    with A.J. the segment table ``tab`` (``twr``, ``trd``: each segment's edges by its slot).
    Registers: ``state`` (:class:`_S`), the bank resolved ``rbank``, the pixel ``x`` and the
    segment's last owned pixel ``end``, the range ``lo``/``hi`` and the resolved range ``glo``/``ghi``
    (guards included), the segment ``seg`` and its ``slot``, the running ``zrun``/``irun``, the
    finish-time counter ``cyc``.
    """

    def __init__(self, m: Module, pxp: ExpertsPxp):
        fmt, W = pxp._fmt, pxp._width
        self.aj = aj = pxp._aj == "c"
        self.W, self.pb, self.ib = W, fmt.pixel_bits, fmt.intensity_bits
        self.word = word = data.StructLayout({"z": unsigned(Z_BITS), "addr": unsigned(ADDR_BITS),
                                              "pix": unsigned(self.pb), "slot": unsigned(SLOT_BITS)})
        # the DSLB: two banks (bank = top address bit), one resolved while the other drains
        m.submodules.mem = mem = Memory(shape=word, depth=2 * W, init=[])
        self.rd = mem.read_port(transparent_for=())      # resolve side: read-compare-write
        self.wr = mem.write_port()
        self.drd = mem.read_port(transparent_for=())     # drain side
        self.ab = (2 * W - 1).bit_length() - 1           # bank bit position
        self.ent = ent = data.StructLayout({
            "xl": unsigned(WORD), "xr": unsigned(WORD), "poly": unsigned(ADDR_BITS),
            "sl": signed(WORD), "ql": signed(WORD), "sr": signed(WORD), "qr": signed(WORD)})
        self.trd = self.twr = None
        if aj:
            m.submodules.tab = tab = Memory(shape=ent, depth=2 << SLOT_BITS, init=[])
            self.trd = tab.read_port(transparent_for=())
            self.twr = tab.write_port()
        self.state = Signal(_S, name="state")
        self.rbank = Signal(name="rbank")
        self.x = Signal(X_END_BITS, name="x")
        self.end = Signal(X_END_BITS, name="end")       # last owned pixel of the segment
        self.lo = Signal(X_INT, name="lo")
        self.hi = Signal(X_END_BITS, name="hi")
        self.glo = Signal(X_END_BITS, name="glo")       # resolved range, guards included
        self.ghi = Signal(X_END_BITS, name="ghi")
        self.seg = Signal(seg_layout(), name="seg")
        self.slot = Signal(SLOT_BITS + 1, name="slot")
        self.zrun = Signal(signed(RUN_BITS), name="zrun")
        self.irun = Signal(signed(RUN_BITS), name="irun")
        self.cyc = Signal(16, name="cyc")
        self.pxp = pxp

    def sample_range(self) -> list:
        """The next line's range ``[lo, hi)`` from the ports, and its resolved range (one guard pixel
        each side with A.J., within the frame), ``x`` at its start."""
        p = self.pxp
        stmts = [self.lo.eq(p.lo), self.hi.eq(p.hi)]
        if self.aj:
            stmts += [self.glo.eq(Mux(p.lo > 0, p.lo - 1, 0)),
                      self.ghi.eq(Mux(p.hi < self.W, p.hi + 1, p.hi)),
                      self.x.eq(Mux(p.lo > 0, p.lo - 1, 0))]
        else:
            stmts += [self.glo.eq(p.lo), self.ghi.eq(p.hi), self.x.eq(p.lo)]
        return stmts


class _StartValues:
    """The segment in and its **start values**, states ``SEG`` and ``START``: as the paper's initial
    processing, the z and intensity at the segment's first owned pixel by the multiplier
    ("担当範囲の開始点における各セグメントの ... Zs値(奥行きの座標値)、輝度値など、以降のHSE等のための
    初期データを計算する", seed 000, 3.2; "PXPにおいても ... 乗算が多数出現するため ... 乗算器を装備", 3.2),
    here for every segment at its own first pixel in the resolved range (``s``; ``e`` its last,
    ``c0``/``c1`` its pixels in the frame). ``SEG`` takes the next ASB (the line's ``last`` token:
    hand over); ``START`` writes its edges into the A.J. segment table and, if it owns a pixel,
    starts the compare at ``s``.
    """

    def __init__(self, m: Module, ln: _Line):
        self.m, self.ln = m, ln
        seg, glo, ghi = ln.seg, ln.glo, ln.ghi
        c0 = Signal(signed(XP_BITS))
        c1 = Signal(signed(XP_BITS))
        s = Signal(signed(XP_BITS))
        e = Signal(signed(XP_BITS))
        m.d.comb += [
            c0.eq((seg.xl + 31) >> X_FRAC),
            c1.eq(((seg.xr + 31) >> X_FRAC) - 1),
            s.eq(Mux(c0 > glo, c0, glo)),
            e.eq(Mux(c1 < ghi - 1, c1, ghi - 1)),
        ]
        d = Signal(signed(20))
        m.d.comb += d.eq((s << X_FRAC) + (1 << (X_FRAC - 1)) - seg.xl)
        # the multiplier: start values at the first owned pixel
        zstart = Signal(signed(RUN_BITS))
        istart = Signal(signed(RUN_BITS))
        m.d.comb += [
            zstart.eq((seg.zl << DZ_FRAC) + ((d * seg.dzdx) >> X_FRAC)),
            istart.eq(seg.il + ((d * seg.didx) >> X_FRAC)),
        ]
        self.s, self.e, self.zstart, self.istart = s, e, zstart, istart

    def states(self):
        m, ln, pxp = self.m, self.ln, self.ln.pxp
        seg, slot, state = ln.seg, ln.slot, ln.state
        with m.Case(_S.SEG):
            m.d.comb += pxp.i.ready.eq(1)
            with m.If(pxp.i.valid):
                m.d.sync += seg.eq(pxp.i.payload)
                with m.If(pxp.i.payload.last):
                    m.d.sync += state.eq(_S.HAND)
                with m.Else():
                    m.d.sync += state.eq(_S.START)
        with m.Case(_S.START):
            if ln.aj:
                twr = ln.twr
                m.d.comb += [twr.addr.eq((ln.rbank << SLOT_BITS) | slot[:SLOT_BITS]),
                             twr.en.eq(slot < (1 << SLOT_BITS)),
                             twr.data.xl.eq(seg.xl), twr.data.xr.eq(seg.xr), twr.data.poly.eq(seg.poly),
                             twr.data.sl.eq(seg.sl), twr.data.ql.eq(seg.ql), twr.data.sr.eq(seg.sr),
                             twr.data.qr.eq(seg.qr)]
                with m.If(slot == (1 << SLOT_BITS)):
                    m.d.sync += pxp.slot_overflow.eq(1)
            with m.If(self.s > self.e):
                m.d.sync += [state.eq(_S.SEG), slot.eq(slot + 1)]
            with m.Else():
                m.d.sync += [ln.x.eq(self.s), ln.end.eq(self.e), ln.zrun.eq(self.zstart), ln.irun.eq(self.istart),
                             state.eq(_S.READ)]


class _DepthCompare:
    """The per-pixel depth compare (ours: the paper's PXP finds the visible segment by its span cull
    and depth search, "iv)で抽出したセグメントに応じてデプス・サーチを行ない、可視セグメントを決定する",
    seed 000, section 4; this line Z-buffer gives the same pixels), states ``READ`` and ``CMP``: one
    read and one compare a pixel of the segment's owned pixels, z and i stepped (S.S.: "一旦可視
    セグメントが決定されればその中では一様な計算で各画素の値を決める", 2.2). The segment wins a pixel by
    its 16-bit key (``key``: the clamped running z), ties to the lower ASB address (``wins``); the
    winner's word (``pix``: hue and clamped intensity) is written with its slot.
    """

    def __init__(self, m: Module, ln: _Line):
        self.m, self.ln = m, ln
        fmt = ln.pxp._fmt
        seg, zrun, irun = ln.seg, ln.zrun, ln.irun
        # compare key (16-bit comparator on the clamped running z) and the shaded pixel
        zk = Signal(signed(RUN_BITS))
        key = Signal(Z_BITS)
        m.d.comb += zk.eq(zrun >> DZ_FRAC)
        m.d.comb += key.eq(Mux(zk < 0, 0, Mux(zk > (1 << Z_BITS) - 1, (1 << Z_BITS) - 1, zk)))
        imax = fmt.i_max << fmt.i_frac
        ic = Signal(WORD)
        m.d.comb += ic.eq(Mux(irun < 0, 0, Mux(irun > imax, imax, irun)))
        pix = Signal(ln.pb)
        m.d.comb += pix.eq((seg.hue << ln.ib) | (ic >> fmt.i_frac))
        stored = Signal(ln.word)
        m.d.comb += stored.eq(ln.rd.data)
        wins = Signal()
        m.d.comb += wins.eq((key < stored.z) | ((key == stored.z) & (seg.addr < stored.addr)))
        self.key, self.pix, self.wins = key, pix, wins

    def states(self):
        m, ln = self.m, self.ln
        rd, wr, x, seg, slot, state = ln.rd, ln.wr, ln.x, ln.seg, ln.slot, ln.state
        with m.Case(_S.READ):
            m.d.comb += [rd.addr.eq((ln.rbank << ln.ab) | x), rd.en.eq(1)]
            m.d.sync += state.eq(_S.CMP)
        with m.Case(_S.CMP):
            with m.If(self.wins):
                m.d.comb += [wr.addr.eq((ln.rbank << ln.ab) | x), wr.en.eq(1), wr.data.z.eq(self.key),
                             wr.data.addr.eq(seg.addr), wr.data.pix.eq(self.pix), wr.data.slot.eq(slot)]
            m.d.sync += [ln.zrun.eq(ln.zrun + seg.dzdx), ln.irun.eq(ln.irun + seg.didx), x.eq(x + 1)]
            with m.If(x == ln.end):
                m.d.sync += [state.eq(_S.SEG), slot.eq(slot + 1)]
            with m.Else():
                m.d.sync += state.eq(_S.READ)


def _clear(m: Module, ln: _Line) -> None:
    """State ``CLEAR`` (ours): the bank's resolved range cleared to the farthest key and the
    background, one pixel a cycle; then the line's segments."""
    m.d.comb += [ln.wr.addr.eq((ln.rbank << ln.ab) | ln.x),
                 ln.wr.data.eq(ln.word.const({"z": (1 << Z_BITS) - 1, "addr": NONE, "pix": 0, "slot": 0})),
                 ln.wr.en.eq(ln.x < ln.ghi)]
    m.d.sync += ln.x.eq(ln.x + 1)
    with m.If(ln.x + 1 >= ln.ghi):
        m.d.sync += [ln.state.eq(_S.SEG), ln.slot.eq(0)]


def _hand_over(m: Module, ln: _Line, drain: Drain) -> None:
    """State ``HAND``: the resolved bank goes to the drain once the drain is free (the DSLB's two
    banks, :class:`_Line`), and the next line's range is sampled."""
    pxp = ln.pxp
    with m.If(~drain.dbusy):
        m.d.sync += [*drain.hand(bank=ln.rbank, lo=ln.lo, hi=ln.hi, glo=ln.glo, ghi=ln.ghi),
                     ln.rbank.eq(~ln.rbank), ln.state.eq(_S.CLEAR),
                     pxp.line_cycles.eq(ln.cyc + 1), ln.cyc.eq(0), pxp.lines.eq(pxp.lines + 1),
                     *ln.sample_range()]


@params("width", "aj")
class ExpertsPxp(wiring.Component):
    """One PXP: clipped ASL in, the range's pixel words out, line by line.

    Parameters
    ----------
    width : int
        Frame width (1..1024): depth of the line memory.
    intensity_bits : int
        Intensity field width (1..7); the pixel word is ``3 * 3 + intensity_bits`` bits.
    aj : str
        ``"none"`` or ``"c"`` (anti-jagging, method (c)).

    Members
    -------
    i : In(stream.Signature(seg_layout()))
    o : Out(stream.Signature(unsigned(RGB_BITS + intensity_bits)))
    lo, hi : In(X_INT), In(X_END_BITS)
        The range ``[lo, hi)``, sampled at the start of each line.
    line_cycles : Out(16)
        Finish-time counter: cycles of the last line from its first clear cycle to its hand-over to
        the drain (waits for the drain included).
    lines : Out(16)
        Lines handed over.
    slot_overflow : Out(1)
        Sticky (A.J. only): a line had more segments than the segment table's 256 slots (the
        DMM/P bank in front holds 256, so this cannot happen behind one).

    Cycles with the input always valid and the output always ready: ``pxp_cycles.schedule``
    (resolve ``G + sum(2 + 2 n) + 1`` and one hand-over cycle per line, overlapped with the drain
    of the line before: ``2 R``, with A.J. ``3 G`` plus one at the frame's right edge).
    """

    def __init__(self, *, width: int = 512, intensity_bits: int = 7, aj: str = "none"):
        check_pxp_params(width=width, aj=aj)
        self._fmt = Formats(intensity_bits)
        self._width = width
        self._aj = aj
        super().__init__({**pxp_members(seg_layout(), self._fmt.pixel_bits), "slot_overflow": Out(1)})

    @property
    def intensity_bits(self) -> int:
        return self._fmt.intensity_bits

    def elaborate(self, platform):
        m = Module()
        # the line memory, the registers and the datapaths outside the FSM, in this order (the
        # netlist's statement order)
        ln = _Line(m, self)
        start = _StartValues(m, ln)
        cmp = _DepthCompare(m, ln)
        m.d.comb += [ln.rd.en.eq(0), ln.wr.en.eq(0), self.i.ready.eq(0)]
        if ln.aj:
            m.d.comb += ln.twr.en.eq(0)
        # the drain side (drain.py)
        drain = Drain(m, o=self.o, drd=ln.drd, word=ln.word, bank_bit=ln.ab, width=ln.W, ib=ln.ib, aj=ln.aj,
                      trd=ln.trd, ent=ln.ent if ln.aj else None, ent_bank_bit=SLOT_BITS)
        m.d.sync += ln.cyc.eq(ln.cyc + 1)
        started = Signal()
        with m.If(~started):
            # out of reset: sample the first line's range
            m.d.sync += [started.eq(1), ln.cyc.eq(0), *ln.sample_range()]
        with m.Else(), m.Switch(ln.state):
            with m.Case(_S.CLEAR):
                _clear(m, ln)
            start.states()
            cmp.states()
            with m.Case(_S.HAND):
                _hand_over(m, ln, drain)
        return m
