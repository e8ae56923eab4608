"""The geometric processor's edge set-up (what it broadcasts per triangle), exactly as the reference
rasteriser's edge functions: shared by the video processors' search, their fixed-point records and
the stack processor."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.screen import SUBPIXEL_BITS, snap
from rasterhw.golden_model.sparse.formats import EDGE_AB_BITS, EDGE_BITS, check_signed

__all__ = ["EdgeSetup", "edge_setup"]

_SUB = 1 << SUBPIXEL_BITS
_HALF = _SUB // 2


@dataclass
class EdgeSetup:
    """What the geometry processor broadcasts per triangle (kept triangles only).

    Attributes
    ----------
    tri : (T,) int64 — index of the triangle in the input.
    A, B, C : (3, T) int64 — oriented edge coefficients per full-raster pixel index
        (interior ``A*x + B*y + C >= thr``).
    thr : (3, T) int64 — 0 on a top or left edge, 1 otherwise.
    sign : (T,) int64 — sign of the snapped area (orientation); ``E_unsigned = sign * E``.
    area : (T,) int64 — twice the signed area on the sub-pixel grid (reference's ``E``).
    bbox : (4, T) int64 — ``Xmin, Xmax, Ymin, Ymax`` of the snapped vertices (sub-pixel units).
    """

    tri: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    thr: np.ndarray
    sign: np.ndarray
    area: np.ndarray
    bbox: np.ndarray


def edge_setup(xy: np.ndarray) -> EdgeSetup:
    """Edge equations of every non-degenerate triangle, exactly as the reference rasteriser."""
    X = snap(xy[:, :, 0]).T.astype(np.int64)  # (3, T)
    Y = snap(xy[:, :, 1]).T.astype(np.int64)
    a = [1, 2, 0]
    b = [2, 0, 1]
    dx = X[b] - X[a]
    dy = Y[b] - Y[a]
    area = dx[0] * (Y[0] - Y[1]) - dy[0] * (X[0] - X[1])
    keep = np.flatnonzero(area != 0)
    s = np.sign(area[keep])
    dx, dy, Xa, Ya = dx[:, keep], dy[:, keep], X[a][:, keep], Y[a][:, keep]
    sdx, sdy = s * dx, s * dy
    topleft = (sdy < 0) | ((sdy == 0) & (sdx > 0))
    A = -_SUB * sdy
    B = _SUB * sdx
    C = sdx * (_HALF - Ya) - sdy * (_HALF - Xa)
    check_signed("edge coefficient A/B", np.concatenate([A.ravel(), B.ravel()]), EDGE_AB_BITS)
    check_signed("edge constant C", C, EDGE_BITS)
    return EdgeSetup(tri=keep.astype(np.int64), A=A, B=B, C=C, thr=np.where(topleft, 0, 1).astype(np.int64),
                     sign=s.astype(np.int64), area=area[keep],
                     bbox=np.stack([X[:, keep].min(0), X[:, keep].max(0), Y[:, keep].min(0), Y[:, keep].max(0)]))
