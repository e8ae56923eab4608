"""One ZB/M chip for one scan line: the segment loop of 8 pixel processors DDA-stepping each
packet and Z-testing into the double-Z pixel memories.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm.doublez import DoubleZ
from rasterhw.golden_model.zbm.formats import (
    ATTR_FRAC,
    HALF_A,
    MODE_COLOUR,
    TEX,
    Z_MAX_SAMPLE,
    check_interleave,
    wrap,
)
from rasterhw.golden_model.zbm.initial import initial_processor
from rasterhw.golden_model.zbm.seggen import Segments

__all__ = ["chip_scanline", "sample_z"]


def sample_z(v: np.ndarray) -> np.ndarray:
    """The depth channel's DDA values (N,) Q.24 -> sample z: round half up, clamp."""
    return np.clip((v + HALF_A) >> ATTR_FRAC, 0, Z_MAX_SAMPLE)


def _samples(v: np.ndarray, mode: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel DDA values (N, C) Q.24 -> sample fields z, a, c (N, 4). Round half up, clamp."""
    r = (v + HALF_A) >> ATTR_FRAC
    z = sample_z(v[:, 0])
    a = np.clip(r[:, -1], 0, 255)
    c = np.zeros((v.shape[0], 4), np.int64)
    if mode == MODE_COLOUR:
        c[:, :3] = np.clip(r[:, 1:4], 0, 255)
    else:   # texel index: floor, wrapped to the 256-texel map
        c[:, :4] = (v[:, 1:5] >> ATTR_FRAC) & (TEX - 1)
    return z, a, c


def _insert(buf: DoubleZ, pos: np.ndarray, z, a, c, tag) -> int:
    """Double-Z insert at distinct positions; strict ``<``: on a tie the stored sample stays."""
    z0, z1 = buf.z[pos, 0], buf.z[pos, 1]
    f = z < z0                  # new becomes nearest, old nearest moves to second
    s = (~f) & (z < z1)         # new becomes second
    pf, ps = pos[f], pos[s]
    for arr in (buf.z, buf.a, buf.tag):
        arr[pf, 1] = arr[pf, 0]
    buf.c[pf, 1] = buf.c[pf, 0]
    buf.z[pf, 0], buf.a[pf, 0], buf.c[pf, 0], buf.tag[pf, 0] = z[f], a[f], c[f], tag[f]
    buf.z[ps, 1], buf.a[ps, 1], buf.c[ps, 1], buf.tag[ps, 1] = z[s], a[s], c[s], tag[s]
    return int(f.sum() + s.sum())


def chip_scanline(segs: Segments, y: int, chip: int, interleave: int, width: int,
                  buf: DoubleZ | None = None) -> tuple[DoubleZ, dict]:
    """One chip, one scan line: segment packets through the loop, double-Z pixel memories.

    The pixel memory holds the chip's ``ceil(width / I)`` pixels (chip pixel ``q`` = screen x
    ``q * I + chip``; pixel processor ``q % 8`` owns it). For each segment of line ``y``, in
    emission order, the initial processor forms the packet (:func:`initial_processor`), and
    pixel ``k`` of the packet gets the value ``v + k * (inc * I)`` (the loop's repeated 56-bit adds) and is Z-tested into the
    double-Z memory. Returns the memory and counts (``packets``, ``pixels``, ``writes``).
    """
    check_interleave(interleave, chip)
    npx = -(-(width - chip) // interleave)
    buf = DoubleZ.empty((npx,)) if buf is None else buf
    sl = segs.line(y)
    px, n, v, inc_i, keep = initial_processor(segs.x[sl], segs.len[sl], segs.val[sl], segs.inc[sl],
                                              chip, interleave)
    tags = segs.tag[sl]
    pixels = writes = 0
    for s in np.flatnonzero(keep):
        k = np.arange(n[s])
        vals = wrap(v[s][None, :] + k[:, None] * inc_i[s][None, :])
        z, a, c = _samples(vals, segs.mode)
        q = (px[s] - chip) // interleave + k
        writes += _insert(buf, q, z, a, c, np.full(k.size, tags[s]))
        pixels += int(k.size)
    return buf, {"packets": int(keep.sum()), "pixels": pixels, "writes": writes}
