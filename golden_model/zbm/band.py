"""A band of scan lines of an edge-pair stream: the edge pairs that draw lines ``y0 .. y1 - 1``,
each as the segment generator would hold it on line ``y0``.

Golden model of the ZB/M (seed 003). Scan lines are independent once an edge pair is known on
a line: the segment generator steps every active pair by the same 56-bit wrapping adds on every
line (``seggen.segment_generator``), and ``k`` such adds are one add of ``k`` times the step
(modular arithmetic). So a pair whose top line is above the band enters it at ``y0`` with its
values ``k = y0 - y`` lines on, and one frame can be drawn as bands on separate units or
processes and stitched; ``tests/zbm/test_zbm_band.py`` holds the stitched frame equal to the
whole one.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.edgepair import EdgePairs
from rasterhw.golden_model.zbm.formats import wrap

__all__ = ["edge_pair_band"]


def edge_pair_band(eps: EdgePairs, y0: int, y1: int) -> EdgePairs:
    """The pairs of ``eps`` (FIFO order) that cover a line of ``y0 .. y1 - 1``, clipped to those
    lines, order kept (the segment generator's active memory keeps load order, so each line's
    segments come out in the same order as in the whole frame). Line numbers stay the frame's."""
    if not (isinstance(y0, (int, np.integer)) and isinstance(y1, (int, np.integer)) and 0 <= y0 < y1):
        raise RasterhwError(f"edge_pair_band: lines must be 0 <= y0 < y1, not {y0!r}, {y1!r}")
    keep = np.flatnonzero((eps.y < y1) & (eps.y + eps.h > y0))
    b = eps.take(keep)
    k = np.maximum(y0 - b.y, 0)           # lines the pair has already been stepped on entering
    b.x, b.len = wrap(b.x + k * b.dxdy), wrap(b.len + k * b.dlendy)
    b.val = wrap(b.val + k[:, None] * b.ddy)
    b.h = np.minimum(b.y + b.h, y1) - (b.y + k)
    b.y = b.y + k
    return b
