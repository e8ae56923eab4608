"""A whole-array variant (labelled as such, not the paper's algorithm): every segment line of
every segment is expanded into fragments at once, the Z-buffer is resolved with one sort, and
the shadow count buffer with one weighted ``bincount``.

It uses the same set-up, segment blocks and exact span rule as algorithms 1 and 2 and gives
their frame (tested), but it has no s-list and no passes: vector length = all fragments. It is
the benchmark's "how fast can NumPy do the paper's job" line beside the paper-faithful vz2.
"""

from __future__ import annotations

import time

import numpy as np
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.vzbuf.blocks import blocks_from_scene, quantise_rgbi, setup
from rasterhw.golden_model.vzbuf.segments import (
    SegmentBlock,
    build_segments,
    concat_segments,
    spans_at,
)
from rasterhw.golden_model.vzbuf.shadows import shadow_polygons

__all__ = ["fragments", "render_whole"]

CHUNK = 1 << 18


def _spans(seg: SegmentBlock, width: int, lo_s: int, hi_s: int):
    """Every non-empty (segment, line) span of segments ``lo_s .. hi_s - 1``: segment, line,
    first pixel, pixel count."""
    ids = np.arange(lo_s, hi_s)
    nl = seg.yend[ids] - seg.y0[ids] + 1
    rec = np.repeat(ids, nl)
    rows = seg.y0[rec] + (np.arange(rec.size) - np.repeat(np.cumsum(nl) - nl, nl))
    lo, hi = spans_at(seg, rec, rows, width)
    n = np.maximum(hi - lo + 1, 0)
    keep = n > 0
    return rec[keep], rows[keep], lo[keep], n[keep]


def fragments(seg: SegmentBlock, width: int, lo_s: int = 0, hi_s: int | None = None):
    """Fragments of segments ``lo_s .. hi_s - 1``: (pixel, z, intensity, segment) arrays."""
    hi_s = seg.n if hi_s is None else hi_s
    rec, rows, lo, n = _spans(seg, width, lo_s, hi_s)
    e = seg.edges
    dl = rows - seg.y0[rec]
    L, R = seg.left[rec], seg.right[rec]
    xl = e.x[L] + dl * e.dxdy[L]
    zl = e.z[L] + dl * e.dzdy[L]
    il = e.i[L] + dl * e.didy[L]
    xr = e.x[R] + dl * e.dxdy[R]
    ir = e.i[R] + dl * e.didy[R]
    with np.errstate(divide="ignore", invalid="ignore"):
        didx = np.where(xr > xl, (ir - il) / (xr - xl), 0.0)
    start = np.cumsum(n) - n
    F = int(n.sum())
    r = np.repeat(np.arange(rec.size), n)
    col = lo[r] + (np.arange(F) - start[r])
    xc = col + 0.5 - xl[r]
    z = zl[r] + seg.dzdx[rec][r] * xc
    return rows[r] * width + col, z, il[r] + didx[r] * xc, rec[r]


def shadow_fragments(seg: SegmentBlock, width: int, sign: np.ndarray, lo_s: int, hi_s: int):
    """(pixel, z, sign) of the fragments of shadow segments ``lo_s .. hi_s - 1``, lean: per-line
    values are spread with ``np.repeat`` and only what the count buffer needs is formed."""
    rec, rows, lo, n = _spans(seg, width, lo_s, hi_s)
    e = seg.edges
    dl = rows - seg.y0[rec]
    L = seg.left[rec]
    xl = e.x[L] + dl * e.dxdy[L]
    zl = e.z[L] + dl * e.dzdy[L]
    F = int(n.sum())
    start = np.cumsum(n) - n
    col = np.repeat(lo - start, n) + np.arange(F)
    pix = np.repeat(rows * width, n) + col
    xc = col + 0.5
    xc -= np.repeat(xl, n)
    xc *= np.repeat(seg.dzdx[rec], n)
    xc += np.repeat(zl, n)
    return pix, xc, np.repeat(sign[rec], n)


def _chunks(seg: SegmentBlock):
    nl = seg.yend - seg.y0 + 1
    cum = np.cumsum(nl * 16)
    b = [0]
    while b[-1] < seg.n:
        base = cum[b[-1] - 1] if b[-1] else 0
        b.append(max(int(np.searchsorted(cum, base + CHUNK, side="right")), b[-1] + 1))
    return zip(b[:-1], b[1:], strict=True)


def render_whole(scene: Scene, width: int = 512, height: int = 512, *, shadows: str = "polygons") -> dict:
    """The frame of vz2 (shadows none|polygons) by whole-array operations; CPU times per stage."""
    clk = time.process_time
    t0 = clk()
    blk = blocks_from_scene(scene, width, height)
    sp = setup(scene, width, height, blk)
    sh = shadow_polygons(scene, width, height) if shadows == "polygons" else None
    t1 = clk()
    seg = build_segments(sp, height)
    sseg, sign = None, None
    if sh is not None:
        parts = [build_segments(sh[k], height) for k in ("front", "back") if sh[k] is not None]
        sseg = concat_segments(parts)
        sign = np.concatenate([np.full(p.n, s, np.int64) for p, s in zip(parts, (1, -1), strict=False)])
    t2 = clk()
    npix = width * height
    depth = np.full(npix, np.inf)
    qid = np.full(npix, -1, np.int64)
    inten = np.zeros(npix)
    # Z resolve: one sort by (pixel, z, submission order) per chunk; first of each pixel wins
    nfrag = 0
    for a, b in _chunks(seg):
        pix, z, i, s = fragments(seg, width, a, b)
        nfrag += pix.size
        o = np.lexsort((s, z, pix))
        p = pix[o]
        first = np.r_[True, p[1:] != p[:-1]]
        w = o[first]
        better = z[w] < depth[pix[w]]
        w = w[better]
        depth[pix[w]] = z[w]
        qid[pix[w]] = seg.poly[s[w]]
        inten[pix[w]] = i[w]
    t3 = clk()
    shadowed = np.zeros(npix, bool)
    sfrag = 0
    if sseg is not None and sseg.n:
        count = np.zeros(npix, np.int64)
        for a, b in _chunks(sseg):
            pix, z, sg = shadow_fragments(sseg, width, sign, a, b)
            sfrag += pix.size
            win = z < depth[pix]
            count += np.bincount(pix[win], weights=sg[win], minlength=npix).astype(np.int64)
        shadowed = (qid >= 0) & (count > 0)
        inten[shadowed] = blk.control.ia
    t4 = clk()
    vis = qid >= 0
    poly = np.where(vis, sp.poly[np.maximum(qid, 0)], -1)
    _, i7, rgb8 = quantise_rgbi(blk.polygon.colour[np.maximum(poly, 0)], inten)
    rgb8[~vis] = 0
    t5 = clk()
    return {"poly": poly.reshape(height, width), "depth": depth.reshape(height, width),
            "inten": inten.reshape(height, width), "shadowed": shadowed.reshape(height, width),
            "rgb8": rgb8.reshape(height, width, 3), "fragments_real": nfrag, "fragments_shadow": sfrag,
            "stages": {"1 set-up": t1 - t0, "2 hidden-surface removal": t3 - t2, "3 shadow polygons": t4 - t3,
                       "4 segment build": (t2 - t1) + (t5 - t4)}}
