"""ZB/M golden model (Matsushita scan-line Z-buffer merger, seed 003): bit-accurate and float.

Stages, one function each, named as the hardware blocks (formats in :mod:`.zbm_formats`):

``edge_pairs``          level-1 processor (software, float64 -> fixed point): triangle -> 2 edge pairs
``segment_generator``   input FIFO + active-edge-pair memory + adders: edge pairs -> segments per line
``initial_processor``   per chip: segment -> segment packet for this chip's interleave slot
``chip_scanline``       per chip: segment loop DDA + double-Z pixel memories for one scan line
``merge``               nearest 2 of 4 samples (upstream input wins ties)
``map_samples``         texture / illumination lookups after the merge (mapping mode)
``composite``           alpha-compositing of the final 2 samples
``render_zbm``          the whole machine: units (segment generator + chips) chained by merge ports

Everything from :class:`EdgePairs` on is integer arithmetic in ``int64`` with the hardware's
widths, masks and shifts
the HDL must match it bit for bit. ``render_zbm_float`` is the ideal
twin (same coverage, attributes from the float plane equations, float double Z).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles, snap
from rasterhw.golden_model.zbm.formats import (
    AEP_CAPACITY,
    ATTR_FRAC,
    CHANNELS,
    COORD_LIMIT,
    INTERLEAVES,
    MAX_HEIGHT,
    MAX_WIDTH,
    MODE_COLOUR,
    MODE_MAPPING,
    OFF_FRAC,
    SUBPIX_BITS,
    TEX_BITS,
    X_FRAC,
    Z_BITS,
    Z_EMPTY,
    Z_MAX_SAMPLE,
    pack_edge_pair,
    pack_samples,
    wrap,
)

__all__ = [
    "EdgePairs", "Segments", "DoubleZ", "ZbmResult",
    "edge_pairs", "max_active_edge_pairs", "segment_generator", "initial_processor", "chip_scanline", "unit_scanline",
    "merge", "merge_chain", "composite", "map_samples", "render_zbm", "render_zbm_float",
    "default_maps",
]

SUB = 1 << SUBPIX_BITS          # sub-pixel grid, 256
HALF_SUB = SUB // 2
ONE_X = 1 << X_FRAC
HALF_X = ONE_X >> 1
ONE_A = 1 << ATTR_FRAC
HALF_A = ONE_A >> 1
Z_SCALE = (1 << Z_BITS) - 1     # float z in [0, 1] -> Z LSBs (same as ScreenTriangles.zq)
TEX = 1 << TEX_BITS
INC_LIMIT = (1 << 47) - 1       # attribute increments saturate here (keeps offset * inc in int64)
VAL_LIMIT = (1 << 53) - 1       # attribute start values saturate here (room for 511 line steps)


# ====================================================================== data types
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


@dataclass
class Segments:
    """Segments as the segment generator emits them, line by line, in emission order.

    Attributes
    ----------
    y, x, len : (S,) line, first covered pixel, covered pixels (>= 1).
    val, inc : (S, C) Q.24 value at the centre of pixel ``x`` and per-pixel increment.
    ep, tag : (S,) edge-pair index (in the stream given) and triangle index (model-only).
    line_start : (H + 1,) segments of line y are ``line_start[y]:line_start[y+1]``.
    loads : (H,) edge pairs loaded from the FIFO at the start of each line.
    empty : (H,) active edge pairs whose segment was empty after the fill rule and clipping.
    late_steps : (H,) always 0 (kept for compatibility: no pair is ever loaded late; a stream
        over capacity raises instead).
    stats : counts (``segments``, ``aep_max``, ``stall_lines``, ``segments_lost``, ...).
    """

    y: np.ndarray
    x: np.ndarray
    len: np.ndarray
    val: np.ndarray
    inc: np.ndarray
    ep: np.ndarray
    tag: np.ndarray
    line_start: np.ndarray
    loads: np.ndarray
    empty: np.ndarray
    late_steps: np.ndarray
    mode: int = MODE_COLOUR
    stats: dict = field(default_factory=dict)

    def line(self, y: int) -> slice:
        return slice(int(self.line_start[y]), int(self.line_start[y + 1]))


@dataclass
class DoubleZ:
    """Double-Z pixels: ``[..., 0]`` nearest sample, ``[..., 1]`` second (Z_EMPTY = none).

    z, a : (..., 2) int64
    c : (..., 2, 4) int64 (r, g, b, 0 or um, vm, ui, vi);
    tag : (..., 2) triangle index, -1 = empty (model-only, not on the bus).
    """

    z: np.ndarray
    a: np.ndarray
    c: np.ndarray
    tag: np.ndarray

    @staticmethod
    def empty(shape) -> DoubleZ:
        shape = tuple(np.atleast_1d(shape)) if not isinstance(shape, tuple) else shape
        return DoubleZ(np.full(shape + (2,), Z_EMPTY, np.int64), np.zeros(shape + (2,), np.int64),
                       np.zeros(shape + (2, 4), np.int64), np.full(shape + (2,), -1, np.int64))

    def words(self) -> np.ndarray:
        """(..., 2) uint64 sample words (:data:`SAMPLE` layout); s0 then s1 = the merge word."""
        return pack_samples(self.z, self.a, self.c)

    def copy(self) -> DoubleZ:
        return DoubleZ(self.z.copy(), self.a.copy(), self.c.copy(), self.tag.copy())


@dataclass
class ZbmResult:
    rgb8: np.ndarray          # (H, W, 3) uint8
    pixels: DoubleZ           # (H, W) final double-Z buffers after the merge chain
    unit_pixels: list         # per unit (H, W) double-Z line buffers before merging
    stats: dict


# ====================================================================== level 1: edge pairs
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
    rounded to nearest Q.24. Lines are clipped to the frame
    pairs with no line are dropped.

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
            # x = n / (256 dy) px -> Q.40 = floor(n * 2**32 / dy); dx/dy -> floor(dX * 2**40 / dy).
            # dx/dy is only used when h >= 2, and then dy > 1 px, so |dx/dy| < 4096 fits the slot;
            # a one-line pair carries dx/dy = 0.
            dy = yb - ya
            n = xa * dy + (Yc - ya) * (xb - xa)
            return _divfloor(n, dy, 32), np.where(hk >= 2, _divfloor(xb - xa, dy, X_FRAC), 0)

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


# ====================================================================== segment generator
def _px_ceil(xq: np.ndarray) -> np.ndarray:
    """First pixel whose centre is >= xq (Q.40): ceil(xq - 0.5)."""
    return (xq - HALF_X + ONE_X - 1) >> X_FRAC


def max_active_edge_pairs(eps: EdgePairs) -> tuple[int, int]:
    """(count, line): the most edge pairs active on one scan line, and the first such line.

    Every pair is active on lines ``y .. y + h - 1``; the segment generator needs this many
    entries of active-edge-pair memory (``capacity``) or it stalls with ``overflow``."""
    if len(eps) == 0:
        return 0, 0
    top = int((eps.y + eps.h).max()) + 1
    d = np.zeros(top + 1, np.int64)
    np.add.at(d, eps.y, 1)
    np.add.at(d, eps.y + eps.h, -1)
    c = np.cumsum(d)
    y = int(np.argmax(c))
    return int(c[y]), y


def segment_generator(eps: EdgePairs, height: int, *, width: int = MAX_WIDTH,
                      capacity: int = AEP_CAPACITY) -> Segments:
    """Edge pairs (FIFO order) -> the segments of every scan line, line by line.

    Per line ``y``: (1) the loader moves every FIFO edge pair whose top line is ``<= y`` into the
    active-edge-pair memory (appended, FIFO order); (2) the active pairs are read in memory
    order, each emits its segment for line ``y`` (if not empty after the fill rule and clipping
    to ``[0, width)``), is stepped (``x += dx/dy``, ``len += dlen/dy``, attributes ``+= d/dy``,
    56-bit wrap) and written back unless this was its last line (the paper: "read in order,
    updated, and only the ones still needed are stored back").

    No loss: if line ``y`` needs more simultaneously active edge pairs than ``capacity``, the
    hardware cannot produce the line (it stalls and raises ``overflow``); this model raises
    :class:`RasterhwError` naming the line and the count. Drivers can check first with
    :func:`max_active_edge_pairs`.

    Left-end values: the value on the edge plus ``floor(off * d/dx)`` where ``off`` is the
    distance from the edge to the centre of the first pixel, truncated to Q.16.
    """
    n = len(eps)
    if not isinstance(height, (int, np.integer)) or not 1 <= height <= MAX_HEIGHT:
        raise RasterhwError(f"segment generator: height must be in 1..{MAX_HEIGHT}, not {height!r}")
    if not isinstance(width, (int, np.integer)) or not 1 <= width <= MAX_WIDTH:
        raise RasterhwError(f"segment generator: width must be in 1..{MAX_WIDTH}, not {width!r}")
    if not isinstance(capacity, (int, np.integer)) or capacity < 1:
        raise RasterhwError(f"segment generator: capacity must be a positive integer, not {capacity!r}")
    if n:
        if eps.len.min() < 0:
            i = int(np.argmin(eps.len))
            raise RasterhwError(f"segment generator: edge pair {i} has len {int(eps.len[i])} < 0")
        bad = np.flatnonzero((eps.y < 0) | (eps.h < 1) | (eps.y + eps.h > height))
        if bad.size:
            i = int(bad[0])
            raise RasterhwError(f"segment generator: edge pair {i} covers lines {int(eps.y[i])}.."
                                f"{int(eps.y[i] + eps.h[i] - 1)}, outside 0..{height - 1}")
        if np.any(np.diff(eps.y) < 0):
            i = int(np.flatnonzero(np.diff(eps.y) < 0)[0]) + 1
            raise RasterhwError(f"segment generator: edge pair {i} (top line {int(eps.y[i])}) is out of "
                                "FIFO order (top lines must not decrease)")
    C = eps.val.shape[1]
    x = eps.x.copy()
    ln = eps.len.copy()
    val = eps.val.copy()
    left = eps.h.copy()
    active = np.zeros(0, np.int64)
    nxt = 0
    out = {k: [] for k in ("y", "x", "len", "val", "inc", "ep")}
    line_start = np.zeros(height + 1, np.int64)
    loads = np.zeros(height, np.int64)
    empty = np.zeros(height, np.int64)
    late = np.zeros(height, np.int64)
    aep_max = 0
    count = 0
    for y in range(height):
        # (1) loader
        start = nxt
        while nxt < n and eps.y[nxt] <= y:
            nxt += 1
        if active.size + (nxt - start) > capacity:
            raise RasterhwError(f"segment generator: line {y} needs {active.size + nxt - start} "
                                f"simultaneously active edge pairs, more than the active-edge-pair "
                                f"memory's capacity {int(capacity)} (the hardware stalls with "
                                f"'overflow'; split the stream or raise capacity)")
        active = np.concatenate([active, np.arange(start, nxt)])
        loads[y] = nxt - start
        aep_max = max(aep_max, active.size)
        # (2) emit
        if active.size:
            a = active
            xs = np.maximum(_px_ceil(x[a]), 0)
            xe = np.minimum(_px_ceil(x[a] + ln[a]), width)
            cnt = xe - xs
            ok = cnt > 0
            empty[y] = int((~ok).sum())
            k = a[ok]
            if k.size:
                off = ((xs[ok] << X_FRAC) + HALF_X - x[k]) >> (X_FRAC - OFF_FRAC)   # Q.16, >= 0
                oi = (off >> OFF_FRAC)[:, None]
                of = (off & ((1 << OFF_FRAC) - 1))[:, None]
                d = eps.ddx[k]
                v0 = wrap(val[k] + oi * d + ((of * d) >> OFF_FRAC))
                for key, arr in (("y", np.full(k.size, y)), ("x", xs[ok]), ("len", cnt[ok]),
                                 ("val", v0), ("inc", d), ("ep", k)):
                    out[key].append(arr)
                count += k.size
            # step
            x[a] = wrap(x[a] + eps.dxdy[a])
            ln[a] = wrap(ln[a] + eps.dlendy[a])
            val[a] = wrap(val[a] + eps.ddy[a])
            left[a] -= 1
            active = a[left[a] > 0]
        line_start[y + 1] = count
    cat = {k: (np.concatenate(v) if v else np.zeros((0, C) if k in ("val", "inc") else 0, np.int64))
           for k, v in out.items()}
    stats = {"segments": count, "empty_segments": int(empty.sum()), "aep_max": aep_max,
             "aep_capacity": int(capacity), "stall_lines": 0, "segments_lost": 0,
             "edge_pairs": n}
    return Segments(cat["y"].astype(np.int64), cat["x"].astype(np.int64), cat["len"].astype(np.int64),
                    cat["val"].astype(np.int64), cat["inc"].astype(np.int64), cat["ep"].astype(np.int64),
                    eps.tag[cat["ep"].astype(np.int64)] if n else cat["ep"].astype(np.int64),
                    line_start, loads, empty, late, eps.mode, stats)


# ====================================================================== ZB/M chip
def _check_interleave(interleave: int, chip: int | None = None) -> None:
    if interleave not in INTERLEAVES:
        raise RasterhwError(f"ZB/M: interleave must be 1, 2, 4, 8 or 16, not {interleave!r}")
    if chip is not None and not (isinstance(chip, (int, np.integer)) and 0 <= chip < interleave):
        raise RasterhwError(f"ZB/M: chip must be in 0..{interleave - 1}, not {chip!r}")


def initial_processor(x: np.ndarray, ln: np.ndarray, val: np.ndarray, inc: np.ndarray,
                      chip: int, interleave: int):
    """Segments -> this chip's packets: first owned pixel, owned count, values there, inc * I.

    Chip ``c`` owns screen pixels ``x % I == c``. ``j = (c - x) mod I`` (< 16) pixels are
    skipped with a small multiply ``j * inc``
    the increment becomes ``inc << log2(I)``.
    Returns ``(px, n, v, inc_i, keep)``
    ``keep`` marks segments with ``n >= 1`` (the others
    are dropped by the initial processor).
    """
    _check_interleave(interleave, chip)
    j = (chip - x) % interleave
    px = x + j
    n = np.maximum(-(-(ln - j) // interleave), 0)
    keep = n > 0
    v = wrap(val + j[:, None] * inc)
    inc_i = wrap(inc << (interleave.bit_length() - 1))
    return px, n, v, inc_i, keep


def _samples(v: np.ndarray, mode: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel DDA values (N, C) Q.24 -> sample fields z, a, c (N, 4). Round half up, clamp."""
    r = (v + HALF_A) >> ATTR_FRAC
    z = np.clip(r[:, 0], 0, Z_MAX_SAMPLE)
    a = np.clip(r[:, -1], 0, 255)
    c = np.zeros((v.shape[0], 4), np.int64)
    if mode == MODE_COLOUR:
        c[:, :3] = np.clip(r[:, 1:4], 0, 255)
    else:   # texel index: floor, wrapped to the 256-texel map
        c[:, :4] = (v[:, 1:5] >> ATTR_FRAC) & (TEX - 1)
    return z, a, c


def _insert(buf: DoubleZ, pos: np.ndarray, z, a, c, tag) -> int:
    """Double-Z insert at distinct positions; strict ``<``: on a tie the stored sample stays."""
    z0, z1 = buf.z[pos, 0], buf.z[pos, 1]
    f = z < z0                  # new becomes nearest, old nearest moves to second
    s = (~f) & (z < z1)         # new becomes second
    pf, ps = pos[f], pos[s]
    for arr in (buf.z, buf.a, buf.tag):
        arr[pf, 1] = arr[pf, 0]
    buf.c[pf, 1] = buf.c[pf, 0]
    buf.z[pf, 0], buf.a[pf, 0], buf.c[pf, 0], buf.tag[pf, 0] = z[f], a[f], c[f], tag[f]
    buf.z[ps, 1], buf.a[ps, 1], buf.c[ps, 1], buf.tag[ps, 1] = z[s], a[s], c[s], tag[s]
    return int(f.sum() + s.sum())


def chip_scanline(segs: Segments, y: int, chip: int, interleave: int, width: int,
                  buf: DoubleZ | None = None) -> tuple[DoubleZ, dict]:
    """One chip, one scan line: segment packets through the loop, double-Z pixel memories.

    The pixel memory holds the chip's ``ceil(width / I)`` pixels (chip pixel ``q`` = screen x
    ``q * I + chip``
    pixel processor ``q % 8`` owns it). For each segment of line ``y`` in
    emission order: the initial processor forms the packet
    pixel ``k`` of the packet gets the
    value ``v + k * (inc * I)`` (the loop's repeated 56-bit adds) and is Z-tested into the
    double-Z memory. Returns the memory and counts (``packets``, ``pixels``, ``writes``).
    """
    _check_interleave(interleave, chip)
    npx = -(-(width - chip) // interleave)
    buf = DoubleZ.empty((npx,)) if buf is None else buf
    sl = segs.line(y)
    px, n, v, inc_i, keep = initial_processor(segs.x[sl], segs.len[sl], segs.val[sl], segs.inc[sl],
                                              chip, interleave)
    tags = segs.tag[sl]
    pixels = writes = 0
    for s in np.flatnonzero(keep):
        k = np.arange(n[s])
        vals = wrap(v[s][None, :] + k[:, None] * inc_i[s][None, :])
        z, a, c = _samples(vals, segs.mode)
        q = (px[s] - chip) // interleave + k
        writes += _insert(buf, q, z, a, c, np.full(k.size, tags[s]))
        pixels += int(k.size)
    return buf, {"packets": int(keep.sum()), "pixels": pixels, "writes": writes}


def unit_scanline(segs: Segments, y: int, interleave: int, width: int) -> tuple[DoubleZ, dict]:
    """All chips of a unit on line ``y``, their memories interleaved back to screen order."""
    line = DoubleZ.empty((width,))
    tot = {"packets": 0, "pixels": 0, "writes": 0}
    for chip in range(min(interleave, width)):
        b, st = chip_scanline(segs, y, chip, interleave, width)
        xs = np.arange(chip, width, interleave)
        line.z[xs], line.a[xs], line.c[xs], line.tag[xs] = b.z, b.a, b.c, b.tag
        for k in tot:
            tot[k] += st[k]
    return line, tot


def _unit_frame_fast(segs: Segments, height: int, width: int) -> tuple[DoubleZ, dict]:
    """Bit-identical shortcut for a whole unit: value at pixel x = v + (x - x0) * inc (mod 2**56).

    Holds because the initial processor's ``j * inc`` plus ``k`` loop adds of ``inc << log2 I``
    is ``(j + k * I) * inc`` in modular integer arithmetic, so the image does not depend on
    the interleave (a test checks it against :func:`chip_scanline`).
    """
    buf = DoubleZ.empty((height, width))
    flat = DoubleZ(buf.z.reshape(-1, 2), buf.a.reshape(-1, 2), buf.c.reshape(-1, 2, 4), buf.tag.reshape(-1, 2))
    pixels = writes = 0
    for s in range(segs.y.shape[0]):
        k = np.arange(segs.len[s])
        vals = wrap(segs.val[s][None, :] + k[:, None] * segs.inc[s][None, :])
        z, a, c = _samples(vals, segs.mode)
        pos = segs.y[s] * width + segs.x[s] + k
        writes += _insert(flat, pos, z, a, c, np.full(k.size, segs.tag[s]))
        pixels += int(k.size)
    return buf, {"pixels": pixels, "writes": writes, "packets": None}


# ====================================================================== merge, mapping, composite
def merge(a: DoubleZ, b: DoubleZ) -> DoubleZ:
    """Merger: nearest 2 of ``a``'s 2 and ``b``'s 2 samples; ``a`` (upstream input) wins ties.

    Same selection as ``hdl/zbm_merger.py``'s ``merge_words``: ``s0 = a0 if a0.z <= b0.z else
    b0``
    ``s1`` the nearer of (a1, b0) or of (a0, b1), upstream first on equal Z. Equivalent to
    a stable sort of (a0, a1, b0, b1) by Z, so chaining is associative.
    """
    a_first = a.z[..., 0] <= b.z[..., 0]
    s1a = a.z[..., 1] <= b.z[..., 0]
    s1b = a.z[..., 0] <= b.z[..., 1]
    out = DoubleZ.empty(a.z.shape[:-1])
    for name in ("z", "a", "c", "tag"):
        A, B = getattr(a, name), getattr(b, name)
        if name == "c":       # (..., 2, 4): put the slot axis last so masks broadcast
            A, B = np.moveaxis(A, -2, -1), np.moveaxis(B, -2, -1)
            m0, m1a, m1b = a_first[..., None], s1a[..., None], s1b[..., None]
        else:
            m0, m1a, m1b = a_first, s1a, s1b
        s0 = np.where(m0, A[..., 0], B[..., 0])
        s1 = np.where(m0, np.where(m1a, A[..., 1], B[..., 0]), np.where(m1b, A[..., 0], B[..., 1]))
        res = np.stack([s0, s1], axis=-1)
        setattr(out, name, np.moveaxis(res, -1, -2) if name == "c" else res)
    return out


def merge_chain(units: list[DoubleZ]) -> DoubleZ:
    """Units chained by merge ports: unit 0 is the head (upstream of all)."""
    acc = units[0]
    for u in units[1:]:
        acc = merge(acc, u)
    return acc


def default_maps(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A seeded 256x256 RGB texture (checker + noise) and a 256x256 illumination map."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.arange(TEX), np.arange(TEX))
    chk = ((u // 32 + v // 32) % 2).astype(np.int64)
    tex = np.stack([chk * 200 + 40, (1 - chk) * 180 + 50, rng.integers(0, 256, (TEX, TEX))], axis=-1)
    illum = (128 + 127 * np.cos(u / TEX * 2 * np.pi) * np.sin(v / TEX * np.pi)).astype(np.int64)
    return tex.astype(np.int64), np.clip(illum, 0, 255)


def map_samples(px: DoubleZ, texture: np.ndarray, illum: np.ndarray) -> tuple[DoubleZ, dict]:
    """Mapping after the merge: look up only samples that reach the output.

    A sample reaches the output if it is s0 and valid, or s1, valid, behind a non-opaque s0.
    Colour = ``(tex[vm, um] * illum[vi, ui] + 127) // 255`` per channel. Returns colour-mode
    samples and ``{"texture_lookups", "illum_lookups"}``.
    """
    tex = np.asarray(texture, np.int64)
    il = np.asarray(illum, np.int64)
    if tex.shape != (TEX, TEX, 3) or il.shape != (TEX, TEX):
        raise RasterhwError(f"ZB/M: texture must be ({TEX}, {TEX}, 3) and illum ({TEX}, {TEX}), "
                            f"got {tex.shape}, {il.shape}")
    out = px.copy()
    valid = px.z != Z_EMPTY
    need = valid.copy()
    need[..., 1] &= px.a[..., 0] < 255
    um, vm, ui, vi = (px.c[..., i] for i in range(4))
    t = tex[vm[need], um[need]]
    lit = il[vi[need], ui[need]]
    out.c[need] = 0
    out.c[..., :3][need] = (t * lit[:, None] + 127) // 255
    out.c[~need] = 0
    n = int(need.sum())
    return out, {"texture_lookups": n, "illum_lookups": n}


def composite(px: DoubleZ, background=(0, 0, 0)) -> np.ndarray:
    """Alpha-composite the final 2 samples over the background -> (H, W, 3) uint8.

    ``back = (a1 * c1 + (255 - a1) * bg + 127) // 255`` (bg if s1 empty), then
    ``out = (a0 * c0 + (255 - a0) * back + 127) // 255`` (bg if s0 empty)
    with a0 = 255 the
    output is exactly c0. Samples behind the second are lost (the paper keeps 2).
    """
    bg = np.asarray(background, np.int64)
    if bg.shape != (3,) or bg.min() < 0 or bg.max() > 255:
        raise RasterhwError(f"ZB/M: background must be three integers 0..255, not {background!r}")
    v0 = (px.z[..., 0] != Z_EMPTY)[..., None]
    v1 = (px.z[..., 1] != Z_EMPTY)[..., None]
    a0, a1 = px.a[..., 0:1], px.a[..., 1:2]
    c0, c1 = px.c[..., 0, :3], px.c[..., 1, :3]
    back = np.where(v1, (a1 * c1 + (255 - a1) * bg + 127) // 255, bg)
    out = np.where(v0, (a0 * c0 + (255 - a0) * back + 127) // 255, bg)
    return out.astype(np.uint8)


# ====================================================================== the machine
def render_zbm(tris: ScreenTriangles, *, interleave: int = 8, units: int = 1, mode: int = MODE_COLOUR,
               alpha=None, capacity: int = AEP_CAPACITY, maps=None, background=(0, 0, 0),
               per_chip: bool = False) -> ZbmResult:
    """Render with ``units`` polygon-processing units (segment generator + ``interleave`` chips).

    Triangles are dealt to units round-robin (triangle i -> unit i % units)
    each unit has its
    own segment generator and per-line double-Z buffers; the units' lines are merged along
    the chain (unit 0 at the head), then mapped (mapping mode) and alpha-composited.
    ``per_chip=True`` runs every chip's loop (:func:`chip_scanline`); the default uses the
    bit-identical whole-unit shortcut. Returns :class:`ZbmResult` (rgb8, final double-Z
    buffers, per-unit buffers, stats).
    """
    _check_interleave(interleave)
    if not isinstance(units, (int, np.integer)) or not 1 <= units <= 256:
        raise RasterhwError(f"ZB/M: units must be an integer in 1..256, not {units!r}")
    eps = edge_pairs(tris, mode=mode, alpha=alpha)
    W, H = tris.width, tris.height
    unit_bufs, stats = [], {"units": [], "interleave": interleave, "edge_pairs": len(eps)}
    for u in range(units):
        sel = np.flatnonzero(eps.tag % units == u)
        segs = segment_generator(eps.take(sel), H, width=W, capacity=capacity)
        if per_chip:
            buf = DoubleZ.empty((H, W))
            st = {"packets": 0, "pixels": 0, "writes": 0}
            for y in range(H):
                line, s = unit_scanline(segs, y, interleave, W)
                buf.z[y], buf.a[y], buf.c[y], buf.tag[y] = line.z, line.a, line.c, line.tag
                for k in st:
                    st[k] += s[k]
        else:
            buf, st = _unit_frame_fast(segs, H, W)
        unit_bufs.append(buf)
        stats["units"].append({**segs.stats, **st})
    final = merge_chain(unit_bufs)
    stats["fragments"] = sum(s["pixels"] for s in stats["units"])
    stats["z_writes"] = sum(s["writes"] for s in stats["units"])
    shown = final
    if mode == MODE_MAPPING:
        tex, il = default_maps() if maps is None else maps
        shown, ls = map_samples(final, tex, il)
        stats.update(ls)
        # what mapping before the Z test would cost: one lookup pair per fragment
        stats["lookups_if_mapped_before_merge"] = stats["fragments"]
    return ZbmResult(composite(shown, background), final, unit_bufs, stats)


def render_zbm_float(tris: ScreenTriangles, *, alpha=None, background=(0.0, 0.0, 0.0)) -> dict:
    """The ideal twin (colour mode): the same coverage, float64 everywhere else.

    Coverage comes from the bit-accurate segment generator (it is exact: the reference's top-left
    rule)
    depth and colour are the float plane equations at pixel centres
    double Z in float
    (strict ``<``, earlier segment wins ties)
    float alpha-compositing of the 2 nearest.
    Returns ``{"rgb": (H, W, 3) float in [0, 1], "z": (H, W, 2) float (inf = empty),
    "tag": (H, W, 2)}``.
    """
    eps = edge_pairs(tris, alpha=alpha)
    W, H = tris.width, tris.height
    segs = segment_generator(eps, H, width=W)
    xy = np.asarray(tris.xy, np.float64)
    X = snap(xy[..., 0]) / SUB
    Y = snap(xy[..., 1]) / SUB
    att = _attributes(tris, MODE_COLOUR, alpha) / np.array([Z_SCALE, 255, 255, 255, 255])
    zb = np.full((H, W, 2), np.inf)
    cb = np.zeros((H, W, 2, 4))
    tg = np.full((H, W, 2), -1, np.int64)
    for s in range(segs.y.shape[0]):
        t = segs.tag[s]
        xc = segs.x[s] + np.arange(segs.len[s]) + 0.5
        yc = segs.y[s] + 0.5
        x0, y0 = X[t], Y[t]
        det = (x0[1] - x0[0]) * (y0[2] - y0[0]) - (x0[2] - x0[0]) * (y0[1] - y0[0])
        w1 = ((xc - x0[0]) * (y0[2] - y0[0]) - (x0[2] - x0[0]) * (yc - y0[0])) / det
        w2 = ((x0[1] - x0[0]) * (yc - y0[0]) - (xc - x0[0]) * (y0[1] - y0[0])) / det
        v = att[t, 0] + w1[:, None] * (att[t, 1] - att[t, 0]) + w2[:, None] * (att[t, 2] - att[t, 0])
        xs = segs.x[s] + np.arange(segs.len[s])
        y = segs.y[s]
        z = v[:, 0]
        f = z < zb[y, xs, 0]
        sc = (~f) & (z < zb[y, xs, 1])
        xf, xsc = xs[f], xs[sc]
        zb[y, xf, 1], cb[y, xf, 1], tg[y, xf, 1] = zb[y, xf, 0], cb[y, xf, 0], tg[y, xf, 0]
        zb[y, xf, 0], cb[y, xf, 0], tg[y, xf, 0] = z[f], v[f, 1:], t
        zb[y, xsc, 1], cb[y, xsc, 1], tg[y, xsc, 1] = z[sc], v[sc, 1:], t
    bg = np.asarray(background, np.float64)
    v0 = np.isfinite(zb[..., 0])[..., None]
    v1 = np.isfinite(zb[..., 1])[..., None]
    a0, a1 = cb[..., 0, 3:4], cb[..., 1, 3:4]
    back = np.where(v1, a1 * cb[..., 1, :3] + (1 - a1) * bg, bg)
    rgb = np.where(v0, a0 * cb[..., 0, :3] + (1 - a0) * back, bg)
    return {"rgb": rgb, "z": zb, "tag": tg}
