"""Bit-accurate depth: the quantised depth as a fixed-point plane per processor lattice.

The geometry processor sends depth as a linear function ("параметров поверхностей ... линейных
функций"). Here it is ``zq`` (``z_bits`` wide, 0 = near) as ``Zq(x, y) = Z00 + Zx*x + Zy*y`` over
full-raster pixel indices, rounded once to ``Z_FRAC_BITS`` fraction bits (round half up). Each
processor rewrites it for its lattice exactly as the edges: ``Z0 = Z00 + a*Zx + b*Zy``,
``Zu = p*Zx``, ``Zv = q*Zy`` (integers, no new rounding). Widths in :mod:`.formats`; slopes are clamped to
``2**(z_bits + 1)`` per pixel (a sliver steeper than that spans the depth range in half a pixel).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap
from rasterhw.golden_model.sparse.formats import Z_ACC_BITS, Z_FRAC_BITS, check_signed

__all__ = ["broadcast_records", "depth_plane", "plane_full"]


def plane_full(tris: ScreenTriangles, es) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Z00, Zx, Zy)`` (T,) int64: the depth plane over full-raster pixel indices, as the
    geometry processor broadcasts it, for the kept triangles of ``es`` (an EdgeSetup)."""
    sub = float(1 << SUBPIXEL_BITS)
    xy = np.asarray(tris.xy, dtype=np.float64)[es.tri]
    X = snap(xy[:, :, 0]) / sub  # snapped vertex positions in px
    Y = snap(xy[:, :, 1]) / sub
    Zq = np.asarray(tris.zq, dtype=np.float64)[es.tri]
    x1, x2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    y1, y2 = Y[:, 1] - Y[:, 0], Y[:, 2] - Y[:, 0]
    z1, z2 = Zq[:, 1] - Zq[:, 0], Zq[:, 2] - Zq[:, 0]
    det = x1 * y2 - x2 * y1  # non-zero: degenerate triangles are not kept
    zx = (z1 * y2 - z2 * y1) / det
    zy = (x1 * z2 - x2 * z1) / det
    # A slope above 2**(z_bits + 1) per pixel crosses the whole depth range inside half a pixel;
    # clamping it there keeps every accumulator in range and changes no pixel of a real scene.
    lim = float(1 << (tris.z_bits + 1))
    zx, zy = np.clip(zx, -lim, lim), np.clip(zy, -lim, lim)
    one = float(1 << Z_FRAC_BITS)
    # value at the centre of pixel (0, 0)
    z00 = Zq[:, 0] + zx * (0.5 - X[:, 0]) + zy * (0.5 - Y[:, 0])
    Zx = np.floor(zx * one + 0.5).astype(np.int64)
    Zy = np.floor(zy * one + 0.5).astype(np.int64)
    Z00 = np.floor(z00 * one + 0.5).astype(np.int64)
    check_signed("depth plane", np.concatenate([Z00, Zx, Zy]), Z_ACC_BITS)
    return Z00, Zx, Zy


def depth_plane(tris: ScreenTriangles, es, p: int, q: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Z0 (T, q, p), Zu (T,), Zv (T,))`` int64: :func:`plane_full` rewritten for every
    processor's lattice (``Z0 = Z00 + a*Zx + b*Zy``, ``Zu = p*Zx``, ``Zv = q*Zy``)."""
    Z00, Zx, Zy = plane_full(tris, es)
    a = np.arange(p, dtype=np.int64)
    b = np.arange(q, dtype=np.int64)
    Z0 = Z00[:, None, None] + b[None, :, None] * Zy[:, None, None] + a[None, None, :] * Zx[:, None, None]
    Zu, Zv = p * Zx, q * Zy
    check_signed("depth plane", np.concatenate([Z0.ravel(), Zu, Zv]), Z_ACC_BITS)
    return Z0, Zu, Zv


def broadcast_records(tris: ScreenTriangles) -> list[dict]:
    """What the geometry processor broadcasts, one dict of Python ints per non-degenerate
    triangle in submission order: ``A, B, C, thr`` (3 each, oriented edge equations over
    full-raster pixel indices), ``bbox`` (Xmin, Xmax, Ymin, Ymax in sub-pixel units),
    ``z00, zx, zy`` (the depth plane, ``Z_FRAC_BITS`` fraction bits) and ``tri`` (input index).
    The HDL video processor takes exactly these fields (``hdl/sparse/layouts.py``)."""
    from rasterhw.golden_model.sparse.search import edge_setup

    xy, _, _ = tris.validate(who="sparse broadcast", max_coord=float(1 << 13))
    es = edge_setup(xy)
    Z00, Zx, Zy = plane_full(tris, es)
    out = []
    for t in range(es.tri.size):
        out.append({"A": [int(v) for v in es.A[:, t]], "B": [int(v) for v in es.B[:, t]],
                    "C": [int(v) for v in es.C[:, t]], "thr": [int(v) for v in es.thr[:, t]],
                    "bbox": [int(v) for v in es.bbox[:, t]], "z00": int(Z00[t]), "zx": int(Zx[t]),
                    "zy": int(Zy[t]), "tri": int(es.tri[t])})
    return out
