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

__all__ = ["DoubleZ", "arrival_layers"]


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


def arrival_layers(pos: np.ndarray) -> list[np.ndarray]:
    """Fragments in arrival order (``pos[i]`` = pixel of fragment ``i``) split into layers:
    layer ``r`` holds, for every pixel, its ``r``-th fragment (indices into ``pos``, ascending).

    Each layer touches every pixel at most once, so inserting the layers in order, each as one
    vectorised step, gives exactly what inserting the fragments one by one in arrival order
    gives (per pixel the arrivals keep their order; pixels do not interact).
    """
    pos = np.asarray(pos)
    if pos.size == 0:
        return []
    order = np.argsort(pos, kind="stable")
    sp = pos[order]
    first = np.ones(sp.size, bool)
    first[1:] = sp[1:] != sp[:-1]
    start = np.maximum.accumulate(np.where(first, np.arange(sp.size), 0))
    rank = np.arange(sp.size) - start
    by_rank = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[by_rank], np.arange(int(rank.max()) + 2))
    return [np.sort(order[by_rank[bounds[r]:bounds[r + 1]]]) for r in range(int(rank.max()) + 1)]
