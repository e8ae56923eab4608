"""A ZB/M unit for one scan line / a frame: the segment generator's segments through every
chip of the interleave (and the bit-identical whole-unit shortcut).

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm.chip import _insert, _samples, chip_scanline
from rasterhw.golden_model.zbm.doublez import DoubleZ
from rasterhw.golden_model.zbm.formats import (
    wrap,
)
from rasterhw.golden_model.zbm.seggen import Segments

__all__ = ["unit_scanline"]


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
    pixels = writes = 0
    for s in range(segs.y.shape[0]):
        k = np.arange(segs.len[s])
        vals = wrap(segs.val[s][None, :] + k[:, None] * segs.inc[s][None, :])
        z, a, c = _samples(vals, segs.mode)
        pos = segs.y[s] * width + segs.x[s] + k
        writes += _insert(flat, pos, z, a, c, np.full(k.size, segs.tag[s]))
        pixels += int(k.size)
    return buf, {"pixels": pixels, "writes": writes, "packets": None}
