"""Brute-force coverage and visibility: the independent check of ``reference.py``.

One pixel, one triangle at a time, in plain Python integers, written to be read rather than
to be fast. It shares no edge or coverage code with :mod:`rasterhw.golden_model.reference`;
only the documented conventions are the same:

* vertices snapped to the 1/256-px grid, round half up (``floor(v * 256 + 0.5)``);
* the pixel centre of ``(col, row)`` is ``(256*col + 128, 256*row + 128)`` on that grid;
* a centre strictly inside a triangle is covered; a centre exactly on an edge is covered
  only if that edge is a *top* edge (horizontal, the third vertex below it, y down) or a
  *left* edge (not horizontal, the third vertex to its right). Here "top" and "left" are
  decided geometrically from the third vertex, with exact fractions, not from the winding;
* zero-area triangles (after snapping) cover nothing;
* depth at a covered centre: ``w1 = E1 / E``, ``w2 = E2 / E``, ``w0 = (1 - w1) - w2`` in
  float64 (``E_i`` twice the signed area of the sub-triangle opposite vertex ``i``, ``E``
  twice the triangle's signed area), ``z = w0*z0 + w1*z1 + w2*z2``; the visible triangle is
  the first one submitted among those with the smallest ``z`` (strict ``<`` Z test).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles

__all__ = ["brute_coverage", "brute_visible"]

GRID = 1 << SUBPIXEL_BITS   # the convention (screen.py); the arithmetic below is our own


def _snap(v: float) -> int:
    return math.floor(float(v) * GRID + 0.5)


def _cross(ax: int, ay: int, bx: int, by: int, px: int, py: int) -> int:
    """Twice the signed area of (a, b, p): > 0 when p is on one side of a->b, < 0 on the other."""
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def _edge_owns_centre(u: tuple[int, int], v: tuple[int, int], o: tuple[int, int]) -> bool:
    """Is the edge u-v (third vertex o) a top or a left edge?"""
    (ux, uy), (vx, vy), (ox, oy) = u, v, o
    if uy == vy:  # horizontal: a top edge when the triangle lies below it (y grows down)
        return oy > uy
    # Not horizontal: a left edge when the triangle lies to its right, i.e. the third vertex
    # is right of the edge's line at the third vertex's height.
    x_on_line = Fraction(ux) + Fraction((oy - uy) * (vx - ux), vy - uy)
    return Fraction(ox) > x_on_line


def _triangle_covers(p: list[tuple[int, int]], cx: int, cy: int) -> bool:
    area = _cross(*p[0], *p[1], *p[2])
    if area == 0:
        return False
    for i in range(3):
        u, v, o = p[(i + 1) % 3], p[(i + 2) % 3], p[i]
        side = _cross(*u, *v, cx, cy)
        side_o = _cross(*u, *v, *o)  # nonzero: the triangle has area
        if side == 0:
            if not _edge_owns_centre(u, v, o):
                return False
        elif (side > 0) != (side_o > 0):
            return False
    return True


def _depth(p: list[tuple[int, int]], z, cx: int, cy: int) -> float:
    area = _cross(*p[0], *p[1], *p[2])
    e1 = _cross(*p[2], *p[0], cx, cy)  # sub-triangle opposite vertex 1
    e2 = _cross(*p[0], *p[1], cx, cy)  # opposite vertex 2
    w1 = float(e1) / float(area)
    w2 = float(e2) / float(area)
    w0 = (1.0 - w1) - w2
    return w0 * float(z[0]) + w1 * float(z[1]) + w2 * float(z[2])


def _snapped(tris: ScreenTriangles) -> list[list[tuple[int, int]]]:
    xy = np.asarray(tris.xy, dtype=np.float64)
    return [[(_snap(xy[t, k, 0]), _snap(xy[t, k, 1])) for k in range(3)] for t in range(xy.shape[0])]


def brute_coverage(tris: ScreenTriangles) -> np.ndarray:
    """(T, H, W) bool: which pixels each triangle covers, by the fill rule."""
    pts = _snapped(tris)
    out = np.zeros((len(pts), tris.height, tris.width), dtype=bool)
    for t, p in enumerate(pts):
        for row in range(tris.height):
            for col in range(tris.width):
                out[t, row, col] = _triangle_covers(p, GRID * col + GRID // 2, GRID * row + GRID // 2)
    return out


def brute_visible(tris: ScreenTriangles) -> tuple[np.ndarray, np.ndarray, int]:
    """Per-pixel serial Z-buffer by brute force.

    Returns ``(tri_id (H, W) int64, -1 where empty; depth (H, W) float64, +inf where empty;
    pixels_written)``, where ``pixels_written`` counts the fragments that passed the Z test
    when they arrived, triangles taken in submission order.
    """
    pts = _snapped(tris)
    z = np.asarray(tris.z, dtype=np.float64)
    tri_id = np.full((tris.height, tris.width), -1, dtype=np.int64)
    depth = np.full((tris.height, tris.width), np.inf)
    written = 0
    for row in range(tris.height):
        for col in range(tris.width):
            cx, cy = GRID * col + GRID // 2, GRID * row + GRID // 2
            best, best_z = -1, math.inf
            for t, p in enumerate(pts):
                if _triangle_covers(p, cx, cy):
                    d = _depth(p, z[t], cx, cy)
                    if d < best_z:
                        best, best_z = t, d
                        written += 1
            tri_id[row, col] = best
            depth[row, col] = best_z
    return tri_id, depth, written
