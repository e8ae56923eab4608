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
    # every (pair, line) it is active on; the active memory holds pairs in load (FIFO) order, so
    # a line's segments come out by pair index. k steps of 56-bit wrapping adds are one add of k
    # times the step (modular arithmetic; int64 products wrap mod 2**64, then to 56 bits)
    h = eps.h.astype(np.int64)
    pair = np.repeat(np.arange(n), h)
    k = np.arange(pair.size) - np.repeat(np.cumsum(h) - h, h)
    line = eps.y[pair] + k
    active = np.bincount(line, minlength=height)
    over = np.flatnonzero(active > capacity)
    if over.size:
        y = int(over[0])
        raise RasterhwError(f"segment generator: line {y} needs {int(active[y])} "
                            f"simultaneously active edge pairs, more than the active-edge-pair "
                            f"memory's capacity {int(capacity)} (the hardware stalls with "
                            f"'overflow'; split the stream or raise capacity)")
    at = np.argsort(line * max(n, 1) + pair, kind="stable")
    pair, k, line = pair[at], k[at], line[at]
    x = wrap(eps.x[pair] + k * eps.dxdy[pair])
    ln = wrap(eps.len[pair] + k * eps.dlendy[pair])
    xs = np.maximum(_px_ceil(x), 0)
    xe = np.minimum(_px_ceil(x + ln), width)
    cnt = xe - xs
    ok = cnt > 0
    empty = np.bincount(line[~ok], minlength=height)
    p, xs, x, line, k = pair[ok], xs[ok], x[ok], line[ok], k[ok]
    val = wrap(eps.val[p] + k[:, None] * eps.ddy[p])
    off = ((xs << X_FRAC) + HALF_X - x) >> (X_FRAC - OFF_FRAC)   # Q.16, >= 0
    oi = (off >> OFF_FRAC)[:, None]
    of = (off & ((1 << OFF_FRAC) - 1))[:, None]
    d = eps.ddx[p]
    v0 = wrap(val + oi * d + ((of * d) >> OFF_FRAC))
    line_start = np.zeros(height + 1, np.int64)
    line_start[1:] = np.cumsum(np.bincount(line, minlength=height))
    loads = np.bincount(eps.y, minlength=height).astype(np.int64) if n else np.zeros(height, np.int64)
    stats = {"segments": int(p.size), "empty_segments": int(empty.sum()), "aep_max": int(active.max(initial=0)),
             "aep_capacity": int(capacity),
             "edge_pairs": n}
    return Segments(line.astype(np.int64), xs.astype(np.int64), cnt[ok].astype(np.int64),
                    v0.reshape(-1, C).astype(np.int64), d.reshape(-1, C).astype(np.int64), p.astype(np.int64),
                    eps.tag[p].astype(np.int64) if n else p.astype(np.int64),
                    line_start, loads, empty.astype(np.int64), eps.mode, stats)
