"""What the geometry pipeline hands to every rasteriser: screen-space triangles.

Conventions (written once, used everywhere; see ``docs/conventions.md``):

* pixel (col, row) covers ``[col, col+1) x [row, row+1)``; its centre is at
  ``(col + 0.5, row + 0.5)``; x grows right, y grows **down** (row 0 is the top line);
* coverage uses the **top-left fill rule**: a centre exactly on an edge belongs to the
  triangle only if that edge is a top edge or a left edge;
* ``z`` is the float depth after the perspective divide mapped to [0, 1]:
  **0 = near plane, 1 = far plane**; it is affine in screen space, so linear
  interpolation over the triangle is exact;
* ``zq`` is ``z`` quantised to ``z_bits`` (round to nearest, clamp), and when
  ``z_far_is_zero`` it is flipped: ``zq = 2**z_bits - 1 - q`` so far = 0 and a
  *larger* value is nearer (the SNU pixel-bus convention);
* the reference Z test is ``z_new < z_stored`` (strict): on a tie the polygon
  submitted first keeps the pixel;
* colours are Gouraud-interpolated linearly in screen space, in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ScreenTriangles"]


@dataclass
class ScreenTriangles:
    """Triangles in submission order, ready for scan conversion.

    Attributes
    ----------
    width, height : frame size in pixels.
    xy : (T, 3, 2) float64 — vertex positions in pixels (see module conventions).
    z : (T, 3) float64 — depth in [0, 1], 0 = near.
    zq : (T, 3) int64 — quantised depth, ``z_bits`` wide (flipped if ``z_far_is_zero``).
    colour : (T, 3, 3) float64 — lit vertex colours in [0, 1].
    poly_id : (T,) int64 — index of the scene polygon each triangle came from.
    uv : (T, 3, 2) float64 or None.
    z_bits : width of ``zq``.
    z_far_is_zero : whether ``zq`` is flipped.
    stats : counts from the pipeline (``polygons_in``, ``polygons_culled``,
        ``polygons_clipped_away``, ``polygons_cut`` (crossed a clip plane and survived),
        ``polygons_drawn``, ``triangles``).
    ops : per-stage operation counts from the instrumented pipeline
        (stage name -> {"mul", "add", "cmp", "div", "sqrt", "lookup", "cvt", "total"}),
        totals over the whole scene, plus ``"vertices"``, ``"triangles"`` and
        ``"polygons"`` processed (see ``golden_model/opcount.py``).
    """

    width: int
    height: int
    xy: np.ndarray
    z: np.ndarray
    zq: np.ndarray
    colour: np.ndarray
    poly_id: np.ndarray
    uv: np.ndarray | None = None
    z_bits: int = 24
    z_far_is_zero: bool = False
    stats: dict = field(default_factory=dict)
    ops: dict = field(default_factory=dict)

    @property
    def n_triangles(self) -> int:
        return int(self.xy.shape[0])
