"""The segment generator (input FIFO, active-edge-pair memory, adders): edge pairs -> the
segments of every scan line, left-end values and per-pixel increments.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.edgepair import EdgePairs
from rasterhw.golden_model.zbm.formats import (
    AEP_CAPACITY,
    HALF_X,
    MAX_HEIGHT,
    MAX_WIDTH,
    MODE_COLOUR,
    OFF_FRAC,
    ONE_X,
    X_FRAC,
    wrap,
)

__all__ = ["Segments", "check_edge_pair_stream", "max_active_edge_pairs", "segment_generator"]


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
    stats : counts (``segments``, ``aep_max``, ``aep_capacity``, ...).
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
    mode: int = MODE_COLOUR
    stats: dict = field(default_factory=dict)

    def line(self, y: int) -> slice:
        return slice(int(self.line_start[y]), int(self.line_start[y + 1]))


def check_edge_pair_stream(eps: EdgePairs, height: int, *, who: str) -> None:
    """The checks every consumer of an edge-pair stream makes (the golden segment generator and
    the HDL drivers): ``len >= 0``, every pair's lines inside ``0..height-1`` (``h >= 1``), top
    lines in FIFO order. ``RasterhwError`` naming ``who`` and the first bad pair otherwise."""
    if len(eps) == 0:
        return
    if eps.len.min() < 0:
        i = int(np.argmin(eps.len))
        raise RasterhwError(f"{who}: edge pair {i} has len {int(eps.len[i])} < 0")
    bad = np.flatnonzero((eps.y < 0) | (eps.h < 1) | (eps.y + eps.h > height))
    if bad.size:
        i = int(bad[0])
        raise RasterhwError(f"{who}: edge pair {i} covers lines {int(eps.y[i])}.."
                            f"{int(eps.y[i] + eps.h[i] - 1)}, outside 0..{height - 1}")
    if np.any(np.diff(eps.y) < 0):
        i = int(np.flatnonzero(np.diff(eps.y) < 0)[0]) + 1
        raise RasterhwError(f"{who}: edge pair {i} (top line {int(eps.y[i])}) is out of "
                            "FIFO order (top lines must not decrease)")


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
    check_edge_pair_stream(eps, height, who="segment generator")
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
             "aep_capacity": int(capacity),
             "edge_pairs": n}
    return Segments(cat["y"].astype(np.int64), cat["x"].astype(np.int64), cat["len"].astype(np.int64),
                    cat["val"].astype(np.int64), cat["inc"].astype(np.int64), cat["ep"].astype(np.int64),
                    eps.tag[cat["ep"].astype(np.int64)] if n else cat["ep"].astype(np.int64),
                    line_start, loads, empty, eps.mode, stats)
