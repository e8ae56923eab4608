"""The compiled fast path of the float reference rasteriser (numba).

:mod:`rasterhw.golden_model.reference` is the specification: whole-array NumPy code whose
every step is written to be read. This module draws the same pixels, bit for bit, with one
compiled loop (:func:`_band`) that is a serial Z-buffer written out plainly:

* for each triangle in submission order, the same set-up as ``reference._setup`` (the same
  float64 operations, in the same order, on the same snapped integers), computed on the spot,
  one edge at a time (:func:`_edge`);
* for each scan line of its bounding box (clipped to the band being drawn), the same exact
  span from ``ceil`` / ``floor`` of the same quotients ``N_i / sS_i``, clamped to the box, one
  edge at a time (:func:`_clip`); both per-edge helpers are inlined by numba, so the loop runs
  as if they were written out three times;
* for each pixel of the span, the same barycentric weights and depth, the same expressions
  evaluated in the same order (``w1 = (S1*col + K1) / E`` ...,
  ``z = (z0*w0 + z1*w1) + z2*w2``), in a first pass over the span with no branches (so the
  compiler vectorises its divisions), then, in a second pass, the strict Z test against the
  depth held there;
* a fragment that passes writes only the outputs the caller asked for: colour (float64,
  ``(w0*c0 + w1*c1) + w2*c2`` per channel) or RGB8 (``Frame.to_rgb8``'s rounding), the
  triangle index and the polygon id, each at the integer width of the caller's buffer.

A serial Z-buffer in submission order is what the NumPy code's chunked, sorted resolve
computes (``reference._resolve``), and IEEE-754 double arithmetic gives the same bits for the
same operations in the same order; numba compiles without fast-math, so nothing is
reassociated or fused into a multiply-add. ``tests/test_reference_fast.py`` holds the two
bit-identical on c300, sp27, c300 at 1280x1024 and on hypothesis-generated scenes, and the
brute-force tests of ``tests/test_reference*.py`` run on both.

The kernel is compiled on first use and cached on disk (``cache=True``; where:
:func:`rasterhw.golden_model.numba_jit.njit_cached`).

This module imports numba at the top: :mod:`reference` loads it on first use
(:class:`rasterhw.golden_model.fastpath.FastPath`) and falls back to the NumPy code, with one line
on stderr, when that fails.
"""

from __future__ import annotations

import numba
import numpy as np
from rasterhw.golden_model.numba_jit import njit_cached as _jit

__all__ = ["band", "prepare"]


def _inline(fn):
    """A helper of :func:`_band`, inlined into it by numba (its IR, not a call), so writing a
    per-edge step once costs nothing in the hot loop; compiled and cached with its caller."""
    return numba.njit(inline="always", nogil=True)(fn)


HALF = 128.0  # SUBPIXEL // 2
SUB = 256.0  # SUBPIXEL


@_inline
def _edge(dx, dy, Xa, Ya, s):  # pragma: no cover - compiled
    """Set-up of the edge from vertex ``(Xa, Ya)`` along ``(dx, dy)`` in a triangle of
    orientation ``s`` (``reference._setup``): ``(k, S, sS, na, nb)`` with ``k = -dx*Ya -
    dy*(HALF - Xa)``, ``S = -SUB*dy``, and the fill rule's ``sS*col >= N = na*Yc + nb``,
    ``na = -s*dx``, ``nb = thr - s*k`` (``thr`` 0 on top/left edges, else 1)."""
    k = -dx * Ya - dy * (HALF - Xa)
    S = -SUB * dy
    thr = 0.0 if (s * dy < 0 or (s * dy == 0 and s * dx > 0)) else 1.0
    return k, S, s * S, -s * dx, thr - s * k


@_inline
def _clip(lo, hi, N, sS):  # pragma: no cover - compiled
    """The span ``lo .. hi`` cut by one edge: ``sS > 0`` bounds it below (``ceil(N / sS)``),
    ``sS < 0`` above (``floor``); a horizontal edge (``sS == 0``) passes the whole row
    (``N <= 0``) or none of it (``N > 0``: an empty span, ``hi = -1`` below any ``lo >= 0``)."""
    if sS > 0:
        return max(lo, np.ceil(N / sS)), hi
    if sS < 0:
        return lo, min(hi, np.floor(N / sS))
    if N > 0:
        return lo, -1.0
    return lo, hi


@_jit
def _to8(v):  # pragma: no cover - compiled
    """``Frame.to_rgb8`` of one channel: ``floor(v * 255 + 0.5)`` clamped to 0..255. Below 0
    the result is 0, from 256 on it is 255, and in between ``floor`` is the truncation."""
    q = v * 255.0 + 0.5
    if q < 0.0:
        return np.uint8(0)
    if q >= 256.0:
        return np.uint8(255)
    return np.uint8(np.int32(q))


@_jit
def _prepare(xy, W, H, y0, y1, n):  # pragma: no cover - compiled; tested through prepare()
    """The snapped coordinates ``X``, ``Y`` (T, 3) of ``xy`` (T, 3, 2), and ``n + 1`` row
    boundaries from ``y0`` to ``y1`` that split the bounding-box pixels of the triangles evenly
    (an estimate of the work; any cut draws the same pixels)."""
    T = xy.shape[0]
    X = np.empty((T, 3))
    Y = np.empty((T, 3))
    for t in range(T):
        for v in range(3):  # screen.snap: floor(v * 256 + 0.5), the same operations
            X[t, v] = np.floor(xy[t, v, 0] * SUB + 0.5)
            Y[t, v] = np.floor(xy[t, v, 1] * SUB + 0.5)
    cut = np.empty(n + 1, np.int64)
    for k in range(n + 1):
        cut[k] = y0 + (y1 - y0) * k // n
    if n == 1:
        return X, Y, cut
    d = np.zeros(y1 - y0 + 1, np.int64)  # per row: pixels of the bounding boxes, as differences
    for t in range(T):
        r0 = max(np.ceil((min(Y[t, 0], Y[t, 1], Y[t, 2]) - HALF) / SUB), float(y0))
        r1 = min(np.floor((max(Y[t, 0], Y[t, 1], Y[t, 2]) - HALF) / SUB), float(y1 - 1))
        c0 = max(np.ceil((min(X[t, 0], X[t, 1], X[t, 2]) - HALF) / SUB), 0.0)
        c1 = min(np.floor((max(X[t, 0], X[t, 1], X[t, 2]) - HALF) / SUB), float(W - 1))
        if r1 >= r0 and c1 >= c0:
            w = int(c1 - c0) + 1
            d[int(r0) - y0] += w
            d[int(r1) - y0 + 1] -= w
    total = 0
    run = 0
    for r in range(y1 - y0):
        run += d[r]
        total += run
    if total == 0:
        return X, Y, cut
    done = 0  # work of the rows before row y0 + r
    run = 0
    k = 1
    for r in range(y1 - y0):
        run += d[r]
        done += run
        while k < n and done * n > total * k:  # row y0 + r takes the band past k/n of the work
            cut[k] = y0 + r
            k += 1
    return X, Y, cut


def prepare(xy: np.ndarray, W: int, H: int, y0: int, y1: int, n: int) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """``(X, Y, cuts)``: the snapped vertex coordinates (T, 3) of ``xy`` (T, 3, 2, float64; as
    :func:`rasterhw.golden_model.screen.snap`, bit for bit), and ``n + 1`` row boundaries from
    ``y0`` to ``y1`` splitting the bounding-box work of the rows into ``n`` even bands."""
    X, Y, cut = _prepare(np.ascontiguousarray(xy, dtype=np.float64), int(W), int(H), int(y0), int(y1), int(n))
    return X, Y, cut.tolist()


@_jit
def _band(X, Y, z, col, pid, W, H, y0, y1, bg, want_rgb8, rgb8, want_colour, colour, depth,
          want_tri, tri, want_poly, poly):  # pragma: no cover - compiled; tested through band()
    """Rows ``y0 .. y1 - 1`` of a ``W x H`` frame. Every output array holds exactly those rows
    (pixel ``(row, col)`` at ``(row - y0) * W + col``, flat, colour channels interleaved); the
    unwanted ones may be empty. ``depth`` is the Z-buffer (float64), always used.

    Returns ``(fragments, pixels_written, pixels_covered)`` of the band."""
    npix = (y1 - y0) * W
    depth[:npix] = np.inf
    if want_tri:
        tri[:npix] = -1
    if want_poly:
        poly[:npix] = -1
    g0, g1, g2 = _to8(bg[0]), _to8(bg[1]), _to8(bg[2])
    if want_rgb8 and g0 == g1 and g1 == g2:
        rgb8[:3 * npix] = g0
    elif want_rgb8:
        for p in range(npix):
            rgb8[3 * p] = g0
            rgb8[3 * p + 1] = g1
            rgb8[3 * p + 2] = g2
    if want_colour:
        for p in range(npix):
            colour[3 * p] = bg[0]
            colour[3 * p + 1] = bg[1]
            colour[3 * p + 2] = bg[2]
    bw0 = np.empty(W)  # one scan line's weights and depths
    bw1 = np.empty(W)
    bw2 = np.empty(W)
    bz = np.empty(W)
    fragments = 0
    written = 0
    covered = 0
    for t in range(X.shape[0]):
        Xv0, Xv1, Xv2 = X[t, 0], X[t, 1], X[t, 2]
        Yv0, Yv1, Yv2 = Y[t, 0], Y[t, 1], Y[t, 2]
        # Edge i runs from vertex a[i] to b[i] (a = 1, 2, 0; b = 2, 0, 1): reference._setup.
        dx0 = Xv2 - Xv1
        dy0 = Yv2 - Yv1
        dx1 = Xv0 - Xv2
        dy1 = Yv0 - Yv2
        dx2 = Xv1 - Xv0
        dy2 = Yv1 - Yv0
        area = dx0 * (Yv0 - Yv1) - dy0 * (Xv0 - Xv1)
        if area == 0:
            continue
        r0 = max(np.ceil((min(Yv0, Yv1, Yv2) - HALF) / SUB), 0.0)
        r1 = min(np.floor((max(Yv0, Yv1, Yv2) - HALF) / SUB), float(H - 1))
        c0 = max(np.ceil((min(Xv0, Xv1, Xv2) - HALF) / SUB), 0.0)
        c1 = min(np.floor((max(Xv0, Xv1, Xv2) - HALF) / SUB), float(W - 1))
        if r1 < r0 or c1 < c0:
            continue
        ra = max(int(r0), y0)
        rb = min(int(r1), y1 - 1)
        if rb < ra:
            continue
        s = 1.0 if area > 0 else -1.0
        _, _, sS0, na0, nb0 = _edge(dx0, dy0, Xv1, Yv1, s)
        k1, S1, sS1, na1, nb1 = _edge(dx1, dy1, Xv2, Yv2, s)
        k2, S2, sS2, na2, nb2 = _edge(dx2, dy2, Xv0, Yv0, s)
        za, zb, zc = z[t, 0], z[t, 1], z[t, 2]
        pt = pid[t]
        # the vertex colours, held in registers (the outputs may alias anything for the compiler)
        ca0, ca1, ca2 = col[t, 0, 0], col[t, 0, 1], col[t, 0, 2]
        cb0, cb1, cb2 = col[t, 1, 0], col[t, 1, 1], col[t, 1, 2]
        cc0, cc1, cc2 = col[t, 2, 0], col[t, 2, 1], col[t, 2, 2]
        for row in range(ra, rb + 1):
            Yc = float(row * 256 + 128)
            # The span: the bounding box's columns cut by the three edges.
            lo, hi = _clip(c0, c1, na0 * Yc + nb0, sS0)
            lo, hi = _clip(lo, hi, na1 * Yc + nb1, sS1)
            lo, hi = _clip(lo, hi, na2 * Yc + nb2, sS2)
            if hi < lo:
                continue
            clo = int(lo)
            chi = int(hi)
            fragments += chi - clo + 1
            K1 = dx1 * Yc + k1  # E_1, E_2 at column 0 of the row
            K2 = dx2 * Yc + k2
            base = (row - y0) * W + clo
            n = chi - clo + 1
            # Pass 1, no branches (the compiler vectorises it): weights and depth of the span.
            for i in range(n):
                colf = float(clo + i)
                a1 = (S1 * colf + K1) / area
                a2 = (S2 * colf + K2) / area
                a0 = (1.0 - a1) - a2
                bw0[i] = a0
                bw1[i] = a1
                bw2[i] = a2
                bz[i] = (za * a0 + zb * a1) + zc * a2
            # Pass 2: the serial Z test, and the outputs of the fragments that pass.
            for i in range(n):
                zz = bz[i]
                p = base + i
                held = depth[p]
                if zz < held:
                    if held == np.inf:
                        covered += 1
                    depth[p] = zz
                    written += 1
                    if want_tri:
                        tri[p] = t
                    if want_poly:
                        poly[p] = pt
                    if want_colour or want_rgb8:
                        w0 = bw0[i]
                        w1 = bw1[i]
                        w2 = bw2[i]
                        v0 = (w0 * ca0 + w1 * cb0) + w2 * cc0
                        v1 = (w0 * ca1 + w1 * cb1) + w2 * cc1
                        v2 = (w0 * ca2 + w1 * cb2) + w2 * cc2
                        if want_colour:
                            colour[3 * p] = v0
                            colour[3 * p + 1] = v1
                            colour[3 * p + 2] = v2
                        if want_rgb8:
                            rgb8[3 * p] = _to8(v0)
                            rgb8[3 * p + 1] = _to8(v1)
                            rgb8[3 * p + 2] = _to8(v2)
    return fragments, written, covered


_EMPTY = {np.dtype(np.uint8): np.empty(0, np.uint8), np.dtype(np.float64): np.empty(0, np.float64),
          np.dtype(np.int64): np.empty(0, np.int64)}


def band(X, Y, z, col, pid, W: int, H: int, y0: int, y1: int, bg: np.ndarray, *, depth: np.ndarray,
         rgb8=None, colour=None, tri=None, poly=None) -> tuple[int, int, int]:
    """Draw rows ``y0 .. y1 - 1`` into flat arrays that hold exactly those rows (see
    :func:`_band`); ``None`` = not wanted. ``X``, ``Y``: snapped vertex coordinates (T, 3)
    (:func:`prepare`); ``z`` (T, 3), ``col`` (T, 3, 3), ``bg`` (3,) float64, ``pid`` (T,)
    int64, all C-contiguous."""
    return _band(X, Y, z, col, pid, int(W), int(H), int(y0), int(y1), bg,
                 rgb8 is not None, _EMPTY[np.dtype(np.uint8)] if rgb8 is None else rgb8,
                 colour is not None, _EMPTY[np.dtype(np.float64)] if colour is None else colour,
                 depth,
                 tri is not None, _EMPTY[np.dtype(np.int64)] if tri is None else tri,
                 poly is not None, _EMPTY[np.dtype(np.int64)] if poly is None else poly)
