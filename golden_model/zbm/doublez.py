"""Double Z: every pixel keeps the two nearest samples (z, alpha, colour/mapping, tag).

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.zbm.formats import (
    Z_EMPTY,
    pack_samples,
)

__all__ = ["DoubleZ"]


@dataclass
class DoubleZ:
    """Double-Z pixels: ``[..., 0]`` nearest sample, ``[..., 1]`` second (Z_EMPTY = none).

    z, a : (..., 2) int64
    c : (..., 2, 4) int64 (r, g, b, 0 or um, vm, ui, vi);
    tag : (..., 2) triangle index, -1 = empty (model-only, not on the bus).
    """

    z: np.ndarray
    a: np.ndarray
    c: np.ndarray
    tag: np.ndarray

    @staticmethod
    def empty(shape) -> DoubleZ:
        shape = tuple(np.atleast_1d(shape)) if not isinstance(shape, tuple) else shape
        return DoubleZ(np.full(shape + (2,), Z_EMPTY, np.int64), np.zeros(shape + (2,), np.int64),
                       np.zeros(shape + (2, 4), np.int64), np.full(shape + (2,), -1, np.int64))

    def words(self) -> np.ndarray:
        """(..., 2) uint64 sample words (:data:`SAMPLE` layout); s0 then s1 = the merge word."""
        return pack_samples(self.z, self.a, self.c)

    def copy(self) -> DoubleZ:
        return DoubleZ(self.z.copy(), self.a.copy(), self.c.copy(), self.tag.copy())
