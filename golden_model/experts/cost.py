"""EXPERTS cost model (seed 000, section 4): the paper's formulas and the same quantities measured.

Formulas (Dc = 3, x = y = 512; the per-stage terms are damaged in the print, the totals are
consistent: 893 + 31607 = 32500)::

    Q_seq = 4 Fr + 3.46 Fr sqrt(Fr) + 32500 sqrt(Fr)
    Q_s   = (4 Fr + 3.46 Fr sqrt(Fr) + 893 sqrt(Fr)) / Sn      SLP: Y-sort, X-merge, L-sort
    Q_p   = 31607 sqrt(Fr) / (Sn Pn)                           PXP: span cull, depth search
    Q_par = max(Q_s, Q_p)

Measured: the same stage sets counted by the instrumented golden model
(:data:`paper.PAPER_SLP`, :data:`paper.PAPER_PXP`), Q_par as the busiest SLP or PXP of an equal
static Sn x Pn partition (the paper's division by Sn and Sn Pn assumes a perfect split).
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.experts.alpha import ALPHA, alpha_area
from rasterhw.golden_model.experts.model import (
    ExpertsFrame,
    equal_bounds,
    pxp_range_ops,
    slp_band_ops,
)
from rasterhw.golden_model.experts.paper import PAPER_COST, PAPER_PXP, PAPER_SLP
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = ["q_seq", "q_s", "q_p", "q_par", "balance_pn", "measured_q", "measured_q_run", "realtime", "alpha_error",
           "line_segments",
           "total_ops"]


_C = PAPER_COST


def q_seq(fr: float) -> float:
    r = math.sqrt(fr)
    return _C["fr"] * fr + _C["fr_sqrt_fr"] * fr * r + _C["seq_sqrt_fr"] * r


def q_s(fr: float, sn: int) -> float:
    r = math.sqrt(fr)
    return (_C["fr"] * fr + _C["fr_sqrt_fr"] * fr * r + _C["slp_sqrt_fr"] * r) / sn


def q_p(fr: float, sn: int, pn: int) -> float:
    return _C["pxp_sqrt_fr"] * math.sqrt(fr) / (sn * pn)


def q_par(fr: float, sn: int, pn: int) -> float:
    return max(q_s(fr, sn), q_p(fr, sn, pn))


def balance_pn(fr: float) -> float:
    """Pn where Q_s = Q_p (independent of Sn)."""
    r = math.sqrt(fr)
    return _C["pxp_sqrt_fr"] * r / (_C["fr"] * fr + _C["fr_sqrt_fr"] * fr * r + _C["slp_sqrt_fr"] * r)


def measured_q(f: ExpertsFrame, sn: int, pn: int) -> dict:
    """Q_seq, Q_s, Q_p, Q_par from counted operations (paper's stage sets), equal static split."""
    bands = equal_bounds(f.height, sn)
    sl = slp_band_ops(f, bands, pn)
    qs = max(sum(d.get(s, 0) for s in PAPER_SLP) for d in sl)
    rb = equal_bounds(f.width, pn)
    pt = pxp_range_ops(f, rb, PAPER_PXP)       # (H, Pn)
    qp = max(float(pt[bands[s]:bands[s + 1]].sum(axis=0).max()) for s in range(sn))
    one = slp_band_ops(f, equal_bounds(f.height, 1), 1)[0]
    seq = sum(one.get(s, 0) for s in PAPER_SLP) + float(pxp_range_ops(f, equal_bounds(f.width, 1), PAPER_PXP).sum())
    return {"q_seq": seq, "q_s": float(qs), "q_p": qp, "q_par": max(float(qs), qp)}


def measured_q_run(f: ExpertsFrame, sn: int, pn: int, cache: dict | None = None) -> dict:
    """Q_seq, Q_s, Q_p, Q_par as :func:`measured_q`, from the machine as the paper built it:
    Q_s from the SLP's sorts as they run (:mod:`slp_run`: Y-sort, X-merge, L-sort, executed
    compares, moves and exchanges), Q_p from the span PXP (:mod:`span`: span cull + depth search
    as executed). ``cache`` (a dict) keeps the runs of one frame between calls."""
    from rasterhw.golden_model.experts import slp_run, span
    cache = {} if cache is None else cache

    def slp_ops(n):
        if ("slp", n) not in cache:
            cache[("slp", n)] = [sum(r.ops[s] for s in PAPER_SLP)
                                 for r in slp_run.run_bands(f, equal_bounds(f.height, n))]
        return cache[("slp", n)]

    def pxp_ops(n):
        if ("pxp", n) not in cache:
            sp = span.span_pxp(f.setup, f.records, f.width, f.height, equal_bounds(f.width, n))
            cache[("pxp", n)] = sum(sp.ops[s] for s in PAPER_PXP)
        return cache[("pxp", n)]

    bands = equal_bounds(f.height, sn)
    qs = float(max(slp_ops(sn)))
    pt = pxp_ops(pn)
    qp = max(float(pt[bands[s]:bands[s + 1]].sum(axis=0).max()) for s in range(sn))
    seq = float(sum(slp_ops(1)) + pxp_ops(1).sum())
    return {"q_seq": seq, "q_s": qs, "q_p": qp, "q_par": max(qs, qp)}


def realtime(f: ExpertsFrame, sn: int, pn: int, fps: float = 30.0) -> dict:
    """The clock each of SLP and PXP needs for ``fps`` frames/s, equal static Sn x Pn split.

    SLP: the busiest band's operations, one per cycle -- the sorts and block lists as they run
    (:mod:`slp_run`) plus the other SLP stages as counted in :func:`slp.slp_line_ops` (PL read,
    set-up, ASL update, DMM/P write). PXP: the busiest PXP's cycles over its band's lines by the
    span PXP's operation-count model (:func:`span.span_cycles`; not the HDL's cycles, which
    ``span_cycles.py`` counts). The two overlap through DMM/P, so the
    frame needs each processor at its own clock."""
    from rasterhw.golden_model.experts import slp_run, span
    bands = equal_bounds(f.height, sn)
    ranges = equal_bounds(f.width, pn)
    runs = slp_run.run_bands(f, bands, ranges, guard=1 if f.aj == "c" else 0)   # A.J. (c): guard pixels
    counted = slp_band_ops(f, bands, pn)
    slp_ops = [sum(r.ops.values()) + sum(v for k, v in c.items() if k not in r.ops) for r, c in zip(runs, counted, strict=True)]
    sp = span.span_pxp(f.setup, f.records, f.width, f.height, ranges)
    cyc = span.span_cycles(f, sp)
    pxp = [cyc[bands[s]:bands[s + 1]].sum(axis=0) for s in range(sn)]
    busy_s, busy_p = int(max(slp_ops)), int(max(int(p.max()) for p in pxp))
    return {"slp_ops": busy_s, "pxp_cycles": busy_p, "slp_clock_for_30fps_hz": busy_s * fps,
            "pxp_clock_for_30fps_hz": busy_p * fps, "slp_detail": runs, "span": sp}


def total_ops(f: ExpertsFrame) -> int:
    """Every SLP and PXP operation of the frame on one SLP and one PXP (A.J. overhead base)."""
    from rasterhw.golden_model.experts.model import stage_totals
    return int(sum(stage_totals(f, sn=1, pn=1).values()))


def alpha_error(n_angles: int = 91, n_offsets: int = 201) -> dict[str, np.ndarray]:
    """Error of alpha (b) and (c) against the exact area (a), per edge angle from the scan line.

    For each angle (0 = horizontal edge, 90 = vertical), the edge crosses the pixel's centre row at
    offsets ``delta`` uniform in [-1, 1] px from the centre (every offset that cuts the pixel).
    Returns angles and the mean and max |error| per method (our curves; fig. 2.7 is illegible).
    """
    ang = np.linspace(0.0, 90.0, n_angles)
    delta = np.linspace(-1.0, 1.0, n_offsets)
    out = {"angle": ang}
    with np.errstate(divide="ignore", over="ignore"):
        s = 1.0 / np.tan(np.radians(np.maximum(ang, 1e-6)))      # dx/dy
    for m in ("b", "c"):
        e = np.abs(ALPHA[m](delta[None, :], s[:, None]) - alpha_area(delta[None, :], s[:, None]))
        out[f"{m}_mean"] = e.mean(axis=1)
        out[f"{m}_max"] = e.max(axis=1)
    return out


def line_segments(n: int = 8, *, width: int = 512, height: int = 512, seed: int = 22, thick: float = 2.0,
                  length: float = 300.0) -> ScreenTriangles:
    """``n`` line segments drawn as thin quads (two triangles each), random angles (table 2.2)."""
    rng = np.random.default_rng(seed)
    ang = rng.uniform(0, np.pi, n)
    cx = rng.uniform(0.3 * width, 0.7 * width, n)
    cy = rng.uniform(0.3 * height, 0.7 * height, n)
    d = np.stack([np.cos(ang), np.sin(ang)], axis=1) * length / 2
    nrm = np.stack([-np.sin(ang), np.cos(ang)], axis=1) * thick / 2
    c = np.stack([cx, cy], axis=1)
    p = [c - d - nrm, c + d - nrm, c + d + nrm, c - d + nrm]
    xy = np.concatenate([np.stack([p[0], p[1], p[2]], axis=1), np.stack([p[0], p[2], p[3]], axis=1)])
    t = 2 * n
    z = np.repeat(rng.uniform(0.2, 0.8, n), 2)[:, None] * np.ones((t, 3))
    col = np.repeat(0.3 + 0.7 * rng.random((n, 1, 3)), 2, axis=0) * np.ones((t, 3, 3))
    pid = np.concatenate([np.arange(n), np.arange(n)])
    order = np.argsort(pid, kind="stable")
    return ScreenTriangles(width=width, height=height, xy=xy[order], z=z[order],
                           zq=np.rint(z[order] * 65535).astype(np.int64), colour=col[order], poly_id=pid[order])


def tolerance(tris: ScreenTriangles) -> dict:
    """Bit model against float model on one frame: how many pixels differ, and why.

    A pixel whose visible triangle differs is put down to **x** (16-bit vertex and edge x:
    Q10.6 vertices, edge stepping) when the two models do not agree on which triangles cover it,
    and to **z** (16-bit depth: Q16.0 zL, sQ11.4 dz/dx, the 16-bit comparator and its tie rule)
    when they agree on the cover but pick a different nearest one.
    """
    from rasterhw.golden_model.experts import pxp
    from rasterhw.golden_model.experts.model import render_frame
    fl, bt = render_frame(tris, model="float"), render_frame(tris, model="bit")
    npix = fl.width * fl.height
    T = int(tris.n_triangles) + 1

    def pairs(f):
        fr = pxp.fragments(f.setup, f.records, f.width)
        return fr["pix"] * T + f.setup.keep[f.records.tri[fr["rec"]]]

    pf, pb = pairs(fl), pairs(bt)
    both = fl.covered & bt.covered
    diff = np.flatnonzero((both & (fl.tri_id != bt.tri_id)).ravel())
    tf, tb = fl.tri_id.ravel()[diff], bt.tri_id.ravel()[diff]
    same_cover = np.isin(diff * T + tf, pb) & np.isin(diff * T + tb, pf)
    zt = int(np.count_nonzero(same_cover))
    # z ties: the bit model's 16-bit keys of the two candidates are equal
    return {"pixels": npix, "covered": int(fl.covered.sum()),
            "cover_diff": int(np.count_nonzero(fl.covered != bt.covered)),
            "visible_diff": int(diff.size), "visible_diff_x": int(diff.size - zt), "visible_diff_z": zt,
            "sat_dzdx": bt.stats["sat_dzdx"], "sat_didx": bt.stats["sat_didx"]}
