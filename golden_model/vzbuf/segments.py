"""Segment blocks, edge blocks and the y-list (seed 001, 2.3.2 1) and fig. 1), and the
segment splitting of algorithm 2.

A *segment* is the part of a convex screen polygon between two consecutive vertex rows: on
every scan line of it the same left edge and the same right edge bound the span.

Segment block (paper): y end, polygon, left edge, right edge, next (y-list link), dz/dx.
Edge block (paper): x, dx/dy, z, dz/dy, i, di/dy at the segment's first line -- no di/dx, so
the intensity slope across a span is computed per span.

Our additions, each said once here:

* ``y0`` (first line; the y-list index it hangs on) and, for the exact top-left fill rule of
  ``docs/conventions.md``, per edge the integer edge-function numerator ``n`` at the current
  line, its step ``dn`` per line and the divisor ``ss``: the span ends are
  ``ceil(n_L / ss_L)`` and ``floor(n_R / ss_R)`` (the reference rasteriser's formula), stepped
  exactly in integers held in float64 beside the paper's float ``x += dx/dy``;
* ``part, parts``: algorithm 2's split in x cuts every line's exact span ``[lo, hi]`` into
  ``parts`` pieces at ``lo + floor(j (hi - lo + 1) / parts)`` -- the edges
  ``L + j (R - L) / parts`` rounded on the line's span, so the pieces partition it exactly;
* one edge block per segment side (a polygon edge spanning two segments gets two blocks):
  nothing reads an edge of a segment that is not active.

y-list order: the segments starting on a line are linked in polygon order (head = the
earliest polygon), our choice; it only decides exact-z ties.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.vzbuf.blocks import SUB, ScreenPolygons

__all__ = ["EdgeBlock", "SegmentBlock", "build_segments", "split_segments", "spans_at", "ylist"]


@dataclass
class EdgeBlock:
    """Per edge, the state at its segment's first line (paper fields, then exact fields)."""

    x: np.ndarray
    dxdy: np.ndarray
    z: np.ndarray
    dzdy: np.ndarray
    i: np.ndarray
    didy: np.ndarray
    n: np.ndarray
    dn: np.ndarray
    ss: np.ndarray


@dataclass
class SegmentBlock:
    """Segments in creation order; ``left``/``right`` index :attr:`edges`."""

    y0: np.ndarray
    yend: np.ndarray
    poly: np.ndarray       # screen-polygon index (ScreenPolygons row)
    left: np.ndarray
    right: np.ndarray
    dzdx: np.ndarray
    part: np.ndarray
    parts: np.ndarray
    edges: EdgeBlock
    src: dict              # the polygon edges each segment side came from (for splitting)

    @property
    def n(self) -> int:
        return int(self.y0.size)


def _edge_state(src: dict, side: str, rows: np.ndarray) -> dict:
    """Edge fields at line ``rows`` for the source edges of one side."""
    XA, YA, XB, YB = (src[f"{side}{k}"] for k in ("XA", "YA", "XB", "YB"))
    zA, zB, iA, iB, s, thr = (src[f"{side}{k}"] for k in ("zA", "zB", "iA", "iB", "s", "thr"))
    dX, dY = XB - XA, YB - YA
    Yc = rows * SUB + SUB // 2
    t = (Yc - YA) / dY
    # per-line steps: one line = SUB grid units = 1 px
    out = {
        "x": (XA + t * dX) / SUB, "dxdy": dX / dY,
        "z": zA + t * (zB - zA), "dzdy": (zB - zA) * SUB / dY,
        "i": iA + t * (iB - iA), "didy": (iB - iA) * SUB / dY,
    }
    # Exact fill rule (reference.py): E(P) = dx (Py - Ya) - dy (Px - Xa) along the polygon's
    # own traversal (dx, dy here are that traversal's, kept in src as tdx, tdy).
    tdx, tdy, tXa, tYa = src[f"{side}tdx"], src[f"{side}tdy"], src[f"{side}tXa"], src[f"{side}tYa"]
    k = -tdx * tYa - tdy * (SUB // 2 - tXa)
    out["n"] = thr - s * (tdx * Yc + k)
    out["dn"] = -s * tdx * SUB
    ss = s * (-SUB * tdy)
    out["ss"] = ss
    return out


def build_segments(sp: ScreenPolygons, height: int) -> SegmentBlock:
    """Fig. 1: every screen polygon -> its segments (whole-array over polygons and edges)."""
    Q = sp.nv.size
    if Q == 0:
        return _empty()
    M = sp.X.shape[1]
    j = np.arange(M)[None, :]
    used = j < sp.nv[:, None]
    nx = (j + 1) % sp.nv[:, None]
    XA, YA = sp.X, sp.Y
    XB, YB = np.take_along_axis(sp.X, nx, 1), np.take_along_axis(sp.Y, nx, 1)
    zA, zB = sp.z, np.take_along_axis(sp.z, nx, 1)
    iA, iB = sp.i, np.take_along_axis(sp.i, nx, 1)
    area = np.where(used, XA * YB - XB * YA, 0.0).sum(axis=1)
    s = np.sign(area)[:, None] * np.ones((1, M))
    tdx, tdy = XB - XA, YB - YA
    sdy = s * tdy
    left = used & (sdy < 0)
    right = used & (sdy > 0)
    # top-left flags: left edges are top-left, right edges are not (horizontal edges bound
    # no segment: their line either belongs to the band below (top) or to none (bottom))
    thr = np.where(left, 0.0, 1.0)
    Ytop, Ybot = np.minimum(YA, YB), np.maximum(YA, YB)
    r0 = np.maximum(np.ceil((Ytop - SUB // 2) / SUB), 0)
    r1 = np.minimum(np.ceil((Ybot - SUB // 2) / SUB) - 1, height - 1)
    # all (left edge, right edge) pairs of a polygon whose line ranges overlap
    lo = np.maximum(r0[:, :, None], r0[:, None, :])
    hi = np.minimum(r1[:, :, None], r1[:, None, :])
    ok = left[:, :, None] & right[:, None, :] & (hi >= lo)
    q, el, er = np.nonzero(ok)
    y0, yend = lo[q, el, er].astype(np.int64), hi[q, el, er].astype(np.int64)
    # edges run top to bottom for the paper's fields
    def pick(arrA, arrB, e):
        down = YA[q, e] <= YB[q, e]
        return np.where(down, arrA[q, e], arrB[q, e]), np.where(down, arrB[q, e], arrA[q, e])

    src = {}
    for side, e in (("L", el), ("R", er)):
        src[f"{side}XA"], src[f"{side}XB"] = pick(XA, XB, e)
        src[f"{side}YA"], src[f"{side}YB"] = pick(YA, YB, e)
        src[f"{side}zA"], src[f"{side}zB"] = pick(zA, zB, e)
        src[f"{side}iA"], src[f"{side}iB"] = pick(iA, iB, e)
        src[f"{side}s"] = s[q, e]
        src[f"{side}thr"] = thr[q, e]
        src[f"{side}tdx"], src[f"{side}tdy"] = tdx[q, e], tdy[q, e]
        src[f"{side}tXa"], src[f"{side}tYa"] = XA[q, e], YA[q, e]
    return _assemble(src, y0, yend, q, np.zeros(q.size, np.int64), np.ones(q.size, np.int64),
                     sp.plane[q, 0].copy())


def _assemble(src, y0, yend, q, part, parts, dzdx) -> SegmentBlock:
    S = y0.size
    L = _edge_state(src, "L", y0.astype(float))
    R = _edge_state(src, "R", y0.astype(float))
    edges = EdgeBlock(**{k: np.concatenate([L[k], R[k]]) for k in L})
    return SegmentBlock(y0=y0, yend=yend, poly=q, left=np.arange(S), right=np.arange(S, 2 * S),
                        dzdx=dzdx, part=part, parts=parts,
                        edges=edges, src=src)


def _empty() -> SegmentBlock:
    z = np.zeros(0)
    zi = np.zeros(0, np.int64)
    return SegmentBlock(zi, zi, zi, zi, zi, z, zi, zi, EdgeBlock(z, z, z, z, z, z, z, z, z), {})


def spans_at(seg: SegmentBlock, idx: np.ndarray, rows: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Exact span ``[lo, hi]`` of segments ``idx`` on lines ``rows`` (closed form, no stepping)."""
    e = seg.edges
    dl = rows - seg.y0[idx]
    nl = e.n[seg.left[idx]] + dl * e.dn[seg.left[idx]]
    nr = e.n[seg.right[idx]] + dl * e.dn[seg.right[idx]]
    return span_from_n(nl, e.ss[seg.left[idx]], nr, e.ss[seg.right[idx]], seg.part[idx], seg.parts[idx], width)


def span_from_n(nl, ssl, nr, ssr, part, parts, width):
    """Span ends from the exact edge numerators (the reference's ceil / floor of N / sS)."""
    lo = np.maximum(np.ceil(nl / ssl), 0)
    hi = np.minimum(np.floor(nr / ssr), width - 1)
    if np.any(parts > 1):
        n = np.maximum(hi - lo + 1, 0)
        base = lo
        lo = base + np.floor(part * n / parts)
        hi = base + np.floor((part + 1) * n / parts) - 1
    return lo.astype(np.int64), hi.astype(np.int64)


def extents(seg: SegmentBlock, width: int) -> tuple[np.ndarray, np.ndarray]:
    """(x length, y length) per segment: the longest span (it is at the first or last line,
    the width being affine in the line up to rounding) and the number of lines."""
    if seg.n == 0:
        return np.zeros(0), np.zeros(0)
    idx = np.arange(seg.n)
    l0, h0 = spans_at(seg, idx, seg.y0, width)
    l1, h1 = spans_at(seg, idx, seg.yend, width)
    xl = np.maximum(np.maximum(h0 - l0 + 1, h1 - l1 + 1), 0)
    return xl.astype(float), (seg.yend - seg.y0 + 1).astype(float)


def split_segments(seg: SegmentBlock, width: int) -> tuple[SegmentBlock, dict]:
    """Algorithm 2's split: "x, y 各方向について、セグメントの最長部が全セグメントの平均長より
    長いセグメントを分割する" -- a segment longer than the mean in y is cut into
    ``ceil(len / mean)`` runs of lines, one longer than the mean in x into ``ceil(len / mean)``
    parts across (see the module docstring); the means are over all segments before splitting.
    """
    if seg.n == 0:
        return seg, {"mean_x": 0.0, "mean_y": 0.0, "segments_before": 0, "segments_after": 0,
                     "split_y": 0, "split_x": 0, "source": np.zeros(0, np.int64)}
    xl, yl = extents(seg, width)
    mx, my = float(xl.mean()), float(yl.mean())
    ky = np.where(yl > my, np.ceil(yl / my), 1).astype(np.int64)
    kx = np.where(xl > mx, np.ceil(xl / max(mx, 1e-300)), 1).astype(np.int64)
    # y pieces: piece p of k covers lines y0 + floor(p n / k) .. y0 + floor((p+1) n / k) - 1
    sid = np.repeat(np.arange(seg.n), ky)
    p = np.arange(sid.size) - np.repeat(np.cumsum(ky) - ky, ky)
    n = yl[sid].astype(np.int64)
    k = ky[sid]
    ny0 = seg.y0[sid] + (p * n) // k
    nyend = seg.y0[sid] + ((p + 1) * n) // k - 1
    # x parts
    kx2 = kx[sid]
    sid2 = np.repeat(sid, kx2)
    ny0 = np.repeat(ny0, kx2)
    nyend = np.repeat(nyend, kx2)
    part = np.arange(sid2.size) - np.repeat(np.cumsum(kx2) - kx2, kx2)
    parts = kx[sid2]
    src = {key: v[sid2] for key, v in seg.src.items()}
    new = _assemble(src, ny0, nyend, seg.poly[sid2], part.astype(np.int64), parts, seg.dzdx[sid2])
    return new, {"mean_x": mx, "mean_y": my, "segments_before": seg.n, "segments_after": new.n,
                 "split_y": int((ky > 1).sum()), "split_x": int((kx > 1).sum()), "source": sid2}


def ylist(seg: SegmentBlock, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The y-list: ``head[y]`` (first segment starting on line y, -1 if none) and ``nxt[s]``.

    Segments starting on the same line are linked in creation (polygon) order.
    """
    order = np.argsort(seg.y0, kind="stable")
    head = np.full(height, -1, np.int64)
    nxt = np.full(seg.n, -1, np.int64)
    if seg.n:
        ys = seg.y0[order]
        first = np.r_[True, ys[1:] != ys[:-1]]
        head[ys[first]] = order[first]
        same = ys[1:] == ys[:-1]
        nxt[order[:-1][same]] = order[1:][same]
    return head, nxt


def concat_segments(parts: list[SegmentBlock]) -> SegmentBlock:
    """Several segment blocks as one (polygon indices offset so they stay distinct)."""
    parts = [p for p in parts if p.n]
    if not parts:
        return _empty()
    if len(parts) == 1:
        return parts[0]
    qoff = np.cumsum([0] + [int(p.poly.max()) + 1 for p in parts[:-1]])
    S = sum(p.n for p in parts)
    keys = ("x", "dxdy", "z", "dzdy", "i", "didy", "n", "dn", "ss")
    E = {k: np.concatenate([getattr(p.edges, k)[:p.n] for p in parts]
                           + [getattr(p.edges, k)[p.n:] for p in parts]) for k in keys}
    cat = lambda name: np.concatenate([getattr(p, name) for p in parts])  # noqa: E731
    return SegmentBlock(y0=cat("y0"), yend=cat("yend"), poly=np.concatenate([p.poly + o for p, o in zip(parts, qoff, strict=True)]),
                        left=np.arange(S), right=np.arange(S, 2 * S), dzdx=cat("dzdx"), part=cat("part"),
                        parts=cat("parts"), edges=EdgeBlock(**E),
                        src={k: np.concatenate([p.src[k] for p in parts]) for k in parts[0].src})
