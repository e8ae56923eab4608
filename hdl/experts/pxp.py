"""EXPERTS pixel processor (PXP) datapath: start values, z/i stepping, 16-bit depth compare, DSLB.

Paper (seed 000, 3.2): the PXP takes the ASL for its part of the scan line, computes the start
values at its first pixel with its multiplier ("担当範囲の開始点における ... 初期データを計算する",
"PXPにおいても ... 乗算が多数出現するため ... 乗算器を装備"), resolves hidden surfaces and
shading up to its last pixel and writes its DSLB.

This block resolves depth segment by segment into a line depth buffer kept beside the DSLB
(one memory word per pixel: z key, ASB address, pixel), which gives exactly the golden depth
search's pixels (16-bit key, ties to the lower ASB address). Bit- and cycle-exact with
``golden_model.experts.pxp_cycles`` (cycle formula there). Not in this block: A.J., the
double-banked DMM/P and DSLB (one bank: the line is drained before the next is cleared).

Input protocol: per line, the clipped ASL segments (``SEG`` payloads with ``last = 0``) in ASL
order, then one ``last = 1`` token; ``lo``/``hi`` (the range ``[lo, hi)``) are sampled when a line
starts. Output: the line's ``hi - lo`` pixel words, left to right, after its last token.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import DZ_FRAC, HUE_BITS, X_FRAC, Z_BITS, Formats
from rasterhw.golden_model.experts.pxp_cycles import ADDR_BITS

__all__ = ["ExpertsPxp", "seg_layout"]


def seg_layout() -> data.StructLayout:
    """One ASB as the PXP reads it (the fields it uses)."""
    return data.StructLayout({
        "last": unsigned(1),          # end of the line's list
        "xl": unsigned(16),           # Q10.6
        "xr": unsigned(16),           # Q10.6
        "zl": unsigned(16),           # Q16.0, 0 = near
        "il": unsigned(16),           # Q(I).(16-I)
        "dzdx": signed(16),           # sQ11.4
        "didx": signed(16),           # sQ(I-1).(16-I)
        "hue": unsigned(3 * HUE_BITS),
        "addr": unsigned(ADDR_BITS),  # ASB address = PL order: the tie-break
    })


class _S(enum.Enum, shape=3):
    CLEAR = 0
    SEG = 1
    START = 2
    READ = 3
    CMP = 4
    DRD = 5
    DOUT = 6


class ExpertsPxp(wiring.Component):
    """One PXP: clipped ASL in, the range's pixel words out, line by line.

    Parameters
    ----------
    width : int
        Frame width (1..1024): depth of the line memory.
    intensity_bits : int
        Intensity field width (1..7); the pixel word is ``3 * 3 + intensity_bits`` bits.

    Members
    -------
    i : In(stream.Signature(seg_layout()))
    o : Out(stream.Signature(unsigned(9 + intensity_bits)))
    lo, hi : In(10), In(11)
        The range ``[lo, hi)``, sampled at the start of each line.
    line_cycles : Out(16)
        Finish-time counter: cycles of the last finished line (clear to last pixel out).
    lines : Out(16)
        Lines finished.

    Latency / throughput: per line ``R + sum(2 + 2 n) + 1 + 2 R`` cycles with the input always
    valid and the output always ready (R pixels, n owned pixels per segment).
    """

    def __init__(self, *, width: int = 512, intensity_bits: int = 7):
        if isinstance(width, bool) or not isinstance(width, int) or not 1 <= width <= 1024:
            raise ValueError(f"width must be an integer in 1..1024, not {width!r}")
        self._fmt = Formats(intensity_bits)
        self._width = width
        super().__init__({
            "i": In(stream.Signature(seg_layout())),
            "o": Out(stream.Signature(unsigned(self._fmt.pixel_bits))),
            "lo": In(10),
            "hi": In(11),
            "line_cycles": Out(16),
            "lines": Out(16),
        })

    @property
    def width(self) -> int:
        return self._width

    @property
    def intensity_bits(self) -> int:
        return self._fmt.intensity_bits

    def elaborate(self, platform):
        m = Module()
        fmt = self._fmt
        pb = fmt.pixel_bits
        word = data.StructLayout({"z": unsigned(Z_BITS), "addr": unsigned(ADDR_BITS), "pix": unsigned(pb)})
        m.submodules.mem = mem = Memory(shape=word, depth=self._width, init=[])
        rd = mem.read_port(transparent_for=())
        wr = mem.write_port()

        state = Signal(_S)
        x = Signal(11)
        end = Signal(11)          # last owned pixel of the segment / last pixel of the range
        lo = Signal(10)
        hi = Signal(11)
        seg = Signal(seg_layout())
        zrun = Signal(signed(40))
        irun = Signal(signed(40))
        cyc = Signal(16)

        c0 = Signal(signed(12))
        c1 = Signal(signed(12))
        s = Signal(signed(12))
        e = Signal(signed(12))
        m.d.comb += [
            c0.eq((seg.xl + 31) >> X_FRAC),
            c1.eq(((seg.xr + 31) >> X_FRAC) - 1),
            s.eq(Mux(c0 > lo, c0, lo)),
            e.eq(Mux(c1 < hi - 1, c1, hi - 1)),
        ]
        d = Signal(signed(20))
        m.d.comb += d.eq((s << X_FRAC) + (1 << (X_FRAC - 1)) - seg.xl)
        # the multiplier: start values at the first owned pixel
        zstart = Signal(signed(40))
        istart = Signal(signed(40))
        m.d.comb += [
            zstart.eq((seg.zl << DZ_FRAC) + ((d * seg.dzdx) >> X_FRAC)),
            istart.eq(seg.il + ((d * seg.didx) >> X_FRAC)),
        ]
        # compare key (16-bit comparator on the clamped running z) and the shaded pixel
        zk = Signal(signed(40))
        key = Signal(Z_BITS)
        m.d.comb += zk.eq(zrun >> DZ_FRAC)
        m.d.comb += key.eq(Mux(zk < 0, 0, Mux(zk > (1 << Z_BITS) - 1, (1 << Z_BITS) - 1, zk)))
        imax = fmt.i_max << fmt.i_frac
        ic = Signal(16)
        m.d.comb += ic.eq(Mux(irun < 0, 0, Mux(irun > imax, imax, irun)))
        pix = Signal(pb)
        m.d.comb += pix.eq((seg.hue << fmt.intensity_bits) | (ic >> fmt.i_frac))
        stored = Signal(word)
        m.d.comb += stored.eq(rd.data)
        wins = Signal()
        m.d.comb += wins.eq((key < stored.z) | ((key == stored.z) & (seg.addr < stored.addr)))

        m.d.comb += [rd.en.eq(0), wr.en.eq(0), self.i.ready.eq(0), self.o.valid.eq(0),
                     self.o.payload.eq(stored.pix)]
        m.d.sync += cyc.eq(cyc + 1)
        started = Signal()

        with m.If(~started):
            # out of reset: sample the first line's range
            m.d.sync += [started.eq(1), lo.eq(self.lo), hi.eq(self.hi), x.eq(self.lo), cyc.eq(0)]
        with m.Else(), m.Switch(state):
            with m.Case(_S.CLEAR):
                m.d.comb += [wr.addr.eq(x), wr.data.eq(word.const({"z": (1 << Z_BITS) - 1,
                                                                   "addr": (1 << ADDR_BITS) - 1, "pix": 0})),
                             wr.en.eq(x < hi)]
                m.d.sync += x.eq(x + 1)
                with m.If(x + 1 >= hi):
                    m.d.sync += state.eq(_S.SEG)
            with m.Case(_S.SEG):
                m.d.comb += self.i.ready.eq(1)
                with m.If(self.i.valid):
                    m.d.sync += seg.eq(self.i.payload)
                    with m.If(self.i.payload.last):
                        m.d.sync += [state.eq(_S.DRD), x.eq(lo)]
                    with m.Else():
                        m.d.sync += state.eq(_S.START)
            with m.Case(_S.START):
                with m.If(s > e):
                    m.d.sync += state.eq(_S.SEG)
                with m.Else():
                    m.d.sync += [x.eq(s), end.eq(e), zrun.eq(zstart), irun.eq(istart), state.eq(_S.READ)]
            with m.Case(_S.READ):
                m.d.comb += [rd.addr.eq(x), rd.en.eq(1)]
                m.d.sync += state.eq(_S.CMP)
            with m.Case(_S.CMP):
                with m.If(wins):
                    m.d.comb += [wr.addr.eq(x), wr.en.eq(1), wr.data.z.eq(key), wr.data.addr.eq(seg.addr), wr.data.pix.eq(pix)]
                m.d.sync += [zrun.eq(zrun + seg.dzdx), irun.eq(irun + seg.didx), x.eq(x + 1)]
                with m.If(x == end):
                    m.d.sync += state.eq(_S.SEG)
                with m.Else():
                    m.d.sync += state.eq(_S.READ)
            with m.Case(_S.DRD):
                m.d.comb += [rd.addr.eq(x), rd.en.eq(1)]
                m.d.sync += state.eq(_S.DOUT)
            with m.Case(_S.DOUT):
                m.d.comb += self.o.valid.eq(1)
                with m.If(self.o.ready):
                    m.d.sync += x.eq(x + 1)
                    with m.If(x + 1 >= hi):
                        # line done: latch the finish-time counter, start the next line
                        m.d.sync += [state.eq(_S.CLEAR), self.line_cycles.eq(cyc + 1), cyc.eq(0),
                                     self.lines.eq(self.lines + 1), x.eq(self.lo), lo.eq(self.lo),
                                     hi.eq(self.hi)]
                    with m.Else():
                        m.d.sync += state.eq(_S.DRD)
        return m
