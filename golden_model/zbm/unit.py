"""A ZB/M unit for one scan line / a frame: the segment generator's segments through every
chip of the interleave (and the bit-identical whole-unit shortcut).

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm.chip import _insert, _samples, chip_scanline, sample_z
from rasterhw.golden_model.zbm.doublez import DoubleZ, arrival_layers, nearest_two
from rasterhw.golden_model.zbm.formats import (
    wrap,
)
from rasterhw.golden_model.zbm.seggen import Segments

__all__ = ["unit_frame", "unit_scanline", "segment_fragments"]


def unit_scanline(segs: Segments, y: int, interleave: int, width: int) -> tuple[DoubleZ, dict]:
    """All chips of a unit on line ``y``, their memories interleaved back to screen order."""
    line = DoubleZ.empty((width,))
    tot = {"packets": 0, "pixels": 0, "writes": 0}
    for chip in range(min(interleave, width)):
        b, st = chip_scanline(segs, y, chip, interleave, width)
        xs = np.arange(chip, width, interleave)
        line.z[xs], line.a[xs], line.c[xs], line.tag[xs] = b.z, b.a, b.c, b.tag
        for k in tot:
            tot[k] += st[k]
    return line, tot


def _unit_frame_fast(segs: Segments, height: int, width: int) -> tuple[DoubleZ, dict]:
    """Bit-identical shortcut for a whole unit: value at pixel x = v + (x - x0) * inc (mod 2**56).

    Holds because the initial processor's ``j * inc`` plus ``k`` loop adds of ``inc << log2 I``
    is ``(j + k * I) * inc`` in modular integer arithmetic, so the image does not depend on
    the interleave (a test checks it against :func:`chip_scanline`).
    """
    buf = DoubleZ.empty((height, width))
    flat = DoubleZ(buf.z.reshape(-1, 2), buf.a.reshape(-1, 2), buf.c.reshape(-1, 2, 4), buf.tag.reshape(-1, 2))
    seg, k = segment_fragments(segs)
    # the same int64 operations as one segment at a time (products wrap mod 2**64, then to 56 bits)
    vals = wrap(segs.val[seg] + k[:, None] * segs.inc[seg])
    z, a, c = _samples(vals, segs.mode)
    pos = segs.y[seg] * width + segs.x[seg] + k
    tag = segs.tag[seg]
    writes = 0
    for ly in arrival_layers(pos):   # fragments in emission order, one vectorised step per layer
        writes += _insert(flat, pos[ly], z[ly], a[ly], c[ly], tag[ly])
    return buf, {"pixels": int(k.size), "writes": writes, "packets": None}


def unit_frame(segs: Segments, height: int, width: int) -> DoubleZ:
    """:func:`_unit_frame_fast`'s buffer without its counts: the two nearest samples of each
    pixel by (z, emission) (:func:`nearest_two`; every sample z is at most ``Z_MAX_SAMPLE``,
    nearer than ``Z_EMPTY``), without inserting layer by layer (the write count needs that)."""
    buf = DoubleZ.empty((height, width))
    flat = DoubleZ(buf.z.reshape(-1, 2), buf.a.reshape(-1, 2), buf.c.reshape(-1, 2, 4), buf.tag.reshape(-1, 2))
    seg, k = segment_fragments(segs)
    # the same int64 operations as _unit_frame_fast's, the other channels only for the kept samples
    z = sample_z(wrap(segs.val[seg, 0] + k * segs.inc[seg, 0]))
    pix, f, s = nearest_two(segs.y[seg] * width + segs.x[seg] + k, z)
    two = s >= 0
    for j, (p, i) in enumerate(((pix, f), (pix[two], s[two]))):
        _, a, c = _samples(wrap(segs.val[seg[i]] + k[i, None] * segs.inc[seg[i]]), segs.mode)
        flat.z[p, j], flat.a[p, j], flat.c[p, j], flat.tag[p, j] = z[i], a, c, segs.tag[seg[i]]
    return buf


def segment_fragments(segs: Segments) -> tuple[np.ndarray, np.ndarray]:
    """Every covered pixel of every segment in emission order: (segment index, pixel offset
    ``k`` in ``0..len-1``), both (N,) int64."""
    n = np.asarray(segs.len, np.int64)
    seg = np.repeat(np.arange(n.size), n)
    start = np.cumsum(n) - n
    return seg, np.arange(seg.size, dtype=np.int64) - start[seg]
