"""The Pixel Processor (PXP) stages: range clip, start values, span cull, depth search, smooth
shading, anti-jagging, DSLB.

Seed 000, 3.2: each PXP owns a part of every scan line; from the ASL it removes the segments left
of its range and computes the start values (z, i) at its first pixel ("担当範囲の開始点における各
セグメントのZs値、輝度値など ... の初期データを計算する") with its multiplier, then runs the scan-line
HSE (span cull, depth search), smooth shading (eqs. (1)-(4)) and A.J. (eq. (5)) up to its last
pixel and writes its DSLB.

Decisions written here (and in docs/experts.md):

* **Depth search** is per pixel within a span: every segment covering the pixel steps its z by
  dz/dx (one add) and is compared with the nearest so far (one compare; the first needs none).
  Nearest is the smaller z (0 = near). **Tie rule**: on equal z the segment whose ASB address is
  lower wins; the SLP allocates ASBs in PL order, so that is the triangle submitted first -- the
  reference rasteriser's rule. The bit model compares the 16-bit integer part of the running z
  (a 16-bit comparator), clamped to 0..65535.
* **Start value**: the PXP computes a segment's z at the first pixel it owns with one multiply,
  ``z = zL + (xc - xL) dz/dx`` (xc the pixel centre). In the bit model the product is
  ``(xc - xL)[Q.6] * dz/dx[Q.4] >> 6``; ``xc`` moves by 64 per pixel, so the value equals the
  stepped one bit for bit and the image does not depend on where the ranges are cut.
* **Smooth shading**: only the visible segment's intensity is needed; at the start of every
  visible run the PXP computes ``i = iL + (xc - xL) di/dx`` (eq. (4)) with the multiplier and
  then steps di/dx.
* **Anti-jagging**: at a boundary between two visible runs of different *polygons* (a seam
  between two triangles of one polygon is not an edge), the boundary edge is the left edge of the
  right run if that segment starts there, else the right edge of the left run if it ends there
  (an interpenetration line is no polygon edge and is not blended). The A.J. pixel is the pixel
  the edge crosses on the line's centre, ``floor(x_e)``; ``C_L``/``C_R`` are the pixel values left
  and right of the boundary (from HSE and S.S., as the paper says) and ``alpha`` is from
  :mod:`alpha`. Fields R, G, B and I are blended separately (the bit model in Q0.8).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.experts.alpha import ALPHA
from rasterhw.golden_model.experts.formats import ALPHA_BITS, DZ_FRAC, SLOPE_FRAC, X_FRAC, Z_BITS
from rasterhw.golden_model.experts.slp import Records, Setup

__all__ = ["PXP_OPS", "fragments", "depth_search", "smooth_shading", "anti_jagging",
           "pixel_costs"]

#: PXP operations per item (16-bit operations)
PXP_OPS = {
    "range_clip_per_segment": 1,   # xL against the range end (or xR against its start)
    "start_per_segment": 3,        # xc - xL, * dz/dx, + zL
    "span_cull_per_segment": 2,    # enters the span set, leaves it
    "shade_run_start": 3,          # xc - xL, * di/dx, + iL
    "shade_per_pixel": 1,          # + di/dx
    "dslb_per_pixel": 1,           # one write
    "aj_edge_test": 1,             # is this run boundary a polygon edge?
}
# A.J. operations per blended pixel are not typed in: :func:`anti_jagging` runs the counted
# routine of :func:`aj_ops.aj_pixel_ops` on every blended pixel and :func:`pixel_costs` adds
# what each pixel executed.


def fragments(st: Setup, rec: Records, W: int) -> dict:
    """Expand every record's span to pixels: (record, pixel) pairs with z and the compare key."""
    n = np.maximum(rec.c1 - rec.c0 + 1, 0)
    nz = np.flatnonzero(n)
    n = n[nz]
    F = int(n.sum())
    r = np.repeat(nz, n)
    start = np.cumsum(n) - n
    col = np.repeat(rec.c0[nz] - start, n) + np.arange(F)
    t = rec.tri[r]
    if st.bit:
        xc = (col << X_FRAC) + (1 << (X_FRAC - 1))
        zrun = (rec.zl[r] << DZ_FRAC) + (((xc - rec.xl[r]) * st.dzdx[t]) >> X_FRAC)
        zkey = np.clip(zrun >> DZ_FRAC, 0, (1 << Z_BITS) - 1).astype(np.float64)
    else:
        zkey = rec.zl[r] + (col + 0.5 - rec.xl[r]) * st.dzdx[t]
    pix = rec.row[r] * W + col
    return {"F": F, "rec": r, "col": col, "pix": pix, "z": zkey}


def depth_search(st: Setup, fr: dict, npix: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest segment per pixel (ties: lower PL index).

    Returns (winning record or -1, cover count k, the winner's z key or +inf)."""
    win = np.full(npix, -1, dtype=np.int64)
    zwin = np.full(npix, np.inf)
    k = np.bincount(fr["pix"], minlength=npix) if fr["F"] else np.zeros(npix, np.int64)
    if fr["F"]:
        o = np.lexsort((fr["rec"], fr["z"], fr["pix"]))  # records are in PL order
        p = fr["pix"][o]
        firsts = np.ones(p.size, bool)
        firsts[1:] = p[1:] != p[:-1]
        win[p[firsts]] = fr["rec"][o[firsts]]
        zwin[p[firsts]] = fr["z"][o[firsts]]
    return win, k, zwin


def shadow_count(st: Setup, rec: Records, win: np.ndarray, zwin: np.ndarray, shadows, W: int) -> dict:
    """Crow's count: signed shadow faces in front of each visible point (see :mod:`shadow`).

    The shadow faces are extra, invisible segments: each steps its z and compares it with the
    visible point's (2 ops per pixel it spans, 3 to start it), adding its sign when nearer.
    """
    from rasterhw.golden_model.experts import slp as _slp
    npix = win.size
    sst = _slp.set_up(shadows.tris, bit=st.bit, fmt=st.fmt)
    srec = _slp.asl_update(sst, W)
    sfr = fragments(sst, srec, W)
    cost = np.zeros(npix, np.int64)
    if not sfr["F"]:
        return {"shadowed": np.zeros(npix, bool), "cost": cost, "segments": 0, "fragments": 0}
    t = sst.keep[srec.tri[sfr["rec"]]]
    sign, owner = shadows.sign[t], shadows.owner[t]
    pix = sfr["pix"]
    vis = win[pix] >= 0
    vpoly = np.where(vis, st.poly[rec.tri[np.maximum(win[pix], 0)]], -1)
    m = vis & (sfr["z"] < zwin[pix]) & (owner != vpoly)
    cnt = np.bincount(pix[m], weights=sign[m], minlength=npix)
    np.add.at(cost, pix, 2)
    ok = srec.c1 >= srec.c0
    np.add.at(cost, srec.row[ok] * W + srec.c0[ok], 3)
    return {"shadowed": cnt > 0.5, "cost": cost, "segments": int(ok.sum()), "fragments": int(sfr["F"]),
            "triangles": int(sst.n)}


def smooth_shading(st: Setup, rec: Records, win: np.ndarray, W: int) -> np.ndarray:
    """Intensity of every visible pixel: float in [0, 1] or the integer level (eq. (4))."""
    out = np.zeros(win.size, dtype=np.float64 if not st.bit else np.int64)
    vis = np.flatnonzero(win >= 0)
    r = win[vis]
    col = vis % W
    t = rec.tri[r]
    fmt = st.fmt
    if st.bit:
        xc = (col << X_FRAC) + (1 << (X_FRAC - 1))
        irun = rec.il[r] + (((xc - rec.xl[r]) * st.didx[t]) >> X_FRAC)
        irun = np.clip(irun, 0, fmt.i_max << fmt.i_frac)
        out[vis] = irun >> fmt.i_frac
    else:
        out[vis] = np.clip(rec.il[r] + (col + 0.5 - rec.xl[r]) * st.didx[t], 0.0, 1.0)
    return out


def pixel_fields(st: Setup, rec: Records, win: np.ndarray, inten: np.ndarray) -> np.ndarray:
    """(npix, 4) pixel fields before A.J.: R, G, B hue and I (float, or 3/3/3/I-bit integers)."""
    f = np.zeros((win.size, 4), dtype=np.float64 if not st.bit else np.int64)
    vis = win >= 0
    f[vis, :3] = st.hue[rec.tri[win[vis]]]
    f[:, 3] = inten
    return f


def anti_jagging(st: Setup, rec: Records, win: np.ndarray, fields: np.ndarray, W: int, H: int,
                 method: str) -> tuple[np.ndarray, dict]:
    """Eq. (5) at the polygon edges of every line. Returns (blended fields, counts)."""
    out = fields.copy()
    w2 = win.reshape(H, W)
    a, b = w2[:, :-1], w2[:, 1:]
    pa = np.where(a >= 0, st.poly[rec.tri[np.maximum(a, 0)]], -1)
    pb = np.where(b >= 0, st.poly[rec.tri[np.maximum(b, 0)]], -1)
    yy, xx = np.nonzero(a != b)
    xx = xx + 1                                   # boundary between pixel x-1 and x
    ra, rb = w2[yy, xx - 1], w2[yy, xx]
    edge_poly = pa[yy, xx - 1] != pb[yy, xx - 1]
    starts = (rb >= 0) & (rec.c0[np.maximum(rb, 0)] == xx)
    ends = (ra >= 0) & (rec.c1[np.maximum(ra, 0)] == xx - 1)
    use_b = edge_poly & starts
    use_a = edge_poly & ~starts & ends
    sel = use_a | use_b
    rr = np.where(use_b, rb, ra)[sel]
    yy, xx, use_b = yy[sel], xx[sel], use_b[sel]
    xe = np.where(use_b, rec.xl[rr], rec.xr[rr])
    s = np.where(use_b, rec.sl[rr], rec.sr[rr])
    q_ = np.where(use_b, rec.ql[rr], rec.qr[rr])
    if st.bit:
        q = np.clip(xe >> X_FRAC, xx - 1, xx)
        delta = xe - ((q << X_FRAC) + (1 << (X_FRAC - 1)))          # Q.6
        one = 1 << ALPHA_BITS
        if method == "c":
            steep = np.abs(s) <= (1 << SLOPE_FRAC)
            al = np.where(steep, (one >> 1) + (delta << (ALPHA_BITS - X_FRAC)),
                          (one >> 1) + ((delta * np.abs(q_)) >> (X_FRAC + SLOPE_FRAC - ALPHA_BITS)))
            shallow = int(np.count_nonzero(~steep))
        else:
            al = np.rint(ALPHA[method](delta / (1 << X_FRAC), s / (1 << SLOPE_FRAC)) * one).astype(np.int64)
            shallow = 0
        al = np.clip(al, 0, one)
        pl = (yy * W + xx - 1)
        pr = (yy * W + xx)
        fl, frr = fields[pl], fields[pr]
        val = (al[:, None] * fl + (one - al[:, None]) * frr + (one >> 1)) >> ALPHA_BITS
    else:
        q = np.clip(np.floor(xe).astype(np.int64), xx - 1, xx)
        delta = xe - (q + 0.5)
        al = ALPHA[method](delta, s)
        shallow = int(np.count_nonzero(np.abs(s) > 1)) if method == "c" else 0
        fl, frr = fields[yy * W + xx - 1], fields[yy * W + xx]
        val = al[:, None] * fl + (1 - al[:, None]) * frr
    qp = yy * W + q
    # the same work, counted: the routine each blended pixel executes (aj_ops)
    from rasterhw.golden_model.experts.aj_ops import aj_pixel_ops
    perp = None if method != "b" else 1.0 / np.sqrt(1.0 + (s / (1 << SLOPE_FRAC) if st.bit else s) ** 2)
    al_counted, _, ops = aj_pixel_ops(method, st.bit, xe, xx, s, q_, perp, fl, frr, x_frac=X_FRAC,
                                      slope_frac=SLOPE_FRAC, alpha_bits=ALPHA_BITS)
    # two boundaries may blend the same pixel (a one-pixel run): the later (right) one wins, as a
    # PXP that walks the line left to right would have it
    _, last = np.unique(qp[::-1], return_index=True)
    keep = qp.size - 1 - last
    out[qp[keep]] = val[keep]
    return out, {"pixels": int(qp.size), "shallow": shallow, "boundaries": int(np.count_nonzero(a != b)),
                 "qpix": qp, "shallow_mask": (np.abs(s) > (1 << SLOPE_FRAC if st.bit else 1)),
                 "ops": ops, "alpha": al, "alpha_counted": al_counted, "blend": val}


def to_rgb8(st: Setup, fields: np.ndarray, H: int, W: int) -> np.ndarray:
    """Display colour: hue x intensity (the VOC's D/A), as 8-bit RGB."""
    if st.bit:
        rgb = fields[:, :3] / 7.0 * (fields[:, 3:4] / st.fmt.i_max)
    else:
        rgb = fields[:, :3] * fields[:, 3:4]
    return np.clip(np.floor(rgb * 255.0 + 0.5), 0, 255).astype(np.uint8).reshape(H, W, 3)


def pixel_words(st: Setup, fields: np.ndarray) -> np.ndarray:
    """Bit model: the 16-bit (or 9 + I bit) pixel word R3 G3 B3 I."""
    ib = st.fmt.intensity_bits
    f = fields.astype(np.int64)
    return (f[:, 0] << (6 + ib)) | (f[:, 1] << (3 + ib)) | (f[:, 2] << ib) | f[:, 3]


def pixel_costs(st: Setup, rec: Records, win: np.ndarray, k: np.ndarray, W: int, H: int,
                aj: str, aj_info: dict | None, shadow_cost: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Per-pixel PXP operation counts by stage, (H, W) arrays, plus the range-start extras.

    A range [a, b) of line y costs the sum of its pixels' entries, plus ``cross[y, a]`` times the
    per-segment costs (a segment that started left of ``a`` is clipped, gets a start value and
    enters the span set again) and ``midrun[y, a]`` times the extra of starting a shading run.
    """
    npix = W * H
    seg_at = np.zeros(npix, np.int64)
    ok = rec.c1 >= rec.c0
    np.add.at(seg_at, rec.row[ok] * W + rec.c0[ok], 1)
    c = {}
    c["range_clip"] = PXP_OPS["range_clip_per_segment"] * seg_at
    c["start_values"] = PXP_OPS["start_per_segment"] * seg_at
    c["span_cull"] = PXP_OPS["span_cull_per_segment"] * seg_at
    c["depth_search"] = np.where(k > 0, 2 * k - 1, 0)
    w2 = win.reshape(H, W)
    runstart = np.zeros((H, W), bool)
    runstart[:, 0] = w2[:, 0] >= 0
    runstart[:, 1:] = (w2[:, 1:] >= 0) & (w2[:, 1:] != w2[:, :-1])
    vis = (w2 >= 0)
    c["smooth_shading"] = (np.where(runstart, PXP_OPS["shade_run_start"], 0)
                           + np.where(vis & ~runstart, PXP_OPS["shade_per_pixel"], 0)).ravel()
    c["dslb"] = np.full(npix, PXP_OPS["dslb_per_pixel"], np.int64)
    if aj != "none" and aj_info is not None:
        a = np.zeros(npix, np.int64)
        np.add.at(a, aj_info["qpix"], aj_info["ops"])        # executed per blended pixel (aj_ops)
        bnd = np.zeros((H, W), np.int64)
        bnd[:, 1:] = (w2[:, 1:] != w2[:, :-1])
        c["anti_jagging"] = a + PXP_OPS["aj_edge_test"] * bnd.ravel()
    if shadow_cost is not None:
        c["shadows"] = shadow_cost
    # segments covering x that started left of x: cover count minus starts at x
    cross = k - seg_at
    midrun = (vis & ~runstart).ravel().astype(np.int64)
    out = {name: v.reshape(H, W) for name, v in c.items()}
    out["_cross"] = cross.reshape(H, W)
    out["_midrun"] = midrun.reshape(H, W)
    return out


CROSS_OPS = {"range_clip": PXP_OPS["range_clip_per_segment"], "start_values": PXP_OPS["start_per_segment"],
             "span_cull": PXP_OPS["span_cull_per_segment"]}
MIDRUN_OPS = {"smooth_shading": PXP_OPS["shade_run_start"] - PXP_OPS["shade_per_pixel"]}
