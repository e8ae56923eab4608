"""ZB/M fixed-point formats: every field the hardware carries, in hardware order.

This file is the contract between the golden model (``golden_model/zbm/``) and the HDL
(``hdl/zbm_*.py``): the same widths, fractional bits, signedness, rounding and bit order.
Words are packed **LSB first**: the first field of a layout sits in bit 0.

Where the numbers come from (seed 003, Matsushita ZB/M; our translation in quotes):

* edge pair = "a polygon whose top and bottom sides are parallel to the scan line"; its input
  is "the (x, y, z) of the top-left vertex, the horizontal length of the edge (len), the
  mapping coordinates (u, v), their increments one scan line down (dx/dy, dlen/dy, ...) and
  their increments one pixel to the right (dz/dx, ...)" (sec. 4.1);
* "loading an edge pair into the segment generator takes 9 cycles" (sec. 6.1, cond. 4): we
  make the edge-pair record 9 words, one per cycle: a header and one word per channel of the
  mapping variant (x, len, z, um, vm, ui, vi, alpha = 8 channels);
* the segment generator outputs "segment data containing the left-end parameter values and
  the horizontal increments" (sec. 4.1);
* "the segment loop is 112 bits wide ... a segment packet is at most 8 cycles long, and only
  one segment packet is in the loop at a time" (sec. 5.4): one 112-bit flit = one channel's
  (value, per-pixel increment) pair, 56 + 56 bits; a packet is always sent as 8 flits (unused
  ones zero) so its length does not depend on the mode -- the paper's cycle estimate counts 8;
* DDA channels "x, len, z, r, g, b, alpha" or "x, len, z, um, vm, ui, vi, alpha" (sec. 5.4);
* double Z: "always keep the Z values and pixel data of the nearest 2 points" (sec. 5.2).

Screen: frames up to 512 x 512 (the paper's scan-line memories); vertices snapped to the
reference rasteriser's 1/256-px grid; Z is 24 bits, **0 = near**, and ``Z_EMPTY = 0xFFFFFF``
is reserved for "no sample" (real samples are clamped to ``0xFFFFFE``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS

__all__ = [
    "SCHEDULES", "GAP_PENDING", "paper_lead",
    "MAX_WIDTH", "MAX_HEIGHT", "SUBPIX_BITS", "COORD_LIMIT", "X_FRAC", "ATTR_FRAC", "OFF_FRAC",
    "SLOT_BITS", "Z_BITS", "Z_EMPTY", "Z_MAX_SAMPLE", "COLOUR_BITS", "TEX_BITS",
    "EP_WORDS", "EP_LOAD_CYCLES", "LOOP_BITS", "PACKET_FLITS", "PP_PER_CHIP", "INTERLEAVES",
    "AEP_CAPACITY", "MODE_COLOUR", "MODE_MAPPING", "CHANNELS",
    "check_interleave", "Field", "Layout", "EP_HEADER", "EP_CHANNEL", "SEG_HEADER", "FLIT", "PKT_HEADER",
    "SAMPLE", "PIXEL2",
    "wrap", "to_fixed_floor", "slot_check",
    "pack_edge_pair", "unpack_edge_pair", "pack_segment", "unpack_segment",
    "pack_samples", "unpack_samples",
]

# ---------------------------------------------------------------- global parameters
MAX_WIDTH = 512          #: pixels per scan line the chips' line memories hold (x: 10 bits u)
MAX_HEIGHT = 512         #: scan lines (y: 9 bits u)
SUBPIX_BITS = SUBPIXEL_BITS  #: vertices snapped to 1/256 px, round half up (screen.snap)
COORD_LIMIT = 2048       #: |vertex coordinate| < 2048 px (12 integer bits incl. sign)
X_FRAC = 40              #: x, len, dx/dy, dlen/dy: signed Q.40 pixels, floor-rounded
ATTR_FRAC = 24           #: z, colour, alpha, u, v values and increments: signed Q.24
OFF_FRAC = 16           #: sub-pixel offset used for the left-end correction: unsigned Q.16 (floor)
SLOT_BITS = 56           #: every value/increment slot is a signed 56-bit two's complement number
Z_BITS = 24              #: stored depth
Z_EMPTY = (1 << Z_BITS) - 1      #: clear value of a sample slot: "no sample"
Z_MAX_SAMPLE = Z_EMPTY - 1       #: real samples are clamped to this
COLOUR_BITS = 8          #: r, g, b, alpha stored per sample
TEX_BITS = 8             #: texture / illumination maps are 256 x 256 (u, v wrap)
EP_WORDS = 9             #: edge-pair record: header + 8 channel words
EP_LOAD_CYCLES = 9       #: paper, sec. 6.1 cond. 4: one word per cycle
LOOP_BITS = 112          #: segment-loop width (paper, sec. 5.4)
PACKET_FLITS = 8         #: segment packet length in loop cycles (paper: "at most 8")
PP_PER_CHIP = 8          #: pixel processors per ZB/M chip (paper, fig. 5)
INTERLEAVES = (1, 2, 4, 8, 16)   #: chips per unit (paper, sec. 5.3)
AEP_CAPACITY = 256       #: active-edge-pair memory depth (paper silent; our choice)

MODE_COLOUR = 0          #: DDA channels x, len, z, r, g, b, alpha
MODE_MAPPING = 1         #: DDA channels x, len, z, um, vm, ui, vi, alpha
#: attribute channels after x and len, in hardware order, per mode
CHANNELS = {
    MODE_COLOUR: ("z", "r", "g", "b", "a"),
    MODE_MAPPING: ("z", "um", "vm", "ui", "vi", "a"),
}

_SLOT_MIN = -(1 << (SLOT_BITS - 1))
_SLOT_MAX = (1 << (SLOT_BITS - 1)) - 1


def check_interleave(interleave, chip=None) -> None:
    """The one check of the ZB/M interleave, for the golden model, the HDL blocks' signatures
    (``hdl/zbm/layouts.py`` re-exports it) and the drivers: ``interleave`` one of
    :data:`INTERLEAVES` (paper, sec. 5.3) and, if given, ``0 <= chip < interleave``; else
    :class:`RasterhwError` (one line on the command line)."""
    if not isinstance(interleave, (int, np.integer)) or isinstance(interleave, bool) or interleave not in INTERLEAVES:
        raise RasterhwError(f"ZB/M: interleave must be 1, 2, 4, 8 or 16, not {interleave!r}")
    if chip is not None and not (isinstance(chip, (int, np.integer)) and not isinstance(chip, bool)
                                 and 0 <= chip < interleave):
        raise RasterhwError(f"ZB/M: chip must be in 0..{interleave - 1}, not {chip!r}")


def wrap(v, bits: int = SLOT_BITS, signed: bool = True):
    """Two's-complement wrap of ``v`` (int or int64 array) to ``bits``, as a hardware adder does."""
    mask = (1 << bits) - 1
    if isinstance(v, np.ndarray):
        v = v.astype(np.int64) & np.int64(mask)
        if signed:
            v = np.where(v >= (1 << (bits - 1)), v - (1 << bits), v)
        return v
    v = int(v) & mask
    if signed and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


def to_fixed_floor(x: np.ndarray, frac: int) -> np.ndarray:
    """float -> int64 with ``frac`` fractional bits, floor (used only where inputs are exact)."""
    return np.floor(np.asarray(x, dtype=np.float64) * (1 << frac)).astype(np.int64)


def slot_check(name: str, v: np.ndarray) -> None:
    """Raise :class:`RasterhwError` if any value does not fit a signed 56-bit slot."""
    v = np.asarray(v)
    if v.size and (v.min() < _SLOT_MIN or v.max() > _SLOT_MAX):
        bad = int(v.max() if v.max() > _SLOT_MAX else v.min())
        raise RasterhwError(f"ZB/M: {name} = {bad} does not fit a signed {SLOT_BITS}-bit slot")


# ---------------------------------------------------------------- layouts
@dataclass(frozen=True)
class Field:
    """One field of a hardware word.

    ``frac`` is the number of fractional bits (0 = integer; -1 = depends on the channel:
    ``X_FRAC`` for x and len, ``ATTR_FRAC`` for the attributes); ``meaning`` cites the paper.
    """

    name: str
    width: int
    signed: bool = False
    frac: int = 0
    meaning: str = ""


class Layout:
    """An ordered list of fields packed LSB first into one integer word."""

    def __init__(self, name: str, fields: list[Field], width: int | None = None):
        self.name = name
        self.fields = tuple(fields)
        self.offsets: dict[str, int] = {}
        off = 0
        for f in self.fields:
            self.offsets[f.name] = off
            off += f.width
        self.used = off
        self.width = off if width is None else width
        if self.used > self.width:
            raise ValueError(f"layout {name}: fields need {self.used} bits, word has {self.width}")

    def __getitem__(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(name)

    def pack(self, **values: int) -> int:
        """Fields (ints; missing ones are 0) -> one word. Out-of-range values raise."""
        unknown = set(values) - set(self.offsets)
        if unknown:
            raise RasterhwError(f"{self.name}: unknown field(s) {sorted(unknown)}")
        word = 0
        for f in self.fields:
            v = int(values.get(f.name, 0))
            lo, hi = (-(1 << (f.width - 1)), (1 << (f.width - 1)) - 1) if f.signed else (0, (1 << f.width) - 1)
            if not lo <= v <= hi:
                raise RasterhwError(f"{self.name}.{f.name} = {v} does not fit {f.width} bits "
                                    f"({'signed' if f.signed else 'unsigned'})")
            word |= (v & ((1 << f.width) - 1)) << self.offsets[f.name]
        return word

    def unpack(self, word: int) -> dict[str, int]:
        """One word -> dict of field values (signed fields sign-extended)."""
        out = {}
        for f in self.fields:
            v = (int(word) >> self.offsets[f.name]) & ((1 << f.width) - 1)
            if f.signed and v >= 1 << (f.width - 1):
                v -= 1 << f.width
            out[f.name] = v
        return out


def _slot(name: str, frac: int, meaning: str) -> Field:
    return Field(name, SLOT_BITS, True, frac, meaning)


# Edge-pair record, word 0 (header). 168-bit words (3 slots) on the loader bus.
EP_WORD_BITS = 3 * SLOT_BITS
EP_HEADER = Layout("ep_header", [
    Field("y", 9, meaning="first scan line whose pixel centre is inside the trapezoid (the top; paper: "
                          "'top-left vertex (x, y, z)')"),
    Field("h", 10, meaning="number of scan lines, 1..512 (paper silent: the generator must know when "
                           "the pair ends)"),
    Field("mode", 1, meaning="0 = colour (x,len,z,r,g,b,a), 1 = mapping (x,len,z,um,vm,ui,vi,a)"),
], width=EP_WORD_BITS)
# Edge-pair record, words 1..8: one per channel: value, per-line increment, per-pixel increment.
#   word 1: x   : value = left-edge x at the centre of line y, Q.40 px (floor); ddy = dx/dy (floor); ddx = 0
#   word 2: len : value = right-edge x - left-edge x, Q.40 (>= 0); ddy = dlen/dy; ddx = 0
#   words 3..: attribute channels CHANNELS[mode], Q.24 (round to nearest):
#       value = attribute on the left edge at line y's centre, ddy = d/dy along the left edge
#       (= plane d/dy + dx/dy * plane d/dx), ddx = plane d/dx.  Units: z in 24-bit Z LSBs
#       (0 = near), r/g/b/a in 8-bit LSBs (0..255), um/vm/ui/vi in texels.
#   colour mode: word 8 is zero.
EP_CHANNEL = Layout("ep_channel", [
    _slot("value", -1, "value at the left edge of line y (x, len: Q.40; attributes: Q.24)"),
    _slot("ddy", -1, "increment one scan line down (paper: dx/dy, dlen/dy, ...)"),
    _slot("ddx", -1, "increment one pixel right (paper: dz/dx, ...); 0 for x and len"),
], width=EP_WORD_BITS)

# Segment record: segment generator -> every chip of the unit (segment input port).
# Word 0 header, then one 112-bit word per attribute channel (same layout as a loop flit).
SEG_HEADER = Layout("seg_header", [
    Field("y", 9, meaning="scan line"),
    Field("x", 10, meaning="first covered pixel (top-left rule, clipped to the frame)"),
    Field("len", 10, meaning="covered pixels, 1..512 (paper: 'len')"),
    Field("mode", 1, meaning="as EP_HEADER.mode"),
], width=LOOP_BITS)
FLIT = Layout("flit", [
    _slot("value", ATTR_FRAC, "channel value at the pixel centre (segment: at pixel x; packet: at the "
                              "chip's first pixel), Q.24"),
    _slot("inc", ATTR_FRAC, "per-pixel increment (segment: d/dx; packet: d/dx * interleave), Q.24"),
], width=LOOP_BITS)
# Segment packet on a chip's 112-bit loop: flit 0 = PKT_HEADER, flits 1.. = FLIT per channel of
# CHANNELS[mode], then zero flits up to PACKET_FLITS (8) -- colour uses 6, mapping 7.
PKT_HEADER = Layout("pkt_header", [
    Field("x", 10, meaning="screen x of the first pixel of the segment this chip owns"),
    Field("len", 10, meaning="pixels of the segment this chip owns (>= 1); each pixel processor "
                             "decrements it"),
    Field("y", 9, meaning="scan line"),
    Field("mode", 1, meaning="as EP_HEADER.mode"),
    Field("dx", 5, meaning="screen-x step per chip pixel = interleave (1..16)"),
], width=LOOP_BITS)

# Per-pixel sample (64 bits). Colour mode: c0..c2 = r, g, b, c3 = 0; mapping mode:
# c0..c3 = um, vm, ui, vi (texel index, wrapped to TEX_BITS) -- mapping happens after the merge.
SAMPLE = Layout("sample", [
    Field("z", Z_BITS, meaning="depth, 0 = near; 0xFFFFFF = no sample (clear value)"),
    Field("a", COLOUR_BITS, meaning="alpha, 255 = opaque"),
    Field("c0", 8, meaning="r or um"),
    Field("c1", 8, meaning="g or vm"),
    Field("c2", 8, meaning="b or ui"),
    Field("c3", 8, meaning="0 or vi"),
])
# Double-Z pixel = the merge-bus word and the merge-port word: s0 (nearer or equal), s1.
PIXEL2 = Layout("pixel2", [
    Field("s0", 64, meaning="nearest sample (paper: 'the nearest 2 points')"),
    Field("s1", 64, meaning="second nearest sample"),
])


# ---------------------------------------------------------------- record helpers
def pack_edge_pair(header: dict, channels: list[dict]) -> list[int]:
    """Header fields + per-channel dicts (value, ddy, ddx) -> the 9 loader words (ints)."""
    mode = int(header["mode"])
    names = ("x", "len") + CHANNELS[mode]
    if len(channels) != len(names):
        raise RasterhwError(f"edge pair: mode {mode} needs {len(names)} channel words, got {len(channels)}")
    words = [EP_HEADER.pack(**header)] + [EP_CHANNEL.pack(**c) for c in channels]
    return words + [0] * (EP_WORDS - len(words))


def unpack_edge_pair(words: list[int]) -> tuple[dict, list[dict]]:
    """Inverse of :func:`pack_edge_pair`."""
    if len(words) != EP_WORDS:
        raise RasterhwError(f"edge pair: expected {EP_WORDS} words, got {len(words)}")
    h = EP_HEADER.unpack(words[0])
    n = 2 + len(CHANNELS[h["mode"]])
    return h, [EP_CHANNEL.unpack(w) for w in words[1:1 + n]]


def pack_segment(header: dict, channels: list[dict]) -> list[int]:
    """Segment header + per-channel (value, inc) -> words on the segment input port."""
    return [SEG_HEADER.pack(**header)] + [FLIT.pack(**c) for c in channels]


def unpack_segment(words: list[int]) -> tuple[dict, list[dict]]:
    """Inverse of :func:`pack_segment`."""
    h = SEG_HEADER.unpack(words[0])
    return h, [FLIT.unpack(w) for w in words[1:]]


def pack_samples(z, a, c) -> np.ndarray:
    """Arrays z (...), a (...), c (..., 4) -> uint64 sample words (vectorised)."""
    z = np.asarray(z, dtype=np.uint64)
    a = np.asarray(a, dtype=np.uint64)
    c = np.asarray(c, dtype=np.uint64)
    w = z | (a << np.uint64(24))
    for i in range(4):
        w |= c[..., i] << np.uint64(32 + 8 * i)
    return w


def unpack_samples(w) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """uint64 sample words -> (z, a, c (..., 4)) int64 arrays."""
    w = np.asarray(w, dtype=np.uint64)
    z = (w & np.uint64(0xFFFFFF)).astype(np.int64)
    a = ((w >> np.uint64(24)) & np.uint64(0xFF)).astype(np.int64)
    c = np.stack([((w >> np.uint64(32 + 8 * i)) & np.uint64(0xFF)).astype(np.int64) for i in range(4)], axis=-1)
    return z, a, c


# ---------------------------------------------------------------- derived constants
PP_BITS = PP_PER_CHIP.bit_length() - 1         # pixel-processor index bits (8 -> 3)
FLIT_BITS = PACKET_FLITS.bit_length() - 1      # flit index bits within a packet (8 -> 3)
SUB = 1 << SUBPIX_BITS          # sub-pixel grid, 256
HALF_SUB = SUB // 2
ONE_X = 1 << X_FRAC
HALF_X = ONE_X >> 1
ONE_A = 1 << ATTR_FRAC
HALF_A = ONE_A >> 1
Z_SCALE = (1 << Z_BITS) - 1     # float z in [0, 1] -> Z LSBs (same as ScreenTriangles.zq)
TEX = 1 << TEX_BITS
INC_LIMIT = (1 << 47) - 1       # attribute increments saturate here (keeps offset * inc in int64)
VAL_LIMIT = (1 << 53) - 1       # attribute start values saturate here (room for 511 line steps)


# ---------------------------------------------------------------- schedules (sec. 6.1; the HDL and
# the cycle model both take them from here)
SCHEDULES = ("overlap", "paper")
#: ring gap value meaning "a packet is pending in the chip" (larger than any real gap)
GAP_PENDING = 1023


def paper_lead(mode: int) -> int:
    """Cycles from a chip accepting a segment header to that packet's header entering the
    ring (``1 + channels`` words into the initial processor, one cycle into the segment
    processor): 7 (colour), 8 (mapping). In the paper schedule a chip accepts a header only
    when its ring gap is at most this, so the packet starts exactly when the ring frees."""
    return len(CHANNELS[mode]) + 2
