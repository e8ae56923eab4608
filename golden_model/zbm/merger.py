"""The merger: from the upstream chip's 2 samples and its own 2, keep the nearest 2
(upstream wins ties) and pass them down the merge bus.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm.doublez import DoubleZ

__all__ = ["merge", "merge_chain"]


def merge(a: DoubleZ, b: DoubleZ) -> DoubleZ:
    """Merger: nearest 2 of ``a``'s 2 and ``b``'s 2 samples; ``a`` (upstream input) wins ties.

    Same selection as ``hdl/zbm/merger.py``'s ``merge_words``: ``s0 = a0 if a0.z <= b0.z else
    b0``
    ``s1`` the nearer of (a1, b0) or of (a0, b1), upstream first on equal Z. Equivalent to
    a stable sort of (a0, a1, b0, b1) by Z, so chaining is associative.
    """
    a_first = a.z[..., 0] <= b.z[..., 0]
    s1a = a.z[..., 1] <= b.z[..., 0]
    s1b = a.z[..., 0] <= b.z[..., 1]
    out = DoubleZ.empty(a.z.shape[:-1])
    for name in ("z", "a", "c", "tag"):
        A, B = getattr(a, name), getattr(b, name)
        if name == "c":       # (..., 2, 4): put the slot axis last so masks broadcast
            A, B = np.moveaxis(A, -2, -1), np.moveaxis(B, -2, -1)
            m0, m1a, m1b = a_first[..., None], s1a[..., None], s1b[..., None]
        else:
            m0, m1a, m1b = a_first, s1a, s1b
        s0 = np.where(m0, A[..., 0], B[..., 0])
        s1 = np.where(m0, np.where(m1a, A[..., 1], B[..., 0]), np.where(m1b, A[..., 0], B[..., 1]))
        res = np.stack([s0, s1], axis=-1)
        setattr(out, name, np.moveaxis(res, -1, -2) if name == "c" else res)
    return out


def merge_chain(units: list[DoubleZ]) -> DoubleZ:
    """Units chained by merge ports: unit 0 is the head (upstream of all)."""
    acc = units[0]
    for u in units[1:]:
        acc = merge(acc, u)
    return acc
