"""EXPERTS number formats: the one place the machine's widths live.

The paper (seed 000, 3.2) fixes: "EXPERTSの内部データ幅、即ち、SLP、PXPの基本演算データ幅は16ビット
である" (16-bit words in every SLP, PXP, DMM and register file), a logical frame buffer of
"512×512 個の画素", and a 16-bit pixel "色相9ビット、輝度4ビット ... 赤、緑、青それぞれ3ビット".
9 + 4 = 13, not 16; the sister Kyoto paper (seed 001) uses RGBI 3/3/3/7 = 16 bits. We take
**intensity 7 bits as the default** (9 + 7 fills the 16-bit word the text says a pixel is;
the printed "4" leaves 3 bits unexplained) and keep it a parameter, ``intensity_bits``.

Fixed-point formats (``Qm.f``: m integer bits, f fraction bits; ``s`` = two's complement):

==================  =========  ===================================================
field               format     meaning
==================  =========  ===================================================
vertex x, y (PL)    Q10.6      pixels; 0..1023.98 (the frame is 0..512)
ASB xL, xR          Q10.6      left / right edge x at the scan line's centre
ASB zL              Q16.0      depth at the left edge point, 0 = near (z_bits = 16)
ASB iL              QI.(16-I)  intensity at the left edge point, I = intensity_bits
ASB dz/dx           sQ11.4     depth per pixel along the line (saturating)
ASB di/dx           sQ(I-1).(16-I)  intensity per pixel (saturating)
ASB dx/dy, dy/dx    sQ7.8      edge slopes, for anti-jagging only (saturating)
SLP edge accum.     word+16    x, z, i stepped down an edge in 32 bits: the ASB word
                               plus 16 more fraction bits (SLP local memory)
PXP running z       Q16.4      z word + 4 fraction bits (work 1); the register is wide enough
                               never to wrap (40 bits in ours' HDL; the paper's datapath: two
                               16-bit words, |z| < 2**25 at 512 x 512, docs/experts.md "z and i
                               in two words"), the comparator sees the 16-bit key clamped to 0..65535
PXP running i       ASB iL     i word (di/dx has the same fraction bits), clamped when shaded
alpha (A.J.)        Q0.8       mixing ratio, 0..256
==================  =========  ===================================================

Reciprocal ROM (SLP): ``1/d`` with a 16-bit mantissa (``R = round(2**S / d)``,
``S = 15 + bitlen(d)``), used for every division the SLP does (dx/dy, dz/dy, di/dy, eq. (3)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["DATAPATHS", "Datapath", "ADDR_BITS", "SLOT_BITS", "WORD", "FRAME", "HUE_BITS", "X_FRAC", "Z_BITS", "DZ_FRAC", "SLOPE_FRAC", "ACC_EXTRA",
           "ALPHA_BITS", "ASB_WORDS", "Formats", "recip_rom", "rom_div", "sat", "wrap"]

WORD = 16
FRAME = 512
HUE_BITS = 3          # per channel R, G, B
X_FRAC = 6            # x, y: Q10.6
#: the largest frame side: a vertex on the right/bottom edge sits at x = width, and Q10.6 holds at most 1023.98
MAX_SIDE = (1 << (WORD - X_FRAC)) - 1
Z_BITS = 16           # z word, 0 = near
DZ_FRAC = 4           # dz/dx sQ11.4, running z Q16.4
SLOPE_FRAC = 8        # dx/dy, dy/dx sQ7.8
ACC_EXTRA = 16        # SLP edge accumulators: 16 fraction bits beyond the ASB word
ALPHA_BITS = 8        # alpha Q0.8
#: words in one Active Segment Block (fig. 3.2): pointers, RGB+tags, dz/dx di/dx, xL zL iL,
#: dx/dy|L dy/dx|L, xR zR iR, dx/dy|R dy/dx|R, work 1, work 2
ASB_WORDS = 2 + 1 + 2 + 3 + 2 + 3 + 2 + 2


@dataclass(frozen=True)
class Datapath:
    """The width contract of one EXPERTS datapath: what the golden bit model and the HDL share.

    ``word_bits``: the widest register the datapath has; ``acc_extra``: fraction bits the SLP's edge
    accumulators and increments keep beyond the 16-bit ASB word; ``multipliers``: multipliers in the
    processor that has the most (the span PXP's, in ours); ``label``: the paper's or ours.
    """

    name: str
    word_bits: int
    acc_extra: int
    multipliers: int
    label: str


#: ``ours``: today's HDL (40-bit running z and i registers in the PXPs, 32-bit SLP edge accumulators
#: with Q.22 increments of up to 40 bits; the span PXP has three multipliers: z at a span's two ends,
#: i at its start). ``paper``: seed 000, 3.2, "SLP、PXPの基本演算データ幅は16ビットである" and a
#: multiplier a processor ("乗算器 ... を装備"): every SLP edge accumulator and increment is one 16-bit
#: word (the ASB word itself, no extra fraction bits: truncated, see docs/experts.md); the span PXP's
#: running z and i are two words, taken a word a cycle (multi-word, ``span_cycles.multiword``). These are the
#: contracts; what the HDL has is counted from its elaborated design (``hdl/experts/census.py``).
DATAPATHS = {"ours": Datapath("ours", word_bits=40, acc_extra=ACC_EXTRA, multipliers=3, label="ours"),
             "paper": Datapath("paper", word_bits=WORD, acc_extra=0, multipliers=1, label="the paper's")}


@dataclass(frozen=True)
class Formats:
    """The parameters a machine instance may change (everything else above is fixed)."""

    intensity_bits: int = 7
    datapath: Datapath = DATAPATHS["ours"]

    def __post_init__(self) -> None:
        if isinstance(self.intensity_bits, bool) or not isinstance(self.intensity_bits, (int, np.integer)) \
                or not 1 <= self.intensity_bits <= 7:
            raise RasterhwError(f"intensity_bits must be an integer in 1..7 (9 hue bits + I <= 16), "
                                f"not {self.intensity_bits!r}")
        if self.datapath not in DATAPATHS.values():
            raise RasterhwError(f"experts: datapath must be one of {', '.join(DATAPATHS)}, not {self.datapath!r}")

    @property
    def i_frac(self) -> int:
        """Fraction bits of the i word and of di/dx."""
        return WORD - self.intensity_bits

    @property
    def i_max(self) -> int:
        return (1 << self.intensity_bits) - 1

    @property
    def pixel_bits(self) -> int:
        return 3 * HUE_BITS + self.intensity_bits


def sat(v, bits: int, *, signed: bool = True) -> np.ndarray:
    """Saturate integers to a ``bits``-wide field."""
    v = np.asarray(v, dtype=np.int64)
    if signed:
        lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    else:
        lo, hi = 0, (1 << bits) - 1
    return np.clip(v, lo, hi)


def wrap(v, bits: int, *, signed: bool = True) -> np.ndarray:
    """Wrap integers to a ``bits``-wide register (what an adder without saturation does)."""
    v = np.asarray(v, dtype=np.int64) & ((1 << bits) - 1)
    if signed:
        v = np.where(v >= (1 << (bits - 1)), v - (1 << bits), v)
    return v


def recip_rom(d) -> tuple[np.ndarray, np.ndarray]:
    """The SLP's reciprocal ROM: ``|d| -> (R, S)`` with ``R ~= 2**S / |d|`` in 16 bits.

    ``S = 15 + bitlen(|d|)`` puts ``R`` in ``(2**15, 2**16]``; the one value 2**16 (``|d|`` a
    power of two) is stored as 2**16 - 1, the ROM being 16 bits wide. ``d = 0`` returns R = 0.
    """
    d = np.abs(np.asarray(d, dtype=np.int64))
    bl = np.zeros_like(d)
    nz = d > 0
    bl[nz] = np.floor(np.log2(d[nz])).astype(np.int64) + 1
    # log2 of an exact power of two can round down; fix bitlen exactly
    bl = np.where(nz & ((np.int64(1) << np.maximum(bl, 0)) <= d), bl + 1, bl)
    bl = np.where(nz & ((np.int64(1) << np.maximum(bl - 1, 0)) > d), bl - 1, bl)
    s = 15 + bl
    r = np.zeros_like(d)
    r[nz] = np.minimum((((np.int64(1) << s[nz]) + d[nz] // 2) // d[nz]), (1 << 16) - 1)
    return r, s


def rom_div(num, den, shift: int) -> np.ndarray:
    """``round(num * 2**shift / den)`` as the SLP does it: multiply by the ROM reciprocal.

    ``num * R * 2**shift`` is rounded half away from zero and shifted right by ``S``.
    """
    num = np.asarray(num, dtype=np.int64)
    den = np.asarray(den, dtype=np.int64)
    r, s = recip_rom(den)
    sign = np.sign(num) * np.sign(den)
    p = np.abs(num) * r
    if shift >= 0:
        p = p << shift
        q = (p + (np.int64(1) << (s - 1))) >> s
    else:
        sh = s - shift
        q = (p + (np.int64(1) << (sh - 1))) >> sh
    return np.where(den == 0, 0, sign * q)

# the PXP's address and segment-table widths (the HDL and the cycle model take them from here)
ADDR_BITS = 12   # ASB address (PL order) and polygon number: up to 4095 (4095 = none)
SLOT_BITS = 8    # the A.J. segment table: 256 segments per line (= a DMM/P bank)

# widths derived from the names above: what the HDL's fields and registers are (no new numbers)
X_INT = WORD - X_FRAC           # integer bits of Q10.6: a line or pixel number, 0..MAX_SIDE
X_END_BITS = X_INT + 1          # a pixel x or an exclusive range end, 0..MAX_SIDE + 1
XS_BITS = WORD + 1              # a Q10.6 x or y held signed (the SLP's vertices)
RGB_BITS = 3 * HUE_BITS         # the hue field: R, G, B
INC_BITS = 3 * WORD             # an SLP edge-increment field, three words: the Q.22 increment
                                # (X_FRAC + ACC_EXTRA fraction bits) is up to 40 bits
XP_BITS = X_END_BITS + 1        # a pixel x with a spare bit: held signed, a segment's first pixel may lie left of 0
XD_BITS = XS_BITS + 1           # a difference of two such, or a Q10.6 line centre held signed
