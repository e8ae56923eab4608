"""Operation counting for the golden geometry pipeline (SNU paper, section 4.2, table 1).

Every floating-point step of :mod:`rasterhw.golden_model.pipeline` goes through an
:class:`OpCounter` method that *does* the NumPy operation and adds the number of result
elements to the current stage's tally, so the counts follow the code: change a stage
and its count changes with it. Nothing here is copied from the paper; the paper's
figures are kept apart in :data:`PAPER_TABLE1` and only printed beside ours.

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

__all__ = [
    "CATEGORIES",
    "PAPER_TABLE1",
    "PAPER_PER_VERTEX_TEXT",
    "OpCounter",
    "ops_per_triangle",
    "paper_comparison",
]

CATEGORIES = ("mul", "add", "cmp", "div", "sqrt", "lookup", "cvt")

#: The paper's table 1 (seed 004, "표 1"): stage -> (operations per triangle, i860 clocks).
PAPER_TABLE1: dict[str, tuple[int, int]] = {
    "vertex_transform": (72, 60),
    "normal_transform": (45, 39),
    "normalise": (30, 81),
    "light": (72, 60),
    "clip": (24, 24),
    "perspective_divide": (12, 18),
    "screen_map": (15, 27),
}

#: What the paper's text (section 4.2.1-4.2.5) says each stage does per vertex.
PAPER_PER_VERTEX_TEXT: dict[str, str] = {
    "vertex_transform": "4x4 matrix, w fixed at 1.0: 12 mul + 12 add",
    "normal_transform": "3x3 matrix: 9 mul + 6 add",
    "normalise": "3 mul + 2 add (sum of squares), 1 sqrt + 1 recip (counted as 2), 3 mul",
    "light": "12 mul + 10 add + 3 compares + 1 table lookup (= 26, table says 24)",
    "clip": "6 compares (= 18 per triangle, table says 24)",
    "perspective_divide": "1 recip + 3 mul",
    "screen_map": "3 mul + 2 add (one more add if y or z is flipped)",
}


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


def _default_triangle_scene():
    """A single lit, unclipped, front-facing triangle with the full Phong model on."""
    from rasterhw.golden_model.scene import Camera, Light, Material, Scene

    pos = np.array([[[-1.0, -0.8, 0.0], [1.0, -0.6, -0.3], [0.1, 0.9, 0.2]]])
    nrm = np.array([[[-0.2, -0.1, 1.0], [0.3, -0.1, 1.0], [0.0, 0.3, 1.0]]])
    col = np.array([[[0.8, 0.3, 0.2], [0.3, 0.7, 0.2], [0.2, 0.3, 0.8]]])
    return Scene(
        name="one-triangle",
        positions=pos,
        normals=nrm,
        colours=col,
        nverts=np.array([3]),
        camera=Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), near=0.5, far=50.0),
        lights=(Light(direction=(-0.3, -0.4, -1.0), colour=(1.0, 1.0, 1.0)),),
        ambient=(0.2, 0.2, 0.2),
        material=Material(ka=1.0, kd=0.6, ks=0.3, shininess=16),
    )


def ops_per_triangle(
    scene=None, *, width: int = 1280, height: int = 1024
) -> dict[str, dict[str, int]]:
    """Run the pipeline on one triangle and return its per-stage operation counts.

    The default scene is one lit, front-facing triangle fully inside the view volume,
    one directional light, specular on (``ks > 0``), drawn at the SNU system's
    1280 x 1024 with a 24-bit Z flipped so far = 0 -- the paper's assumptions for
    table 1. A given ``scene`` must be one triangle that is drawn without being cut by
    a clip plane. Returns stage -> {category: count, "total": n} in pipeline order
    plus a ``"total"`` row.
    """
    from rasterhw.golden_model.pipeline import STAGES, run_geometry

    scene = _default_triangle_scene() if scene is None else scene
    if scene.n_polygons != 1 or int(scene.nverts[0]) != 3:
        raise RasterhwError(
            f"ops_per_triangle needs a scene of one triangle, got {scene.n_polygons} polygons "
            f"with {scene.nverts.tolist()} corners"
        )
    tris = run_geometry(scene, width, height, z_bits=24, z_far_is_zero=True)
    if (
        tris.stats["polygons_drawn"] != 1
        or tris.stats["polygons_cut"] != 0
        or tris.n_triangles != 1
    ):
        raise RasterhwError(
            f"ops_per_triangle needs a front-facing triangle inside the view volume; stats: {tris.stats}"
        )
    out = {s: dict(tris.ops[s]) for s in STAGES}
    total = _zero() | {"total": 0}
    for row in out.values():
        for k in total:
            total[k] += row[k]
    out["total"] = total
    return out


def paper_comparison(
    counts: dict[str, dict[str, int]] | None = None,
) -> list[tuple[str, int | None, int, str]]:
    """Rows (stage, paper ops per triangle or None, our measured ops, our breakdown)."""
    counts = ops_per_triangle() if counts is None else counts
    rows = []
    for stage, c in counts.items():
        if stage == "total":
            continue
        paper = PAPER_TABLE1.get(stage, (None, None))[0]
        parts = " + ".join(f"{c[k]} {k}" for k in CATEGORIES if c[k])
        rows.append((stage, paper, c["total"], parts or "0"))
    rows.append(("total", sum(v[0] for v in PAPER_TABLE1.values()), counts["total"]["total"], ""))
    return rows
