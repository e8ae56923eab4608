"""Operation counting for the golden geometry pipeline (SNU paper, section 4.2, table 1).

Every floating-point step of :mod:`rasterhw.golden_model.pipeline` goes through an
:class:`OpCounter` method that *does* the NumPy operation and adds the number of result
elements to the current stage's tally, so the counts follow the code: change a stage
and its count changes with it. Nothing here is copied from the paper; the paper's
figures are kept apart (``golden_model/snu/table1.py``) and only printed beside ours.
:func:`rasterhw.golden_model.triangle_ops.ops_per_triangle` runs the pipeline on one triangle.

Categories
----------
``mul``     multiplications
``add``     additions and subtractions (and the integer subtraction that flips ``zq``)
``cmp``     comparisons, including each side of a ``min``/``max`` clamp
``div``     divisions and reciprocals
``sqrt``    square roots
``lookup``  table reads (the specular-exponent table)
``cvt``     float -> integer conversions (table index, ``zq``)

Sign changes (``-w`` in the clip tests) are not counted: they flip one bit in hardware
and fold into the next operation on the i860. Integer index arithmetic (slot numbers,
offsets) is bookkeeping, not floating-point work, and is not counted either.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["CATEGORIES", "OpCounter", "zero_counts"]

CATEGORIES = ("mul", "add", "cmp", "div", "sqrt", "lookup", "cvt")

def _zero() -> dict[str, int]:
    return dict.fromkeys(CATEGORIES, 0)


class OpCounter:
    """Counts the floating-point operations the pipeline performs, per stage.

    Use :meth:`stage` as a context manager around a stage; inside it call the counted
    operations (:meth:`mul`, :meth:`add`, ...) instead of the bare NumPy operators.
    Each call counts ``result.size`` operations of its category.
    """

    def __init__(self) -> None:
        self._counts: dict[str, dict[str, int]] = {}
        self._stage = "unstaged"

    # -- bookkeeping -------------------------------------------------------------
    @contextmanager
    def stage(self, name: str) -> Iterator[OpCounter]:
        prev = self._stage
        self._stage = name
        self._counts.setdefault(name, _zero())
        try:
            yield self
        finally:
            self._stage = prev

    def count(self, category: str, n: int) -> None:
        if category not in CATEGORIES:
            raise RasterhwError(f"unknown operation category {category!r}")
        self._counts.setdefault(self._stage, _zero())[category] += int(n)

    def as_dict(self) -> dict[str, dict[str, int]]:
        """Stage -> {category: count, ..., "total": sum}, stages in first-use order."""
        out = {}
        for name, c in self._counts.items():
            d = dict(c)
            d["total"] = sum(c.values())
            out[name] = d
        return out

    # -- counted operations --------------------------------------------------------
    def _r(self, category: str, r: np.ndarray) -> np.ndarray:
        self.count(category, np.size(r))
        return r

    def mul(self, a, b) -> np.ndarray:
        return self._r("mul", np.multiply(a, b))

    def add(self, a, b) -> np.ndarray:
        return self._r("add", np.add(a, b))

    def sub(self, a, b) -> np.ndarray:
        return self._r("add", np.subtract(a, b))

    def div(self, a, b) -> np.ndarray:
        return self._r("div", np.divide(a, b))

    def recip(self, a) -> np.ndarray:
        return self._r("div", np.divide(1.0, a))

    def sqrt(self, a) -> np.ndarray:
        return self._r("sqrt", np.sqrt(a))

    def le(self, a, b) -> np.ndarray:
        return self._r("cmp", np.less_equal(a, b))

    def ge(self, a, b) -> np.ndarray:
        return self._r("cmp", np.greater_equal(a, b))

    def gt(self, a, b) -> np.ndarray:
        return self._r("cmp", np.greater(a, b))

    def minimum(self, a, b) -> np.ndarray:
        return self._r("cmp", np.minimum(a, b))

    def maximum(self, a, b) -> np.ndarray:
        return self._r("cmp", np.maximum(a, b))

    def rint_int(self, a) -> np.ndarray:
        """Round to nearest (ties to even) and convert to int64."""
        return self._r("cvt", np.rint(a).astype(np.int64))

    def lookup(self, table: np.ndarray, index: np.ndarray) -> np.ndarray:
        return self._r("lookup", table[index])

    # -- compound helpers built only from the counted operations -------------------
    def dot(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Dot product along the last axis: k mul + (k - 1) add per result."""
        k = np.shape(a)[-1]
        acc = self.mul(a[..., 0], b[..., 0])
        for i in range(1, k):
            acc = self.add(acc, self.mul(a[..., i], b[..., i]))
        return acc

    def affine(self, v: np.ndarray, m: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """``v @ m.T (+ t)`` for (N, k) ``v`` and (r, k) ``m``, one row at a time.

        Per vector: r*k mul and r*(k-1) add, plus r add for the translation ``t``
        (a homogeneous coordinate fixed at 1, so it needs no multiplication).
        """
        cols = []
        for r in range(m.shape[0]):
            acc = self.dot(v, m[r])
            if t is not None:
                acc = self.add(acc, t[r])
            cols.append(acc)
        return np.stack(cols, axis=-1)


def zero_counts() -> dict[str, int]:
    """A tally with every category at zero."""
    return _zero()
