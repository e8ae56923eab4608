"""The float reference rasteriser: a full-frame Z-buffer with Gouraud colour.

This is the "ideal arithmetic" image every architecture is compared with. It follows the
conventions of :mod:`rasterhw.golden_model.screen` exactly:

* pixel centres at ``(col + 0.5, row + 0.5)``, y down;
* top-left fill rule, decided **exactly**: vertex positions are snapped to a grid of
  ``1/SUBPIXEL`` px (``SUBPIXEL = 256``, round half up) and the edge functions are then
  integers (held in ``float64``; every value is an integer below 2**53, so they are exact);
* depth ``z``: 0 = near; the Z test is ``z_new < z_stored`` (strict), so on a tie the triangle
  submitted first keeps the pixel;
* colour and depth are interpolated with barycentric weights ``w_i = E_i / E`` in float64
  (``E_i`` is the edge function of the edge opposite vertex ``i``, ``E`` twice the signed area;
  both on the snapped grid) and summed in vertex order, ``w0*a0 + w1*a1 + w2*a2``. At a vertex
  the weights are exactly (1, 0, 0), so a pixel centre on a vertex gets that vertex's colour
  and depth bit for bit.

How it is vectorised (no per-triangle Python loop):

1. triangle set-up for all triangles at once (snapping, signed area, edge coefficients,
   top-left flags, pixel bounding boxes clipped to the frame);
2. one record per (triangle, scan line) of its bounding box; for each record the exact span
   ``[col_lo, col_hi]`` where all three edge functions pass the fill rule, from integer floor
   divisions (``E_k(col)`` is affine in ``col``);
3. the spans are expanded to fragments (each per-record value is gathered on the record
   index of every fragment) and the weights and depth of every fragment are computed as
   whole-array operations;
4. Z resolve (:func:`_resolve`): a fragment alone at its pixel in the chunk is decided by
   one comparison with the depth held there; the others are sorted by (pixel, submission
   order), one sort of packed integer keys, and each pixel's running minimum is carried
   down its run. That is exactly what a serial Z-buffer writes (``pixels_written``) and
   the final winner per pixel;
5. colour is computed only for the winners.

Frames of at least ``THREAD_MIN_PIXELS`` pixels are rendered as ``THREADS`` row bands (one per
CPU, at most 2) in threads at once, each into its rows of the outputs: NumPy's loops release the
GIL, and a band gives exactly the pixels and counts of the whole frame's rows (each pixel's
serial Z-buffer sees the same triangles in the same order), which a test holds bit for bit.

Engines: this module's NumPy code is the specification. :mod:`rasterhw.golden_model.reference_fast`
draws the same pixels, bit for bit, with one compiled numba loop, and is used by default where
numba loads (``RASTERHW_REFERENCE=numpy``, or ``engine="numpy"``, forces the NumPy code; without
numba it runs, with one line on stderr saying so). :func:`render` is the output contract: it
writes only the outputs a caller asks for (RGB8, float colour, depth, triangle index, polygon id)
into the caller's reusable :class:`Target`, ids at the integer width asked for.

Triangles are processed in chunks of at most about ``CHUNK_CANDIDATES`` bounding-box pixels,
carrying the depth buffer from chunk to chunk, so memory stays bounded for large frames.
Fresh memory is expensive here (a page fault per 4 kB page), so the fragment arrays live in a
per-thread pool reused from chunk to chunk and call to call, and the four outputs share one
new block per call, aligned so that it is backed by 2 MiB pages.
"""

from __future__ import annotations

import itertools
import os
import statistics
import threading
import time
import tracemalloc
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.fastpath import FastPath
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap

__all__ = ["SUBPIXEL", "MAX_COORD", "ENGINE_ENV", "Frame", "Target", "choose_engine", "rasterise", "render",
           "rasterise_rgb8", "rasterise_rgb8_memory", "benchmark", "random_triangles", "snap"]

#: Sub-pixel grid: vertex coordinates are snapped to multiples of ``1 / SUBPIXEL`` px.
SUBPIXEL = 1 << SUBPIXEL_BITS
#: Largest vertex coordinate magnitude accepted, in pixels (keeps every edge function an
#: integer below 2**53 on the sub-pixel grid, so float64 holds it exactly).
MAX_COORD = 65536.0
#: Bounding-box pixels per chunk (bounds the size of the fragment arrays).
CHUNK_CANDIDATES = 1 << 18


@dataclass
class Frame:
    """A rendered frame.

    Attributes
    ----------
    colour : (H, W, 3) float64 — Gouraud colour in [0, 1] (background where empty).
    depth : (H, W) float64 — depth of the visible surface, ``+inf`` where empty.
    tri_id : (H, W) int64 — index of the visible triangle in the input, -1 where empty.
    poly_id : (H, W) int64 — ``poly_id`` of that triangle, -1 where empty.
    fragments : pixels covered by all triangles, overdraw included.
    pixels_written : fragments that passed the Z test when they arrived, in submission
        order (the writes of a serial Z-buffer).
    pixels_covered : pixels that end up non-empty.
    """

    colour: np.ndarray
    depth: np.ndarray
    tri_id: np.ndarray
    poly_id: np.ndarray
    fragments: int
    pixels_written: int
    pixels_covered: int

    @property
    def width(self) -> int:
        return int(self.depth.shape[1])

    @property
    def height(self) -> int:
        return int(self.depth.shape[0])

    def to_rgb8(self) -> np.ndarray:
        """(H, W, 3) uint8: ``floor(c * 255 + 0.5)`` (round half up), clamped to 0..255."""
        return np.clip(np.floor(self.colour * 255.0 + 0.5), 0, 255).astype(np.uint8)

    def save_png(self, path: str | Path) -> None:
        """Write :meth:`to_rgb8` as a PNG (Pillow)."""
        from PIL import Image

        Image.fromarray(self.to_rgb8()).save(str(path))


def _check(tris: ScreenTriangles, background) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    xy, z, col = tris.validate(max_coord=MAX_COORD)
    pid = np.asarray(tris.poly_id)
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (3,) or not np.all(np.isfinite(bg)):
        raise RasterhwError(f"background must be three finite numbers, not {background!r}")
    return xy, z, col, np.asarray(pid, dtype=np.int64), bg  # no copy when already int64 (read only)


def _setup(xy: np.ndarray, width: int, height: int) -> dict:
    """Per-triangle set-up, all triangles at once. Returns arrays over the kept triangles."""
    X = snap(xy[:, :, 0]).T  # (3, T) integers on the 1/SUBPIXEL grid
    Y = snap(xy[:, :, 1]).T
    a = [1, 2, 0]  # edge i runs from vertex a[i] to vertex b[i]; it is opposite vertex i
    b = [2, 0, 1]
    dx = X[b] - X[a]  # (3, T)
    dy = Y[b] - Y[a]
    # E_i(P) = dx_i * (Py - Ya_i) - dy_i * (Px - Xa_i); E_0 at vertex 0 = twice the signed area.
    area = dx[0] * (Y[0] - Y[1]) - dy[0] * (X[0] - X[1])
    half = SUBPIXEL // 2
    # Rows / columns whose pixel centres lie inside the vertex bounding box, clipped to the frame.
    r0 = np.maximum(np.ceil((Y.min(axis=0) - half) / SUBPIXEL), 0)
    r1 = np.minimum(np.floor((Y.max(axis=0) - half) / SUBPIXEL), height - 1)
    c0 = np.maximum(np.ceil((X.min(axis=0) - half) / SUBPIXEL), 0)
    c1 = np.minimum(np.floor((X.max(axis=0) - half) / SUBPIXEL), width - 1)
    keep = np.flatnonzero((area != 0) & (r1 >= r0) & (c1 >= c0))
    s = np.sign(area[keep])
    dx, dy, Xa, Ya = dx[:, keep], dy[:, keep], X[a][:, keep], Y[a][:, keep]
    # Top-left flags in the triangle's own orientation (s * edge keeps the interior on its
    # right in y-down screen space): a left edge goes up, a top edge is horizontal going right.
    sdy, sdx = s * dy, s * dx
    topleft = (sdy < 0) | ((sdy == 0) & (sdx > 0))
    # Per row, E_i(col) = K_i(row) + S_i * col with K_i(row) = dx_i * Yc + k_i.
    k = -dx * Ya - dy * (half - Xa)
    S = -SUBPIXEL * dy
    # Fill rule in the triangle's own orientation: s*E_i >= thr_i  <=>  sS_i * col >= N_i with
    # N_i(row) = thr_i - s*K_i(row) = na_i * Yc + nb_i (exact integers, see _fragments).
    sS = s * S
    sS[sS == 0] = 0.0  # horizontal edges: +0.0, never -0.0, so N / sS = +inf exactly when N > 0
    thr = np.where(topleft, 0.0, 1.0)
    na = -s * dx
    nb = thr - s * k
    # An edge with sS < 0 bounds the span from above, any other edge from below.
    side = np.where(sS < 0, -np.inf, np.inf)
    # One (14, T) table repeated over the row records, one (7, T) table gathered for the
    # records that have fragments: what the weights need (E_1, E_2 and the area).
    table = np.concatenate([na, nb, sS, side, c0[keep][None], c1[keep][None]])
    wtab = np.concatenate([dx[1:], k[1:], S[1:], area[keep][None]])
    return {"keep": keep, "table": table, "wtab": wtab, "r0": r0[keep].astype(np.int64),
            "r1": r1[keep].astype(np.int64)}


def _fragments(st: dict, lo_t: int, hi_t: int, width: int, z: np.ndarray, row0: int = 0) -> dict:
    """Spans, fragments and fragment depths for kept triangles ``lo_t .. hi_t - 1``; pixel
    indices count from row ``row0`` (the first row of the tile being rendered)."""
    r0, r1 = st["r0"][lo_t:hi_t], st["r1"][lo_t:hi_t]
    nrows = r1 - r0 + 1
    nr = int(nrows.sum())
    rt = np.repeat(np.arange(lo_t, hi_t), nrows)  # kept-triangle index of each row record
    first = np.cumsum(nrows) - nrows
    row = np.repeat(r0 - first, nrows) + np.arange(nr)
    tab = np.repeat(st["table"][:, lo_t:hi_t], nrows, axis=1)
    na, nb, sS, side, c0, c1 = tab[0:3], tab[3:6], tab[6:9], tab[9:12], tab[12], tab[13]
    Yc = (row * SUBPIXEL + SUBPIXEL // 2).astype(np.float64)
    N = na * Yc
    N += nb  # (3, R), exact integers
    # The span is where sS_i * col >= N_i for all three edges.
    # floor/ceil of the float quotient are exact: N and sS are integers with |sS| <= 2**33,
    # so a non-integer quotient is at least 2**-33 from an integer, while the rounding error
    # of a quotient below 2**17 in size is at most 2**-36. A larger quotient lies beyond
    # every column a triangle can reach (|coordinates| <= 2**16 px), where an error of one
    # changes nothing once the span is clamped to the bounding box.
    with np.errstate(divide="ignore", invalid="ignore"):
        q = N / sS
        # sS > 0: ceil(q) is the smallest column that passes, a lower bound; sS < 0: floor(q)
        # is the largest, an upper bound (``side`` = -inf masks the other kind). A horizontal
        # edge (sS = 0) passes every column or none: q is -inf or NaN (N < 0 or N = 0, all
        # pass) or +inf (N > 0, none); it acts as a lower bound, and fmax ignores NaN.
        lo = np.fmax.reduce(np.minimum(np.ceil(q), side), axis=0)
        hi = np.fmax(np.floor(q), side).min(axis=0)
    hi = np.minimum(hi, c1)
    lo = np.maximum(lo, c0)
    n = np.maximum(hi - lo + 1, 0).astype(np.int64)
    nz = np.flatnonzero(n)
    n = n[nz]
    F = int(n.sum())
    if F == 0:
        return {"F": 0}
    lo = lo[nz].astype(np.int64)
    start = np.cumsum(n) - n
    # Fragment-sized arrays live in the per-thread pool (see _Pool); each per-record value is
    # spread over its fragments by a gather on ``rec``, the record of each fragment.
    pool = _pool()
    iota = pool.iota(F)
    rec = pool.get("rec", F, np.int64)
    rec.fill(0)
    rec[start[1:]] = 1
    np.cumsum(rec, out=rec)

    def spread(v: np.ndarray, name: str, dtype=np.float64) -> np.ndarray:
        return np.take(v, rec, out=pool.get(name, F, dtype), mode="clip")

    pix = spread((row[nz] - row0) * width + (lo - start), "pix", np.int64)
    pix += iota
    colf = spread((lo - start).astype(np.float64), "col")
    colf += iota  # exact: |col| < 2**31
    rt = rt[nz]
    dx1, dx2, k1, k2, S1, S2, area = np.take(st["wtab"], rt, axis=1)
    Yc = Yc[nz]
    K1 = dx1 * Yc + k1  # E_1, E_2 at column 0 of the row, exact integers
    K2 = dx2 * Yc + k2
    zr = np.take(z, rt, axis=1)  # (vertex, record)
    # Barycentric weights (w0 = (1 - w1) - w2 is exact, 1 or 0, at every vertex) and depth,
    # computed in place.
    arear = spread(area, "area")
    t = pool.get("t", F)
    w1 = spread(S1, "w1")
    w1 *= colf
    w1 += np.take(K1, rec, out=t, mode="clip")
    w1 /= arear
    w2 = spread(S2, "w2")
    w2 *= colf
    w2 += np.take(K2, rec, out=t, mode="clip")
    w2 /= arear
    w0 = np.subtract(1.0, w1, out=pool.get("w0", F))
    w0 -= w2
    # Depth z = w0*z0 + w1*z1 + w2*z2, summed left to right; the weights are kept for the
    # colour of the winners.
    zz = spread(zr[0], "z")
    zz *= w0
    np.take(zr[1], rec, out=t, mode="clip")
    t *= w1
    zz += t
    np.take(zr[2], rec, out=t, mode="clip")
    t *= w2
    zz += t
    return {"F": F, "pix": pix, "rec": rec, "z": zz, "w": (w0, w1, w2), "rt": rt}


_local = threading.local()


class _Pool:
    """Fragment-sized scratch arrays kept between calls, one pool per thread.

    Touching fresh memory costs about 2.5 us per 4 kB page on this machine, more than the
    arithmetic done in it, and the C allocator may hand freed blocks back to the kernel
    between chunks, so the fragment arrays of a chunk are written (``out=``) into these
    buffers instead. Nothing from the pool ends up in a Frame. Buffers are sized for the
    largest chunk seen (at most ``CHUNK_CANDIDATES`` fragments are kept; a chunk made of one
    bigger triangle gets temporary buffers)."""

    def __init__(self) -> None:
        self.bufs: dict[str, np.ndarray] = {}
        self._iota = np.arange(0, dtype=np.int64)

    def get(self, name: str, n: int, dtype=np.float64) -> np.ndarray:
        buf = self.bufs.get(name)
        if buf is None or buf.size < n or buf.dtype != dtype:
            buf = np.empty(n, dtype=dtype)
            if n <= CHUNK_CANDIDATES:
                self.bufs[name] = buf
        return buf[:n]

    def iota(self, n: int) -> np.ndarray:
        """``arange(n)`` (int64), read-only."""
        if n > CHUNK_CANDIDATES:
            return np.arange(n, dtype=np.int64)
        if self._iota.size < n:
            self._iota = np.arange(n, dtype=np.int64)
            self._iota.flags.writeable = False
        return self._iota[:n]


def _pool() -> _Pool:
    pool = getattr(_local, "pool", None)
    if pool is None:
        pool = _local.pool = _Pool()
    return pool


_RGB = np.dtype((np.void, 24))  # one pixel's colour (three float64) as a single item


def _scratch(npix: int) -> np.ndarray:
    """A per-pixel int64 count array, all zero (every use restores it), kept between calls
    (per thread) because touching fresh memory costs more than the work done in it."""
    cached = getattr(_local, "scratch", None)
    if cached is None or cached.size != npix:
        cached = np.zeros(npix, dtype=np.int64)
        _local.scratch = cached
    return cached


def _resolve(pix: np.ndarray, zz: np.ndarray, F: int, depth: np.ndarray, cnt: np.ndarray
             ) -> tuple[np.ndarray, int]:
    """The serial Z-buffer over one chunk's fragments (in submission order), vectorised.

    A fragment is written when its depth is below the depth held at its pixel, which is the
    smaller of the depth before the chunk and the depths of the chunk's earlier fragments
    there; the pixel's winner is the last fragment written. Fragments alone at their pixel
    in the chunk (most of them) are decided by one comparison. The others are sorted by
    (pixel, submission order) with one sort of packed integer keys, and each pixel's running
    minimum is carried down its run: step ``k`` takes the ``k``-th fragment of every pixel
    that has more than ``k`` (runs sorted by length, so that is a prefix of them), so the
    steps together touch each of these fragments once.

    Returns (a mask of the winning fragments, one per pixel that was written, and the
    number of writes). ``depth`` is read, not written; ``cnt`` is used as scratch and left zero.
    """
    np.add.at(cnt, pix, 1)
    alone = np.take(cnt, pix) == 1
    cnt[pix] = 0
    held = np.take(depth, pix)  # depth held at each fragment's pixel before the chunk
    won = zz < held
    won &= alone  # a fragment alone at its pixel is written iff it passes against ``held``
    nw = int(np.count_nonzero(won))
    m = np.flatnonzero(~alone)
    if m.size == 0:
        return won, nw
    bits = max(int(F - 1).bit_length(), 1)
    key = np.take(pix, m) << bits
    key |= m
    key.sort()
    mi = key & ((1 << bits) - 1)  # fragment, in (pixel, order) order
    head = np.empty(mi.size, dtype=bool)
    head[0] = True
    np.not_equal(key[1:] >> bits, key[:-1] >> bits, out=head[1:])
    starts = np.flatnonzero(head)
    lens = np.diff(starts, append=mi.size)
    by = np.argsort(-lens, kind="stable")
    starts, lens = starts[by], lens[by]
    zm = np.take(zz, mi)
    run = np.take(held, np.take(mi, starts))  # depth held at each pixel, carried down its run
    win = np.full(starts.size, -1, dtype=np.int64)
    n_at = np.searchsorted(-lens, -np.arange(1, int(lens[0]) + 1), side="right")  # runs longer than k
    for k in range(int(lens[0])):
        n = int(n_at[k])
        at = starts[:n] + k
        zk = np.take(zm, at)
        r = run[:n]
        hit = zk < r
        nw += int(np.count_nonzero(hit))
        np.copyto(r, zk, where=hit)
        np.copyto(win[:n], at, where=hit)
    won[np.take(mi, win[win >= 0])] = True
    return won, nw


def rasterise(tris: ScreenTriangles, *, background=(0.0, 0.0, 0.0), engine: str | None = None) -> Frame:
    """Render screen triangles with a full-frame float Z-buffer and Gouraud colour.

    Parameters
    ----------
    tris : triangles in submission order (see :mod:`rasterhw.golden_model.screen`).
        Either winding is accepted; zero-area triangles (after snapping) cover nothing.
        Any finite ``z`` is accepted (the Z test is a plain float comparison).
    background : RGB in [0, 1] for empty pixels.
    engine : ``"numpy"`` (this module's code, the specification), ``"numba"`` (the compiled
        fast path, bit-identical), or ``None``/``"auto"``: :data:`ENGINE_ENV` if set, else numba
        where it loads (see :func:`choose_engine`).

    Returns
    -------
    Frame (new arrays on every call)
    """
    xy, z, vcol, pid, bg = _check(tris, background)
    W, H = int(tris.width), int(tris.height)
    if choose_engine(engine) == "numba":
        out = depth, tri_id, poly, colour = _outputs(W * H)
        return _frame(out, W, H, *_fast_draw(xy, z, vcol, pid, bg, W, H, 0, H, depth=depth,
                                             colour=colour.reshape(-1), tri=tri_id, poly=poly))
    bands = _bands(W, H, xy.shape[0])
    if len(bands) == 1:
        return _guarded(_rasterise, tris, xy, z, vcol, pid, bg)
    # Row bands in threads (NumPy's loops release the GIL): each pixel's serial Z-buffer sees the
    # same triangles in the same order in its band as in the whole frame (see rasterise_rgb8),
    # so the pixels and counts are exactly those of one band; each band writes its rows of one
    # set of output arrays.
    st = _setup(xy, W, H)
    out = _outputs(W * H)
    parts = list(_executor().map(
        lambda rows: _guarded(_rasterise, tris, xy, z, vcol, pid, bg, st=st, rows=rows,
                              into=tuple(a[rows[0] * W:rows[1] * W] for a in out)), bands))
    return _frame(out, W, H, *(sum(getattr(f, k) for f in parts)
                               for k in ("fragments", "pixels_written", "pixels_covered")))


def _frame(out: tuple, W: int, H: int, fragments: int, written: int, covered: int) -> Frame:
    """The :class:`Frame` of the flat ``(depth, tri_id, poly_id, colour)`` arrays ``out`` and its counts."""
    depth, tri_id, poly, colour = out
    return Frame(colour=colour.reshape(H, W, 3), depth=depth.reshape(H, W), tri_id=tri_id.reshape(H, W),
                 poly_id=poly.reshape(H, W), fragments=int(fragments), pixels_written=int(written),
                 pixels_covered=int(covered))


#: Environment variable choosing the engine when a call does not: ``numpy`` (the specification),
#: ``numba`` (the compiled fast path; an error where numba cannot load), or ``auto`` / unset
#: (numba where it loads, else NumPy with one line on stderr).
ENGINE_ENV = "RASTERHW_REFERENCE"
_FAST = FastPath("rasterhw.golden_model.reference_fast", env=ENGINE_ENV, spec="numpy",
                 fallback="the reference rasteriser runs its NumPy specification (same pixels, slower)")


def choose_engine(engine: str | None = None) -> str:
    """``"numba"`` or ``"numpy"``: the engine that draws for ``engine`` (``None`` = the
    environment variable :data:`ENGINE_ENV`, default ``auto``)."""
    return _FAST.choose(engine)


def _zbuf(n: int) -> np.ndarray:
    """A per-thread float64 Z-buffer of ``n`` pixels (contents undefined), kept between calls."""
    buf = getattr(_local, "zbuf", None)
    if buf is None or buf.size < n:
        buf = _local.zbuf = np.empty(n, dtype=np.float64)
    return buf[:n]


def _fast_draw(xy, z, vcol, pid, bg, W: int, H: int, y0: int, y1: int, *, depth=None, rgb8=None,
               colour=None, tri=None, poly=None) -> tuple[int, int, int]:
    """Rows ``y0 .. y1 - 1`` of the frame by the compiled fast path, into flat arrays holding
    exactly those rows (``None`` = not wanted; without ``depth`` a per-thread Z-buffer is used),
    as :func:`_bands` row bands in threads (the kernel releases the GIL). Returns
    ``(fragments, pixels_written, pixels_covered)``."""
    fast = _FAST.module()
    n = len(_bands(W, y1 - y0, xy.shape[0]))
    X, Y, cuts = fast.prepare(xy, W, H, y0, y1, n * FAST_BANDS_PER_THREAD if n > 1 else 1)
    z = np.ascontiguousarray(z, dtype=np.float64)
    vcol = np.ascontiguousarray(vcol, dtype=np.float64)
    pid = np.ascontiguousarray(pid, dtype=np.int64)
    bg = np.ascontiguousarray(bg, dtype=np.float64)

    def one(rows):
        a, b = rows
        lo, hi = (a - y0) * W, (b - y0) * W
        return fast.band(X, Y, z, vcol, pid, W, H, a, b, bg,
                         depth=depth[lo:hi] if depth is not None else _zbuf(hi - lo),
                         rgb8=None if rgb8 is None else rgb8[3 * lo:3 * hi],
                         colour=None if colour is None else colour[3 * lo:3 * hi],
                         tri=None if tri is None else tri[lo:hi], poly=None if poly is None else poly[lo:hi])

    if n == 1:
        parts = [one((y0, y1))]
    else:  # bands of equal bounding-box work, taken in turn by the calling thread and the workers
        bands = [b for b in itertools.pairwise(cuts) if b[1] > b[0]]
        taken = itertools.count()  # next() is atomic (the GIL): each band is drawn once

        def drain():
            out = []
            while (i := next(taken)) < len(bands):
                out.append(one(bands[i]))
            return out

        rest = [_executor().submit(drain) for _ in range(n - 1)]
        parts = drain()
        for f in rest:
            parts += f.result()
    return tuple(int(sum(p[i] for p in parts)) for i in range(3))


_ID_DTYPES = (np.dtype(np.int32), np.dtype(np.int64))


class Target:
    """Reusable output buffers for :func:`render`: only the outputs a caller asks for, each at
    the width it needs.

    ``rgb8``: (H, W, 3) uint8, :meth:`Frame.to_rgb8` of the colour; ``colour``: (H, W, 3)
    float64; ``depth``: (H, W) float64 (``+inf`` where empty); ``tri_id``, ``poly_id``: (H, W)
    signed integers, -1 where empty, ``True`` for int32 or a dtype (int32 or int64). An output
    not asked for is ``None``. After :func:`render`, ``fragments``, ``pixels_written`` and
    ``pixels_covered`` hold its counts. Every render overwrites the buffers (copy what must
    outlive the next one)."""

    def __init__(self, width: int, height: int, *, rgb8: bool = False, colour: bool = False,
                 depth: bool = False, tri_id=False, poly_id=False):
        if not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1
                   for v in (width, height)):
            raise RasterhwError(f"Target: width and height must be positive integers, not {width!r}x{height!r}")
        self.width, self.height = int(width), int(height)
        h, w = self.height, self.width
        self.rgb8 = np.empty((h, w, 3), np.uint8) if rgb8 else None
        self.colour = np.empty((h, w, 3), np.float64) if colour else None
        self.depth = np.empty((h, w), np.float64) if depth else None
        self.tri_id = self._ids("tri_id", tri_id)
        self.poly_id = self._ids("poly_id", poly_id)
        self.fragments = self.pixels_written = self.pixels_covered = 0

    def _ids(self, name: str, want) -> np.ndarray | None:
        if want is False or want is None:
            return None
        dt = np.dtype(np.int32) if want is True else np.dtype(want)
        if dt not in _ID_DTYPES:
            raise RasterhwError(f"Target: {name} must be True (int32), int32 or int64, not {want!r}")
        return np.empty((self.height, self.width), dt)

    @property
    def counts(self) -> dict:
        return {"fragments": self.fragments, "pixels_written": self.pixels_written,
                "pixels_covered": self.pixels_covered}


def render(tris: ScreenTriangles, target: Target, *, background=(0.0, 0.0, 0.0),
           engine: str | None = None) -> Target:
    """:func:`rasterise` into ``target``'s buffers: the same pixels, only the outputs it holds.

    The NumPy engine renders a :class:`Frame` and converts it (this is the specification of
    every output); the numba engine writes each asked-for output directly, in one pass, and
    allocates nothing per call. Returns ``target`` (its counts set)."""
    xy, z, vcol, pid, bg = _check(tris, background)
    W, H = int(tris.width), int(tris.height)
    if not isinstance(target, Target) or (target.width, target.height) != (W, H):
        raise RasterhwError(f"render: the target must be a Target of {W}x{H}, not {target!r}")
    for name, arr in (("tri_id", target.tri_id), ("poly_id", target.poly_id)):
        if arr is not None and arr.dtype != np.int64:
            info = np.iinfo(arr.dtype)
            top = xy.shape[0] - 1 if name == "tri_id" else (int(pid.max()) if pid.size else 0)
            low = int(pid.min()) if name == "poly_id" and pid.size else 0
            if top > info.max or low < info.min:
                raise RasterhwError(f"render: {name} values up to {top} (from {low}) do not fit the "
                                    f"target's {arr.dtype}; ask for int64")
    if choose_engine(engine) == "numba":
        flat = (None if a is None else a.reshape(-1) for a in
                (target.depth, target.rgb8, target.colour, target.tri_id, target.poly_id))
        d, r8, c, t, p = flat
        counts = _fast_draw(xy, z, vcol, pid, bg, W, H, 0, H, depth=d, rgb8=r8, colour=c, tri=t, poly=p)
    else:
        f = rasterise(tris, background=background, engine="numpy")
        if target.rgb8 is not None:
            target.rgb8[...] = f.to_rgb8()
        for name in ("colour", "depth", "tri_id", "poly_id"):
            arr = getattr(target, name)
            if arr is not None:
                arr[...] = getattr(f, name)
        counts = (f.fragments, f.pixels_written, f.pixels_covered)
    target.fragments, target.pixels_written, target.pixels_covered = (int(v) for v in counts)
    return target


#: Frames of at least this many pixels, with at least this many triangles, are rendered as
#: :data:`THREADS` row bands at once (smaller ones cost more in hand-over than they gain).
THREAD_MIN_PIXELS = 1 << 16
THREAD_MIN_TRIANGLES = 64
#: threads for the row bands: one per CPU, at most 2 (the machines this runs on; llvmpipe,
#: which the bench compares with, also runs one rasteriser thread per CPU)
THREADS = max(1, min(2, os.cpu_count() or 1))
#: row bands per thread on the fast path: the threads take them in turn, so when one thread
#: waits for a core (a busy machine) the others draw its share
FAST_BANDS_PER_THREAD = 3
_pool_lock = threading.Lock()
_exec = None


def _bands(W: int, H: int, n_tris: int) -> list[tuple[int, int]]:
    """Row bands of a frame for :func:`rasterise`: one, or :data:`THREADS` of equal height."""
    n = THREADS if (W * H >= THREAD_MIN_PIXELS and n_tris >= THREAD_MIN_TRIANGLES and H >= THREADS) else 1
    cuts = [H * k // n for k in range(n + 1)]
    return list(itertools.pairwise(cuts))


def _executor():
    global _exec
    with _pool_lock:
        if _exec is None:
            from concurrent.futures import ThreadPoolExecutor

            _exec = ThreadPoolExecutor(THREADS, thread_name_prefix="rasterise")
        return _exec


def _guarded(fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except BaseException:
        _local.scratch = None  # an interrupted layer loop may leave this thread's scratch dirty
        raise


def _outputs(npix: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(depth, tri_id, poly_id, colour (npix, 3)) for ``npix`` pixels, sharing one fresh block
    (a new one per call: a returned Frame is never aliased by a later call)."""
    block = _fresh_block(48 * npix)
    return (block[:8 * npix].view(np.float64), block[8 * npix:16 * npix].view(np.int64),
            block[16 * npix:24 * npix].view(np.int64), block[24 * npix:].view(np.float64).reshape(npix, 3))


def _fresh_block(nbytes: int) -> np.ndarray:
    """A new uint8 buffer of ``nbytes`` whose start is aligned to 2 MiB.

    NumPy asks the kernel for transparent huge pages on allocations of 4 MiB and more, but a
    huge page only backs a 2 MiB-aligned stretch that lies entirely inside the allocation;
    aligning the start makes every whole 2 MiB of the buffer eligible. First touch then costs
    one fault per 2 MiB instead of one per 4 kB (about 0.3 ms against 1 to 1.3 ms per 2 MiB
    on this machine). The unused head of the allocation is never touched, so it costs
    address space only."""
    align = 1 << 21
    if nbytes < align:
        return np.empty(nbytes, dtype=np.uint8)
    raw = np.empty(nbytes + align, dtype=np.uint8)
    off = -raw.ctypes.data % align
    return raw[off:off + nbytes]


def _rasterise(tris, xy, z, vcol, pid, bg, st: dict | None = None, rows: tuple[int, int] | None = None,
               into: tuple | None = None) -> Frame:
    """The frame, or only rows ``rows = (y0, y1)`` of it (a tile: ``st`` is then the set-up of
    the whole frame, restricted here to the triangles that reach the tile). ``into``: the
    tile's (depth, tri_id, poly_id, colour) arrays to write, else new ones (:func:`_outputs`)."""
    W = int(tris.width)
    y0, y1 = rows if rows is not None else (0, int(tris.height))
    H = y1 - y0
    npix = W * H
    depth, tri_id, poly, colour = into if into is not None else _outputs(npix)
    depth.fill(np.inf)
    tri_id.fill(-1)
    poly.fill(-1)
    # Background (a broadcast over a length-3 axis is slow: fill, or copy whole rows).
    if bg.tobytes() == bg[:1].tobytes() * 3:  # same bits in all channels (-0.0 is not 0.0)
        colour.fill(bg[0])
    else:
        np.copyto(colour.reshape(H, 3 * W), np.tile(bg, W))
    cnt = _scratch(npix)  # fragments per pixel in a chunk (all zero between chunks)
    fragments = written = 0
    if st is None and xy.shape[0]:
        st = _setup(xy, W, H)
    elif st is not None:
        st = _restrict(st, y0, y1)
    if st is not None and st["keep"].size:
        keep = st["keep"]
        zk = z[keep].T.copy()  # (vertex, kept triangle)
        pk = pid[keep]
        ctab = vcol[keep].reshape(-1, 9).T.copy()  # (vertex*3 + channel, kept triangle)
        table = st["table"]
        bbox = (st["r1"] - st["r0"] + 1) * (table[13] - table[12] + 1).astype(np.int64)
        # Chunks of consecutive triangles (submission order is preserved across chunks).
        cum = np.cumsum(bbox)
        bounds = [0]
        while bounds[-1] < keep.size:
            base = cum[bounds[-1] - 1] if bounds[-1] else 0
            nxt = int(np.searchsorted(cum, base + CHUNK_CANDIDATES, side="right"))
            bounds.append(max(nxt, bounds[-1] + 1))
        for c in range(len(bounds) - 1):
            fr = _fragments(st, bounds[c], bounds[c + 1], W, zk, y0)
            F = fr["F"]
            if F == 0:
                continue
            fragments += F
            pix, zz = fr["pix"], fr["z"]
            won, nw = _resolve(pix, zz, F, depth, cnt)
            written += nw
            # Colour only for the winners (at most one per pixel in a chunk), gathered in
            # fragment order (ascending indices: sequential reads).
            wf = np.flatnonzero(won)
            wp = np.take(pix, wf)
            depth[wp] = np.take(zz, wf)
            wt = np.take(fr["rt"], np.take(fr["rec"], wf))
            tri_id[wp] = np.take(keep, wt)
            poly[wp] = np.take(pk, wt)
            w0, w1, w2 = (np.take(w, wf) for w in fr["w"])
            rgb = np.empty((wf.size, 3))
            for ch in range(3):
                v = w0 * np.take(ctab[ch], wt)
                v += w1 * np.take(ctab[3 + ch], wt)
                np.add(v, w2 * np.take(ctab[6 + ch], wt), out=rgb[:, ch])
            # One scatter of whole RGB triples (24-byte items).
            colour.view(_RGB)[wp, 0] = rgb.view(_RGB)[:, 0]
    return _frame((depth, tri_id, poly, colour), W, H, fragments, written, np.count_nonzero(tri_id >= 0))


def _restrict(st: dict, y0: int, y1: int) -> dict:
    """The set-up of the triangles whose rows reach ``y0 .. y1 - 1``, rows clipped to them
    (submission order kept, so the tile's serial Z-buffer sees the same sequence)."""
    sel = np.flatnonzero((st["r1"] >= y0) & (st["r0"] < y1))
    return {"keep": st["keep"][sel], "table": st["table"][:, sel], "wtab": st["wtab"][:, sel],
            "r0": np.maximum(st["r0"][sel], y0), "r1": np.minimum(st["r1"][sel], y1 - 1)}


#: pixels per tile of :func:`rasterise_rgb8` (each tile costs ~100 bytes per pixel while it
#: is rendered; the frame kept is 3 bytes per pixel)
TILE_PIXELS = 1 << 21
#: bytes per pixel :func:`rasterise` needs: the Frame (48), the per-pixel scratch (16), and
#: ``to_rgb8`` of it (its float temporaries, 2 x 24, and the result, 3)
FRAME_BYTES_PER_PIXEL = 48 + 16 + 48 + 3
#: bytes per pixel of :func:`rasterise_rgb8` beyond its tiles: the image (3) and one copy of
#: it for the PNG encoder (3)
RGB8_BYTES_PER_PIXEL = 6


def rasterise_rgb8_memory(width: int, height: int, n_triangles: int = 0) -> int:
    """Bytes :func:`rasterise_rgb8` needs for a ``width x height`` frame (an estimate)."""
    tile = min(width * height, max(width, TILE_PIXELS))
    return (RGB8_BYTES_PER_PIXEL * width * height + FRAME_BYTES_PER_PIXEL * tile
            + 40 * CHUNK_CANDIDATES * 8 + 600 * n_triangles)


def rasterise_rgb8(tris: ScreenTriangles, *, background=(0.0, 0.0, 0.0), progress=None,
                   engine: str | None = None) -> tuple[np.ndarray, dict]:
    """:func:`rasterise` for frames too big to hold as a :class:`Frame`: the same pixels,
    rendered in tiles of whole rows (about :data:`TILE_PIXELS` each), keeping only the
    8-bit image.

    Each pixel's serial Z-buffer sees the same triangles in the same order whatever the
    tiling, so the image and the counts are exactly those of ``rasterise(tris)``.

    Returns ``(rgb8 (H, W, 3) uint8, {"fragments", "pixels_written", "pixels_covered"})``.
    ``progress``, if given, is called with the number of rows just finished (tiles are then at
    most 1/32 of the frame, so a bar moves even on a frame of one tile). ``engine``: as for
    :func:`rasterise` (the numba engine writes each tile's RGB8 directly, with a tile-sized
    Z-buffer).
    """
    xy, z, vcol, pid, bg = _check(tris, background)
    W, H = int(tris.width), int(tris.height)
    rgb8 = np.empty((H, W, 3), dtype=np.uint8)
    counts = {"fragments": 0, "pixels_written": 0, "pixels_covered": 0}
    step = max(1, TILE_PIXELS // W)
    if progress is not None:  # at least ~32 updates for a person watching (same pixels: see above)
        step = max(1, min(step, -(-H // 32)))
    if choose_engine(engine) == "numba":
        flat = rgb8.reshape(-1)
        for y0 in range(0, H, step):
            y1 = min(H, y0 + step)
            part = _fast_draw(xy, z, vcol, pid, bg, W, H, y0, y1, rgb8=flat[3 * y0 * W:3 * y1 * W])
            for k, v in zip(counts, part, strict=True):
                counts[k] += v
            if progress is not None:
                progress(y1 - y0)
        return rgb8, counts
    st = _setup(xy, W, H) if xy.shape[0] else None
    try:
        for y0 in range(0, H, step):
            y1 = min(H, y0 + step)
            fr = _rasterise(tris, xy, z, vcol, pid, bg, st=st, rows=(y0, y1))
            rgb8[y0:y1] = fr.to_rgb8()
            for k in counts:
                counts[k] += int(getattr(fr, k))
            del fr
            if progress is not None:
                progress(y1 - y0)
    except BaseException:
        _local.scratch = None
        raise
    return rgb8, counts


def benchmark(tris: ScreenTriangles, repeat: int = 11) -> dict:
    """Time :func:`rasterise` on ``tris`` and trace its peak memory.

    Returns ``{"median_s", "min_s", "repeat", "peak_bytes", "peak_mb", "fragments",
    "pixels_written", "pixels_covered", "triangles", "width", "height"}``. The peak is
    measured in one extra run under :mod:`tracemalloc` (NumPy reports its buffers to it);
    the timed runs are not traced.
    """
    if not isinstance(repeat, int) or repeat < 1:
        raise RasterhwError(f"repeat must be a positive integer, not {repeat!r}")
    times = []
    frame = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        frame = rasterise(tris)
        times.append(time.perf_counter() - t0)
    was_tracing = tracemalloc.is_tracing()
    if not was_tracing:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base, _ = tracemalloc.get_traced_memory()
    rasterise(tris)
    _, peak = tracemalloc.get_traced_memory()
    if not was_tracing:
        tracemalloc.stop()
    return {
        "median_s": statistics.median(times),
        "min_s": min(times),
        "repeat": repeat,
        "peak_bytes": int(peak - base),
        "peak_mb": (peak - base) / 2**20,
        "fragments": frame.fragments,
        "pixels_written": frame.pixels_written,
        "pixels_covered": frame.pixels_covered,
        "triangles": tris.n_triangles,
        "width": tris.width,
        "height": tris.height,
    }


def random_triangles(width: int, height: int, n: int, *, mean_area: float = 128.0,
                     seed: int = 0) -> ScreenTriangles:
    """Random screen triangles for benchmarks and tests (seeded; same seed, same bytes).

    Each triangle is a random triangle of about ``mean_area`` px placed uniformly in the
    frame, with random depth (0..1, one plane per triangle) and random vertex colours.
    """
    if n < 0 or width < 1 or height < 1 or mean_area <= 0:
        raise RasterhwError(f"random_triangles: bad size {width}x{height}, n={n}, mean_area={mean_area}")
    rng = np.random.default_rng(seed)
    centre = rng.random((n, 1, 2)) * [width, height]
    # A unit-ish random triangle has expected area ~0.5 * r^2 * 1.3; scale to mean_area.
    ang = rng.random((n, 3)) * 2 * np.pi
    rad = 0.5 + rng.random((n, 3))
    off = np.stack([np.cos(ang) * rad, np.sin(ang) * rad], axis=-1)
    a = 0.5 * np.abs((off[:, 1, 0] - off[:, 0, 0]) * (off[:, 2, 1] - off[:, 0, 1])
                     - (off[:, 1, 1] - off[:, 0, 1]) * (off[:, 2, 0] - off[:, 0, 0]))
    scale = np.sqrt(mean_area / max(float(a.mean()), 1e-9)) if n else 1.0
    xy = centre + off * scale
    z = np.repeat(rng.random((n, 1)), 3, axis=1) + rng.random((n, 3)) * 0.01
    colour = rng.random((n, 3, 3))
    zq = np.clip(np.rint(z * ((1 << 24) - 1)), 0, (1 << 24) - 1).astype(np.int64)
    return ScreenTriangles(width=width, height=height, xy=xy, z=z, zq=zq, colour=colour,
                           poly_id=np.arange(n, dtype=np.int64))
