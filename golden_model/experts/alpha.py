"""Anti-jagging mixing ratio alpha, eq. (5) ``C = alpha * C_L + (1 - alpha) * C_R`` (seed 000, 2.4).

An edge crosses the scan line's centre at ``x_e`` with slope ``s = dx/dy``; the A.J. pixel has its
centre at ``xc`` on that line and ``delta = x_e - xc``. ``alpha`` is the share of the pixel on the
*left* of the edge line (the side whose candidate is ``C_L``):

a) "1画素領域の面積を1としたときの、直線の左側の部分の面積": exact area (the ideal);
b) "画素領域の中心と直線との距離": ``0.5 + delta / sqrt(1 + s^2)`` (signed perpendicular distance);
c) "画素領域の中心からスキャン・ライン方向、またはスキャン・ラインに垂直な方向 ... (直線の勾配によって
   選択)": along the line ``0.5 + delta`` when the edge is steeper than 45 degrees (``|s| <= 1``),
   across it ``0.5 + delta * |dy/dx|`` when it is shallower (the vertical distance from the
   centre to the edge); this is why the ASB carries both dx/dy and dy/dx.

Every value is clamped to [0, 1]. The formulas for (b) and (c) are ours (the paper names the
distances, not the map to alpha); fig. 2.7's curves are illegible, so the error curves the
report draws are ours.
"""

from __future__ import annotations

import numpy as np

__all__ = ["alpha_area", "alpha_perp", "alpha_scan", "ALPHA"]


def _g(u: np.ndarray) -> np.ndarray:
    """Antiderivative of clamp(u, 0, 1)."""
    return np.where(u <= 0, 0.0, np.where(u >= 1, u - 0.5, 0.5 * u * u))


def alpha_area(delta, s) -> np.ndarray:
    """(a) exact area of the unit pixel left of ``x = x_e + s (y - yc)``."""
    delta = np.asarray(delta, dtype=np.float64)
    s = np.asarray(s, dtype=np.float64)
    a = delta + 0.5  # edge x relative to the pixel's left side, at the centre row
    small = np.abs(s) < 1e-12
    ss = np.where(small, 1.0, s)
    area = (_g(a + 0.5 * ss) - _g(a - 0.5 * ss)) / ss
    return np.clip(np.where(small, np.clip(a, 0, 1), area), 0.0, 1.0)


def alpha_perp(delta, s) -> np.ndarray:
    """(b) perpendicular distance from the centre to the edge."""
    delta = np.asarray(delta, dtype=np.float64)
    return np.clip(0.5 + delta / np.sqrt(1.0 + np.asarray(s, dtype=np.float64) ** 2), 0.0, 1.0)


def alpha_scan(delta, s) -> np.ndarray:
    """(c) distance along the scan line (steep edge) or across it (shallow edge)."""
    delta = np.asarray(delta, dtype=np.float64)
    s = np.abs(np.asarray(s, dtype=np.float64))
    with np.errstate(divide="ignore"):
        d = np.where(s <= 1.0, delta, delta / np.maximum(s, 1e-300))
    return np.clip(0.5 + d, 0.0, 1.0)


ALPHA = {"a": alpha_area, "b": alpha_perp, "c": alpha_scan}
