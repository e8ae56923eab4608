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

__all__ = ["DoubleZ", "arrival_layers", "nearest_two"]


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


def nearest_two(pos: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What inserting fragments one by one in arrival order into empty double-Z pixels keeps
    (strict ``<``: on a tie the stored sample stays), when every ``z`` is nearer than the empty
    value and none is NaN: per pixel, the two least fragments by (``z``, arrival), found without
    the insertion (:func:`arrival_layers` + ``chip._insert``, which the golden model's write count
    needs; ``tests/zbm/test_zbm_golden.py`` holds the two equal).

    Returns ``(pixels, first, second)``: every pixel with a fragment (ascending), the index into
    ``pos`` of its nearest fragment and of its second (-1: it has one fragment)."""
    pos, z = np.asarray(pos), np.asarray(z)
    n = pos.size
    if n == 0:
        e = np.zeros(0, np.int64)
        return e, e, e
    order = np.argsort(pos, kind="stable")          # per pixel, arrivals in order
    sp, sz = pos[order], z[order]
    head = np.ones(n, bool)
    head[1:] = sp[1:] != sp[:-1]
    starts = np.flatnonzero(head)
    group = np.cumsum(head) - 1
    idx = np.arange(n)
    # the nearest: least z, the earliest of equal z (a tie leaves the stored sample ahead)
    i1 = np.minimum.reduceat(np.where(sz == np.minimum.reduceat(sz, starts)[group], idx, n), starts)
    rest = idx != i1[group]
    far = np.inf if sz.dtype.kind == "f" else np.iinfo(sz.dtype).max
    z2 = np.minimum.reduceat(np.where(rest, sz, far), starts)
    i2 = np.minimum.reduceat(np.where(rest & (sz == z2[group]), idx, n), starts)
    second = np.where(i2 < n, order[np.minimum(i2, n - 1)], -1)
    return sp[starts], order[i1], second
