"""The float reference rasteriser: a full-frame Z-buffer with Gouraud colour.

This is the "ideal arithmetic" image every architecture is compared with. It follows the
conventions of :mod:`rasterhw.golden_model.screen` exactly:

* pixel centres at ``(col + 0.5, row + 0.5)``, y down;
* top-left fill rule, decided **exactly**: vertex positions are snapped to a grid of
  ``1/SUBPIXEL`` px (``SUBPIXEL = 256``, round half up) and the edge functions are then
  integers (held in ``int64`` for the span limits and in ``float64`` for the weights; every
  value is an integer below 2**53, so both are exact);
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
3. the spans are expanded to fragments with ``np.repeat`` and the depth of every fragment is
   computed as whole-array operations;
4. Z resolve: fragments are grouped by pixel (stable sort keeps submission order inside a
   pixel) and numbered by layer (0 = the first fragment to arrive at its pixel, 1 = the
   second, ...). Each layer touches every pixel at most once, so a layer is one vectorised
   step of a serial Z-buffer; running the layers in order gives exactly what a serial
   Z-buffer writes (``pixels_written``) and the final winner per pixel;
5. colour is computed only for the winners.

Triangles are processed in chunks of at most about ``CHUNK_CANDIDATES`` bounding-box pixels,
carrying the depth buffer from chunk to chunk, so memory stays bounded for large frames.
"""

from __future__ import annotations

import statistics
import threading
import time
import tracemalloc
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import RasterhwError
from .screen import ScreenTriangles

__all__ = ["SUBPIXEL", "MAX_COORD", "Frame", "rasterise", "benchmark", "random_triangles", "snap"]

#: Sub-pixel grid: vertex coordinates are snapped to multiples of ``1 / SUBPIXEL`` px.
SUBPIXEL = 256
#: Largest vertex coordinate magnitude accepted, in pixels (keeps every edge function an
#: integer below 2**53 on the sub-pixel grid, so float64 holds it exactly).
MAX_COORD = 65536.0
#: Bounding-box pixels per chunk (bounds the size of the fragment arrays).
CHUNK_CANDIDATES = 1 << 18


def snap(v: np.ndarray) -> np.ndarray:
    """Coordinates in pixels -> integers on the sub-pixel grid (float64), round half up."""
    return np.floor(np.asarray(v, dtype=np.float64) * SUBPIXEL + 0.5)


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
    w, h = tris.width, tris.height
    for name, v in (("width", w), ("height", h)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
            raise RasterhwError(f"screen triangles: {name} must be a positive integer, not {v!r}")
    xy = np.asarray(tris.xy, dtype=np.float64)
    if xy.ndim != 3 or xy.shape[1:] != (3, 2):
        raise RasterhwError(f"screen triangles: xy must be (T, 3, 2), got {xy.shape}")
    t = xy.shape[0]
    z = np.asarray(tris.z, dtype=np.float64)
    col = np.asarray(tris.colour, dtype=np.float64)
    pid = np.asarray(tris.poly_id)
    for name, arr, shape in (("z", z, (t, 3)), ("colour", col, (t, 3, 3)), ("poly_id", pid, (t,))):
        if arr.shape != shape:
            raise RasterhwError(f"screen triangles: {name} must be {shape}, got {arr.shape}")
    for name, arr in (("xy", xy), ("z", z), ("colour", col)):
        if not np.all(np.isfinite(arr)):
            bad = int(np.flatnonzero(~np.isfinite(arr).reshape(t, -1).all(axis=1))[0])
            raise RasterhwError(f"screen triangles: triangle {bad} has a NaN or infinite {name}")
    if t and np.abs(xy).max() > MAX_COORD:
        bad = int(np.flatnonzero(np.abs(xy).reshape(t, -1).max(axis=1) > MAX_COORD)[0])
        raise RasterhwError(
            f"screen triangles: triangle {bad} has a vertex coordinate {np.abs(xy[bad]).max():.6g} px "
            f"(more than {MAX_COORD:g} px from the origin)"
        )
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (3,) or not np.all(np.isfinite(bg)):
        raise RasterhwError(f"background must be three finite numbers, not {background!r}")
    return xy, z, col, pid.astype(np.int64), bg


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
    # One (m, T) table so a single gather serves every row record.
    table = np.concatenate([dx, k, S, s * S, np.where(topleft, 0.0, 1.0), s[None],
                            area[keep][None], c0[keep][None], c1[keep][None]])
    return {"keep": keep, "table": table, "r0": r0[keep].astype(np.int64),
            "r1": r1[keep].astype(np.int64)}


def _fragments(st: dict, lo_t: int, hi_t: int, width: int, z: np.ndarray) -> dict:
    """Spans, fragments and fragment depths for kept triangles ``lo_t .. hi_t - 1``."""
    r0, r1 = st["r0"][lo_t:hi_t], st["r1"][lo_t:hi_t]
    nrows = r1 - r0 + 1
    nr = int(nrows.sum())
    rt = np.repeat(np.arange(lo_t, hi_t), nrows)  # kept-triangle index of each row record
    first = np.cumsum(nrows) - nrows
    row = np.repeat(r0 - first, nrows) + np.arange(nr)
    tab = np.repeat(st["table"][:, lo_t:hi_t], nrows, axis=1)
    dx, k, S, sS, thr = tab[0:3], tab[3:6], tab[6:9], tab[9:12], tab[12:15]
    s, area, c0, c1 = tab[15], tab[16], tab[17], tab[18]
    Yc = (row * SUBPIXEL + SUBPIXEL // 2).astype(np.float64)
    K = dx * Yc + k  # (3, R): E_i at column 0 of this row, an exact integer
    # Fill rule in the triangle's own orientation: s*E_i >= thr_i  <=>  sS_i * col >= N_i.
    # floor/ceil of the float quotient are exact: N and sS are integers with |sS| <= 2**33,
    # so a non-integer quotient is at least 2**-33 from an integer, while the rounding error
    # of a quotient below 2**17 in size is at most 2**-36; larger quotients are clipped to
    # just outside the frame, which is all that matters.
    N = thr - s * K
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.clip(N / sS, -2.0, width + 1.0)
    fl = np.floor(q)  # sS < 0: largest col with sS*col >= N
    ce = np.ceil(q)  # sS > 0: smallest col with sS*col >= N
    big = float(width + 2)
    hi = np.where(sS < 0, fl, np.where((sS == 0) & (N > 0), -big, big)).min(axis=0)
    lo = np.where(sS > 0, ce, -big).max(axis=0)
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
    col = np.arange(F, dtype=np.int64)
    col += np.repeat(lo - start, n)
    pix = np.repeat(row[nz] * width, n)
    pix += col
    rec = np.repeat(np.arange(nz.size), n)  # (non-empty) row record of each fragment
    colf = col.astype(np.float64)
    del col
    K1, K2, S1, S2, area = K[1, nz], K[2, nz], S[1, nz], S[2, nz], area[nz]
    zr = z[rt[nz]]
    # Barycentric weights (w0 = (1 - w1) - w2 is exact, 1 or 0, at every vertex) and depth,
    # computed in place to keep the number of fragment-sized temporaries small.
    arear = np.repeat(area, n)
    w1 = np.repeat(S1, n)
    w1 *= colf
    w1 += np.repeat(K1, n)
    w1 /= arear
    w2 = np.repeat(S2, n)
    w2 *= colf
    w2 += np.repeat(K2, n)
    w2 /= arear
    del arear, colf
    zz = np.subtract(1.0, w1)
    zz -= w2
    zz *= np.repeat(zr[:, 0], n)
    w1 *= np.repeat(zr[:, 1], n)  # the weights are not kept: reuse their buffers
    zz += w1
    w2 *= np.repeat(zr[:, 2], n)
    zz += w2
    del w1, w2
    recs = {"row": row[nz], "rt": rt[nz], "K1": K1, "K2": K2, "S1": S1, "S2": S2, "area": area}
    return {"F": F, "pix": pix, "rec": rec, "z": zz, "recs": recs}


def _weights(recs: dict, rec: np.ndarray, col: np.ndarray) -> tuple[np.ndarray, ...]:
    """Barycentric weights of fragments ``(rec, col)``, bit-identical to those in _fragments."""
    colf = col.astype(np.float64)
    area = recs["area"][rec]
    w1 = (recs["S1"][rec] * colf + recs["K1"][rec]) / area
    w2 = (recs["S2"][rec] * colf + recs["K2"][rec]) / area
    return (1.0 - w1) - w2, w1, w2


_local = threading.local()


def _scratch(npix: int) -> tuple[np.ndarray, np.ndarray]:
    """Two per-pixel int64 scratch arrays, kept between calls (per thread) because touching
    fresh memory costs more than the work done in it. ``first`` is returned all ``int64 max``
    (every use restores it); ``win`` holds garbage."""
    cached = getattr(_local, "scratch", None)
    if cached is None or cached.shape[1] != npix:
        cached = np.empty((2, npix), dtype=np.int64)
        cached[1].fill(np.iinfo(np.int64).max)
        _local.scratch = cached
    return cached[0], cached[1]


def rasterise(tris: ScreenTriangles, *, background=(0.0, 0.0, 0.0)) -> Frame:
    """Render screen triangles with a full-frame float Z-buffer and Gouraud colour.

    Parameters
    ----------
    tris : triangles in submission order (see :mod:`rasterhw.golden_model.screen`).
        Either winding is accepted; zero-area triangles (after snapping) cover nothing.
        Any finite ``z`` is accepted (the Z test is a plain float comparison).
    background : RGB in [0, 1] for empty pixels.

    Returns
    -------
    Frame
    """
    xy, z, vcol, pid, bg = _check(tris, background)
    try:
        return _rasterise(tris, xy, z, vcol, pid, bg)
    except BaseException:
        _local.scratch = None  # an interrupted layer loop may leave the scratch dirty
        raise


def _rasterise(tris, xy, z, vcol, pid, bg) -> Frame:
    W, H = int(tris.width), int(tris.height)
    npix = W * H
    # Per-pixel arrays share two blocks: blocks of 4 MB and more are backed by huge pages
    # (NumPy asks for them), which makes first touch several times cheaper than 4 kB pages.
    out = np.empty((3, npix), dtype=np.int64)
    depth = out[0].view(np.float64)
    depth.fill(np.inf)
    tri_id, poly = out[1], out[2]
    tri_id.fill(-1)
    win, first = _scratch(npix)  # winning fragment per pixel (this chunk); layer scratch
    big = np.iinfo(np.int64).max
    colour = np.empty((npix, 3))
    colour[:] = bg
    fragments = written = 0
    if xy.shape[0]:
        st = _setup(xy, W, H)
        keep = st["keep"]
        zk = z[keep]
        ctab = vcol[keep].reshape(-1, 9).T.copy()  # (vertex*3 + channel, kept triangle)
        table = st["table"]
        bbox = (st["r1"] - st["r0"] + 1) * (table[18] - table[17] + 1).astype(np.int64)
        # Chunks of consecutive triangles (submission order is preserved across chunks).
        cum = np.cumsum(bbox)
        bounds = [0]
        while bounds[-1] < keep.size:
            base = cum[bounds[-1] - 1] if bounds[-1] else 0
            nxt = int(np.searchsorted(cum, base + CHUNK_CANDIDATES, side="right"))
            bounds.append(max(nxt, bounds[-1] + 1))
        for c in range(len(bounds) - 1):
            fr = _fragments(st, bounds[c], bounds[c + 1], W, zk)
            F = fr["F"]
            if F == 0:
                continue
            fragments += F
            pix, zz = fr["pix"], fr["z"]
            # Serial Z-buffer, one layer at a time: a layer is the earliest remaining fragment
            # of every pixel, so no pixel appears twice in it and its Z test is one vector op.
            win.fill(-1)
            idx = np.arange(F, dtype=np.int64)
            rp = pix
            while idx.size:
                np.minimum.at(first, rp, idx)
                isfirst = first[rp] == idx
                f, p = idx[isfirst], rp[isfirst]
                first[p] = big
                zf = zz[f]
                ok = zf < depth[p]
                if not ok.all():
                    f, p, zf = f[ok], p[ok], zf[ok]
                written += f.size
                depth[p] = zf
                win[p] = f
                if f.size == idx.size:
                    break
                rest = ~isfirst
                idx, rp = idx[rest], rp[rest]
            # Winners in fragment order (sequential gathers), then colour only for them.
            mark = np.zeros(F, dtype=bool)
            mark[win[win >= 0]] = True
            wf = np.flatnonzero(mark)
            wp = pix[wf]
            rec = fr["rec"][wf]
            recs = fr["recs"]
            wt = recs["rt"][rec]
            tri_id[wp] = keep[wt]
            w0, w1, w2 = _weights(recs, rec, wp - recs["row"][rec] * W)
            flat = colour.reshape(-1)
            for ch in range(3):
                flat[3 * wp + ch] = (w0 * ctab[ch][wt] + w1 * ctab[3 + ch][wt]
                                     + w2 * ctab[6 + ch][wt])
    covered = tri_id >= 0
    if pid.size:
        np.copyto(poly, pid[np.maximum(tri_id, 0)])
        poly[~covered] = -1
    else:
        poly.fill(-1)
    return Frame(
        colour=colour.reshape(H, W, 3),
        depth=depth.reshape(H, W),
        tri_id=tri_id.reshape(H, W),
        poly_id=poly.reshape(H, W),
        fragments=int(fragments),
        pixels_written=int(written),
        pixels_covered=int(np.count_nonzero(covered)),
    )


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
