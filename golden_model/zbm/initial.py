"""The initial processor of a ZB/M chip: a segment -> the segment packet for this chip's
interleave slot (first own pixel, pixel count, values stepped to it, increments x interleave).

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm.formats import check_interleave, wrap

__all__ = ["initial_processor"]


def initial_processor(x: np.ndarray, ln: np.ndarray, val: np.ndarray, inc: np.ndarray,
                      chip: int, interleave: int):
    """Segments -> this chip's packets: first owned pixel, owned count, values there, inc * I.

    Chip ``c`` owns screen pixels ``x % I == c``. ``j = (c - x) mod I`` (< 16) pixels are
    skipped with a small multiply ``j * inc``
    the increment becomes ``inc << log2(I)``.
    Returns ``(px, n, v, inc_i, keep)``
    ``keep`` marks segments with ``n >= 1`` (the others
    are dropped by the initial processor).
    """
    check_interleave(interleave, chip)
    j = (chip - x) % interleave
    px = x + j
    n = np.maximum(-(-(ln - j) // interleave), 0)
    keep = n > 0
    v = wrap(val + j[:, None] * inc)
    inc_i = wrap(inc << (interleave.bit_length() - 1))
    return px, n, v, inc_i, keep
