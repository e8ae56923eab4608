"""Level 1 (the polygon processors, software): triangles -> edge pairs (trapezoids with
scan-line-parallel top and bottom) in the segment generator's fixed-point input format.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles, snap
from rasterhw.golden_model.zbm.formats import (
    CHANNELS,
    COORD_LIMIT,
    HALF_SUB,
    INC_LIMIT,
    MAX_HEIGHT,
    MAX_WIDTH,
    MODE_COLOUR,
    MODE_MAPPING,
    ONE_A,
    ONE_X,
    SUB,
    SUBPIX_BITS,
    TEX,
    VAL_LIMIT,
    X_FRAC,
    Z_SCALE,
    pack_edge_pair,
)

__all__ = ["EdgePairs", "edge_pairs"]


@dataclass
class EdgePairs:
    """Edge pairs in input-FIFO order (sorted by top line, stable), fixed point.

    Attributes
    ----------
    y, h : (E,) top scan line and number of lines.
    x, dxdy, len, dlendy : (E,) Q.40 pixels.
    val, ddy, ddx : (E, C) Q.24, channels ``CHANNELS[mode]``.
    tag : (E,) triangle index (model-only, not a hardware field).
    mode : MODE_COLOUR or MODE_MAPPING.
    """

    y: np.ndarray
    h: np.ndarray
    x: np.ndarray
    dxdy: np.ndarray
    len: np.ndarray
    dlendy: np.ndarray
    val: np.ndarray
    ddy: np.ndarray
    ddx: np.ndarray
    tag: np.ndarray
    mode: int = MODE_COLOUR

    def __len__(self) -> int:
        return int(self.y.shape[0])

    def take(self, idx: np.ndarray) -> EdgePairs:
        """A sub-stream (e.g. one unit's edge pairs), order kept."""
        f = {k: getattr(self, k)[idx] for k in ("y", "h", "x", "dxdy", "len", "dlendy", "val", "ddy", "ddx", "tag")}
        return EdgePairs(**f, mode=self.mode)

    def words(self, i: int) -> list[int]:
        """The 9 loader words of edge pair ``i`` (:data:`EP_HEADER` + :data:`EP_CHANNEL`)."""
        chans = [{"value": int(self.x[i]), "ddy": int(self.dxdy[i]), "ddx": 0},
                 {"value": int(self.len[i]), "ddy": int(self.dlendy[i]), "ddx": 0}]
        chans += [{"value": int(self.val[i, c]), "ddy": int(self.ddy[i, c]), "ddx": int(self.ddx[i, c])}
                  for c in range(self.val.shape[1])]
        return pack_edge_pair({"y": int(self.y[i]), "h": int(self.h[i]), "mode": self.mode}, chans)


def _check_tris(tris: ScreenTriangles) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # |coordinate| must stay below COORD_LIMIT (12 integer bits incl. sign): the largest float
    # under it is the inclusive bound validate() takes
    return tris.validate(who="ZB/M", max_width=MAX_WIDTH, max_height=MAX_HEIGHT,
                         max_coord=float(np.nextafter(COORD_LIMIT, 0)))


def _divfloor(n: np.ndarray, d: np.ndarray, shift: int) -> np.ndarray:
    """floor(n * 2**shift / d) for d > 0 without int64 overflow (d < 2**21, quotient small)."""
    q, r = np.divmod(n, d)
    return q * (1 << shift) + (r * (1 << shift)) // d


def _attributes(tris: ScreenTriangles, mode: int, alpha) -> np.ndarray:
    """(T, 3, C) vertex attribute values in hardware units (Z LSBs, 8-bit LSBs, texels)."""
    t = tris.n_triangles
    z = np.asarray(tris.z, np.float64) * Z_SCALE
    if alpha is None:
        a = np.full((t, 3), 255.0)
    else:
        a = np.asarray(alpha, np.float64)
        if a.shape == (t,):
            a = np.repeat(a[:, None], 3, axis=1)
        if a.shape != (t, 3) or not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 1:
            raise RasterhwError(f"ZB/M: alpha must be (T,) or (T, 3) in [0, 1], got shape {np.shape(alpha)}")
        a = a * 255.0
    if mode == MODE_COLOUR:
        col = np.asarray(tris.colour, np.float64) * 255.0
        return np.stack([z, col[..., 0], col[..., 1], col[..., 2], a], axis=-1)
    if mode == MODE_MAPPING:
        if tris.uv is None:
            raise RasterhwError("ZB/M: mapping mode needs ScreenTriangles.uv")
        uv = np.asarray(tris.uv, np.float64) * TEX
        # One (u, v) per vertex in ScreenTriangles: used for the texture map and the
        # illumination map alike (our decision; SIG-2's illumination maps are per surface).
        return np.stack([z, uv[..., 0], uv[..., 1], uv[..., 0], uv[..., 1], a], axis=-1)
    raise RasterhwError(f"ZB/M: mode must be {MODE_COLOUR} (colour) or {MODE_MAPPING} (mapping), not {mode!r}")


def edge_pairs(tris: ScreenTriangles, *, mode: int = MODE_COLOUR, alpha=None) -> EdgePairs:
    """Triangles -> edge pairs (trapezoids with scan-line-parallel top and bottom).

    A triangle is split at its middle vertex into an upper and a lower pair (the paper's "each
    polygon is expanded into 2 edge pairs"); a pair covers the scan lines whose pixel centre
    ``Yc`` satisfies ``Ytop <= Yc < Ybottom`` and, on each line, the pixels whose centre
    satisfies ``xL <= xc < xR`` -- the top-left rule. Vertices are snapped to 1/256 px (round
    half up) exactly as :func:`rasterhw.golden_model.reference.snap`
    ``x`` and ``dx/dy`` are
    computed exactly from the snapped integers and floor-rounded to Q.40, so the stepped edge
    is never right of the true edge and stays within 2**-31 px of it over 512 lines, closer
    than any pixel centre can be to an edge on this grid without lying on it (>= 2**-28 px):
    the coverage is exactly the reference's. Attributes are float64 plane equations
    rounded to nearest Q.24. Lines are clipped to the frame, and
    pairs with no line left are dropped.

    Returns the pairs in input-FIFO order: sorted by top line, ties in submission order.
    """
    xy, _, _ = _check_tris(tris)
    att = _attributes(tris, mode, alpha)             # (T, 3, C)
    T = xy.shape[0]
    X = snap(xy[..., 0]).astype(np.int64)
    Y = snap(xy[..., 1]).astype(np.int64)
    order = np.argsort(Y, axis=1, kind="stable")
    ti = np.arange(T)[:, None]
    X, Y, att = X[ti, order], Y[ti, order], att[ti, order]
    Xt, Xm, Xb = X[:, 0], X[:, 1], X[:, 2]
    Yt, Ym, Yb = Y[:, 0], Y[:, 1], Y[:, 2]
    d = (Xm - Xt) * (Yb - Yt) - (Ym - Yt) * (Xb - Xt)   # > 0: middle vertex right of the long edge
    # Float plane gradients from the snapped vertices (px units).
    xs, ys = X / SUB, Y / SUB
    e1x, e1y = xs[:, 1] - xs[:, 0], ys[:, 1] - ys[:, 0]
    e2x, e2y = xs[:, 2] - xs[:, 0], ys[:, 2] - ys[:, 0]
    det = e1x * e2y - e2x * e1y
    sdet = np.where(det == 0, 1.0, det)
    da1 = att[:, 1] - att[:, 0]
    da2 = att[:, 2] - att[:, 0]
    dadx = (da1 * e2y[:, None] - da2 * e1y[:, None]) / sdet[:, None]
    dady = (e1x[:, None] * da2 - e2x[:, None] * da1) / sdet[:, None]

    H = tris.height
    recs = []
    for part in (0, 1):                     # 0 = upper (top..mid), 1 = lower (mid..bottom)
        y0 = Yt if part == 0 else Ym
        y1 = Ym if part == 0 else Yb
        r0 = np.maximum(-((-(y0 - HALF_SUB)) // SUB), 0)   # first row with Yc >= y0
        r1 = np.minimum(-((-(y1 - HALF_SUB)) // SUB), H)   # first row with Yc >= y1
        keep = (d != 0) & (r1 > r0)
        # long edge t->b; short edge t->m (upper) or m->b (lower)
        sa = (Xt, Yt) if part == 0 else (Xm, Ym)
        sb = (Xm, Ym) if part == 0 else (Xb, Yb)
        left_long = d > 0
        LXa = np.where(left_long, Xt, sa[0])
        LYa = np.where(left_long, Yt, sa[1])
        LXb = np.where(left_long, Xb, sb[0])
        LYb = np.where(left_long, Yb, sb[1])
        RXa = np.where(left_long, sa[0], Xt)
        RYa = np.where(left_long, sa[1], Yt)
        RXb = np.where(left_long, sb[0], Xb)
        RYb = np.where(left_long, sb[1], Yb)
        idx = np.flatnonzero(keep)
        if idx.size == 0:
            continue
        r0k = r0[idx]
        Yc = r0k * SUB + HALF_SUB

        hk = (r1 - r0)[idx]

        def edge_x(xa, ya, xb, yb, Yc=Yc, hk=hk):
            # x = n / (SUB dy) px -> Q.40 = floor(n * 2**(X_FRAC - SUBPIX_BITS) / dy); dx/dy -> floor(dX * 2**40 / dy).
            # dx/dy is only used when h >= 2, and then dy > 1 px, so |dx/dy| < 4096 fits the slot;
            # a one-line pair carries dx/dy = 0.
            dy = yb - ya
            n = xa * dy + (Yc - ya) * (xb - xa)
            return _divfloor(n, dy, X_FRAC - SUBPIX_BITS), np.where(hk >= 2, _divfloor(xb - xa, dy, X_FRAC), 0)

        xl, dxl = edge_x(LXa[idx], LYa[idx], LXb[idx], LYb[idx])
        xr, dxr = edge_x(RXa[idx], RYa[idx], RXb[idx], RYb[idx])
        # Attribute on the left edge at (xl, Yc), plane d/dy along the left edge.
        px = xl / ONE_X - xs[idx, 0]
        py = (Yc / SUB) - ys[idx, 0]
        val = att[idx, 0] + dadx[idx] * px[:, None] + dady[idx] * py[:, None]
        ddy = dady[idx] + dadx[idx] * (dxl / ONE_X)[:, None]
        def q(v, lim):   # round half up to Q.24, saturate
            return np.clip(np.floor(v * ONE_A + 0.5), -lim, lim).astype(np.int64)

        recs.append({"y": r0k, "h": hk, "x": xl, "dxdy": dxl, "len": xr - xl,
                     "dlendy": dxr - dxl, "val": q(val, VAL_LIMIT), "ddy": q(ddy, INC_LIMIT),
                     "ddx": q(dadx[idx], INC_LIMIT),
                     "tag": idx, "key": idx * 2 + part})
    C = len(CHANNELS[mode])
    if not recs:
        z1 = np.zeros(0, np.int64)
        z2 = np.zeros((0, C), np.int64)
        return EdgePairs(z1, z1, z1, z1, z1, z1, z2, z2, z2, z1, mode)
    cat = {k: np.concatenate([r[k] for r in recs]) for k in recs[0]}
    o = np.lexsort((cat["key"], cat["y"]))     # FIFO order: top line, then submission order
    return EdgePairs(**{k: cat[k][o].astype(np.int64) for k in cat if k != "key"}, mode=mode)
