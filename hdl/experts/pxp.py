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
outputs only ``[lo, hi)``. The DSLB is double-banked ("DSLBもDMM同様、2重系の構成とし、PXPによる
書き込みと、FBへの転送のための読み出しとを並行して同時に行なう"): the next line is cleared and
resolved in one bank while the other drains, the banks swapping by a hand-over once the drain is
free. Bit- and cycle-exact with ``golden_model.experts.pxp_cycles``. Not in this block: shadows.

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
        fmt, W, aj = self._fmt, self._width, self._aj == "c"
        pb, ib = fmt.pixel_bits, fmt.intensity_bits
        word = data.StructLayout({"z": unsigned(Z_BITS), "addr": unsigned(ADDR_BITS), "pix": unsigned(pb),
                                  "slot": unsigned(SLOT_BITS)})
        # the DSLB: two banks (bank = top address bit), one resolved while the other drains
        m.submodules.mem = mem = Memory(shape=word, depth=2 * W, init=[])
        rd = mem.read_port(transparent_for=())      # resolve side: read-compare-write
        wr = mem.write_port()
        drd = mem.read_port(transparent_for=())     # drain side
        ab = (2 * W - 1).bit_length() - 1           # bank bit position
        ent = data.StructLayout({"xl": unsigned(WORD), "xr": unsigned(WORD), "poly": unsigned(ADDR_BITS),
                                 "sl": signed(WORD), "ql": signed(WORD), "sr": signed(WORD), "qr": signed(WORD)})
        if aj:
            m.submodules.tab = tab = Memory(shape=ent, depth=2 << SLOT_BITS, init=[])
            trd = tab.read_port(transparent_for=())
            twr = tab.write_port()

        # ---------------------------------------------------------------- resolve side
        state = Signal(_S)
        rbank = Signal()
        x = Signal(X_END_BITS)
        end = Signal(X_END_BITS)       # last owned pixel of the segment
        lo = Signal(X_INT)
        hi = Signal(X_END_BITS)
        glo = Signal(X_END_BITS)       # resolved range, guards included
        ghi = Signal(X_END_BITS)
        seg = Signal(seg_layout())
        slot = Signal(SLOT_BITS + 1)
        zrun = Signal(signed(RUN_BITS))
        irun = Signal(signed(RUN_BITS))
        cyc = Signal(16)

        def sample_range():
            stmts = [lo.eq(self.lo), hi.eq(self.hi)]
            if aj:
                stmts += [glo.eq(Mux(self.lo > 0, self.lo - 1, 0)),
                          ghi.eq(Mux(self.hi < W, self.hi + 1, self.hi)),
                          x.eq(Mux(self.lo > 0, self.lo - 1, 0))]
            else:
                stmts += [glo.eq(self.lo), ghi.eq(self.hi), x.eq(self.lo)]
            return stmts

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
        # compare key (16-bit comparator on the clamped running z) and the shaded pixel
        zk = Signal(signed(RUN_BITS))
        key = Signal(Z_BITS)
        m.d.comb += zk.eq(zrun >> DZ_FRAC)
        m.d.comb += key.eq(Mux(zk < 0, 0, Mux(zk > (1 << Z_BITS) - 1, (1 << Z_BITS) - 1, zk)))
        imax = fmt.i_max << fmt.i_frac
        ic = Signal(WORD)
        m.d.comb += ic.eq(Mux(irun < 0, 0, Mux(irun > imax, imax, irun)))
        pix = Signal(pb)
        m.d.comb += pix.eq((seg.hue << ib) | (ic >> fmt.i_frac))
        stored = Signal(word)
        m.d.comb += stored.eq(rd.data)
        wins = Signal()
        m.d.comb += wins.eq((key < stored.z) | ((key == stored.z) & (seg.addr < stored.addr)))
        m.d.comb += [rd.en.eq(0), wr.en.eq(0), self.i.ready.eq(0)]
        if aj:
            m.d.comb += twr.en.eq(0)

        # ---------------------------------------------------------------- drain side (drain.py)
        drain = Drain(m, o=self.o, drd=drd, word=word, bank_bit=ab, width=W, ib=ib, aj=aj,
                      trd=trd if aj else None, ent=ent if aj else None, ent_bank_bit=SLOT_BITS)
        dbusy = drain.dbusy

        m.d.sync += cyc.eq(cyc + 1)
        started = Signal()

        with m.If(~started):
            # out of reset: sample the first line's range
            m.d.sync += [started.eq(1), cyc.eq(0), *sample_range()]
        with m.Else(), m.Switch(state):
            with m.Case(_S.CLEAR):
                m.d.comb += [wr.addr.eq((rbank << ab) | x),
                             wr.data.eq(word.const({"z": (1 << Z_BITS) - 1, "addr": NONE, "pix": 0, "slot": 0})),
                             wr.en.eq(x < ghi)]
                m.d.sync += x.eq(x + 1)
                with m.If(x + 1 >= ghi):
                    m.d.sync += [state.eq(_S.SEG), slot.eq(0)]
            with m.Case(_S.SEG):
                m.d.comb += self.i.ready.eq(1)
                with m.If(self.i.valid):
                    m.d.sync += seg.eq(self.i.payload)
                    with m.If(self.i.payload.last):
                        m.d.sync += state.eq(_S.HAND)
                    with m.Else():
                        m.d.sync += state.eq(_S.START)
            with m.Case(_S.START):
                if aj:
                    m.d.comb += [twr.addr.eq((rbank << SLOT_BITS) | slot[:SLOT_BITS]),
                                 twr.en.eq(slot < (1 << SLOT_BITS)),
                                 twr.data.xl.eq(seg.xl), twr.data.xr.eq(seg.xr), twr.data.poly.eq(seg.poly),
                                 twr.data.sl.eq(seg.sl), twr.data.ql.eq(seg.ql), twr.data.sr.eq(seg.sr),
                                 twr.data.qr.eq(seg.qr)]
                    with m.If(slot == (1 << SLOT_BITS)):
                        m.d.sync += self.slot_overflow.eq(1)
                with m.If(s > e):
                    m.d.sync += [state.eq(_S.SEG), slot.eq(slot + 1)]
                with m.Else():
                    m.d.sync += [x.eq(s), end.eq(e), zrun.eq(zstart), irun.eq(istart), state.eq(_S.READ)]
            with m.Case(_S.READ):
                m.d.comb += [rd.addr.eq((rbank << ab) | x), rd.en.eq(1)]
                m.d.sync += state.eq(_S.CMP)
            with m.Case(_S.CMP):
                with m.If(wins):
                    m.d.comb += [wr.addr.eq((rbank << ab) | x), wr.en.eq(1), wr.data.z.eq(key),
                                 wr.data.addr.eq(seg.addr), wr.data.pix.eq(pix), wr.data.slot.eq(slot)]
                m.d.sync += [zrun.eq(zrun + seg.dzdx), irun.eq(irun + seg.didx), x.eq(x + 1)]
                with m.If(x == end):
                    m.d.sync += [state.eq(_S.SEG), slot.eq(slot + 1)]
                with m.Else():
                    m.d.sync += state.eq(_S.READ)
            with m.Case(_S.HAND):
                # swap handshake: the resolved bank goes to the drain once the drain is free
                with m.If(~dbusy):
                    m.d.sync += [*drain.hand(bank=rbank, lo=lo, hi=hi, glo=glo, ghi=ghi),
                                 rbank.eq(~rbank), state.eq(_S.CLEAR),
                                 self.line_cycles.eq(cyc + 1), cyc.eq(0), self.lines.eq(self.lines + 1),
                                 *sample_range()]

        return m
