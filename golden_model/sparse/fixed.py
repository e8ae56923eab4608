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
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap
from rasterhw.golden_model.sparse.edges import edge_setup
from rasterhw.golden_model.sparse.formats import Z_ACC_BITS, Z_FRAC_BITS, check_signed

__all__ = ["COLOUR_BITS", "broadcast_records", "colour_planes", "colour_rgb8", "depth_plane", "plane_full"]

#: bits per colour channel of the bit-accurate colour planes (the reference's ``to_rgb8``)
COLOUR_BITS = 8


def plane_full(tris: ScreenTriangles, es, values: np.ndarray | None = None,
               bits: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Z00, Zx, Zy)`` (T,) int64: the depth plane over full-raster pixel indices, as the
    geometry processor broadcasts it, for the kept triangles of ``es`` (an EdgeSetup).
    ``values`` ((T_in, 3) per-vertex values of another surface parameter, e.g. one colour
    channel in 8-bit levels) and ``bits`` (its range) give that parameter's plane instead."""
    sub = float(1 << SUBPIXEL_BITS)
    xy = np.asarray(tris.xy, dtype=np.float64)[es.tri]
    X = snap(xy[:, :, 0]) / sub  # snapped vertex positions in px
    Y = snap(xy[:, :, 1]) / sub
    if values is None:
        Zq = np.asarray(tris.zq, dtype=np.float64)[es.tri]
        bits = tris.z_bits
    else:
        Zq = np.asarray(values, dtype=np.float64)[es.tri]
    x1, x2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    y1, y2 = Y[:, 1] - Y[:, 0], Y[:, 2] - Y[:, 0]
    z1, z2 = Zq[:, 1] - Zq[:, 0], Zq[:, 2] - Zq[:, 0]
    det = x1 * y2 - x2 * y1  # non-zero: degenerate triangles are not kept
    zx = (z1 * y2 - z2 * y1) / det
    zy = (x1 * z2 - x2 * z1) / det
    # A slope above 2**(z_bits + 1) per pixel crosses the whole depth range inside half a pixel;
    # clamping it there keeps every accumulator in range and changes no pixel of a real scene.
    lim = float(1 << (bits + 1))
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


def colour_planes(tris: ScreenTriangles, es) -> np.ndarray:
    """``(3 channels, 3 [C00, Cx, Cy], T)`` int64: the vertex colours as linear functions over
    full-raster pixel indices in 8-bit levels (``255 * colour``) with ``Z_FRAC_BITS`` fraction
    bits, broadcast with the edges like the depth plane ("параметров поверхностей ... линейных
    функций"). Each processor rewrites them for its lattice as the edges."""
    _, _, vcol = tris.validate(who="sparse colour", max_coord=float(1 << 13))
    lv = float((1 << COLOUR_BITS) - 1)
    # slopes clamped where depth's are (2**25 levels per px, the accumulator's range): a sliver's
    # colour slope can exceed 2**(8 + 1) levels per px and still matter at its pixels
    return np.stack([np.stack(plane_full(tris, es, vcol[:, :, ch] * lv, 24)) for ch in range(3)])


def colour_rgb8(tris: ScreenTriangles, tri_id: np.ndarray, p: int, q: int) -> np.ndarray:
    """The bit-accurate colour of a matrix frame: ``(H, W, 3)`` uint8 from ``tri_id`` (the
    interleaved read-out's visible triangle, -1 empty -> 0). Pixel ``(x, y)`` is processor
    ``(a, b) = (x mod p, y mod q)``'s sparse pixel ``(u, v)``; the processor evaluates
    ``C0 + Cu u + Cv v`` with ``C0 = C00 + a Cx + b Cy``, ``Cu = p Cx``, ``Cv = q Cy`` and rounds
    half up to 8 bits, clamped to 0..255 (the reference's ``to_rgb8`` rounding)."""

    xy, _, _ = tris.validate(who="sparse colour", max_coord=float(1 << 13))
    tri_id = np.asarray(tri_id)
    if tri_id.shape != (tris.height, tris.width) or not np.issubdtype(tri_id.dtype, np.integer):
        raise RasterhwError(f"sparse colour: tri_id must be an integer ({tris.height}, {tris.width}) array, "
                            f"not {tri_id.dtype} {tri_id.shape}")
    if tri_id.size and (tri_id.min() < -1 or tri_id.max() >= len(xy)):
        raise RasterhwError(f"sparse colour: tri_id holds {int(tri_id.min())}..{int(tri_id.max())}, "
                            f"outside -1..{len(xy) - 1}")
    if tris.width % p or tris.height % q:
        raise RasterhwError(f"sparse colour: a {p}x{q} matrix does not divide a {tris.width}x{tris.height} raster")
    es = edge_setup(xy)
    pl = colour_planes(tris, es)  # (3, 3, T)
    kept = np.full(len(xy), -1, dtype=np.int64)
    kept[es.tri] = np.arange(es.tri.size)
    H, W = tri_id.shape
    out = np.zeros((H, W, 3), dtype=np.uint8)
    yy, xx = np.nonzero(tri_id >= 0)
    k = kept[tri_id[yy, xx]]
    if (k < 0).any():
        raise RasterhwError("sparse colour: tri_id names a degenerate (zero-area) triangle")
    a, b, u, v = xx % p, yy % q, xx // p, yy // q
    half = 1 << (Z_FRAC_BITS - 1)
    for ch in range(3):
        c00, cx, cy = pl[ch, 0, k], pl[ch, 1, k], pl[ch, 2, k]
        acc = (c00 + a * cx + b * cy) + (p * cx) * u + (q * cy) * v
        out[yy, xx, ch] = np.clip((acc + half) >> Z_FRAC_BITS, 0, (1 << COLOUR_BITS) - 1)
    return out
