"""What the geometry pipeline hands to every rasteriser: screen-space triangles.

Conventions (written once, used everywhere; see ``docs/conventions.md``):

* pixel (col, row) covers ``[col, col+1) x [row, row+1)``; its centre is at
  ``(col + 0.5, row + 0.5)``; x grows right, y grows **down** (row 0 is the top line);
* coverage uses the **top-left fill rule**: a centre exactly on an edge belongs to the
  triangle only if that edge is a top edge or a left edge; vertices are first snapped to a
  grid of ``1 / 2**SUBPIXEL_BITS`` px (:func:`snap`, round half up) so every rasteriser
  decides edge ties exactly and identically;
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
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["SUBPIXEL_BITS", "ScreenTriangles", "snap"]

#: vertices are snapped to 1/256 px before coverage is decided (every rasteriser, golden and HDL)
SUBPIXEL_BITS = 8


def snap(v) -> np.ndarray:
    """Coordinates in pixels -> integers (as float64) on the 1/2**SUBPIXEL_BITS px grid, round half up."""
    return np.floor(np.asarray(v, dtype=np.float64) * (1 << SUBPIXEL_BITS) + 0.5)


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

    def validate(self, *, who: str = "screen triangles", max_width: int = 16384, max_height: int = 16384,
                 max_coord: float = 65536.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Check what every rasteriser relies on; return ``(xy, z, colour)`` as float64.

        Frame size within ``max_width x max_height``; every array shaped for ``T`` triangles;
        positions, depths and colours finite; no vertex coordinate of magnitude above
        ``max_coord`` px (the rasteriser's fixed-point range). Raises :class:`RasterhwError`
        naming ``who``, the field and the first bad triangle.
        """
        for name, v, lim in (("width", self.width, max_width), ("height", self.height, max_height)):
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not 1 <= v <= lim:
                raise RasterhwError(f"{who}: {name} must be an integer in 1..{lim}, not {v!r}")
        xy = np.asarray(self.xy, dtype=np.float64)
        if xy.ndim != 3 or xy.shape[1:] != (3, 2):
            raise RasterhwError(f"{who}: xy must be of shape (T, 3, 2), got shape {xy.shape}")
        t = xy.shape[0]
        z = np.asarray(self.z, dtype=np.float64)
        col = np.asarray(self.colour, dtype=np.float64)
        for name, arr, shape in (("z", z, (t, 3)), ("zq", np.asarray(self.zq), (t, 3)),
                                 ("colour", col, (t, 3, 3)), ("poly_id", np.asarray(self.poly_id), (t,))):
            if arr.shape != shape:
                raise RasterhwError(f"{who}: {name} must be of shape {shape}, got shape {arr.shape}")
        for name, arr in (("xy", xy), ("z", z), ("colour", col)):
            if np.isfinite(arr.sum()):  # one cheap pass: a NaN or an infinity makes the sum non-finite
                continue
            ok = np.isfinite(arr).reshape(t, arr.size // t if t else 0).all(axis=1)
            if not ok.all():
                raise RasterhwError(f"{who}: triangle {int(np.flatnonzero(~ok)[0])} has a NaN or infinite {name}")
        if t and max(float(xy.max()), -float(xy.min())) > max_coord:
            mag = np.abs(xy).reshape(t, -1).max(axis=1)
            if mag.max() > max_coord:
                bad = int(np.argmax(mag > max_coord))
                raise RasterhwError(
                    f"{who}: triangle {bad} has a vertex coordinate of magnitude {mag[bad]:.6g} px, "
                    f"more than {max_coord:g} px (outside the rasteriser's range; clip first)")
        return xy, z, col
