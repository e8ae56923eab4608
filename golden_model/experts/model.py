"""The EXPERTS scan-line machine as one golden model: SLP stages then PXP stages, float or bit-accurate.

``render_frame(tris, model="float"|"bit", aj="none"|"a"|"b"|"c")`` runs every stage over the whole
frame (vectorised over segments and pixels) and keeps what the parallel and cost models need:
per-line SLP counts and per-pixel PXP counts, from which the operations of any band / range
partition follow exactly (:func:`slp_band_ops`, :func:`pxp_range_ops`). The image never depends
on the partition (see the start-value notes in :mod:`slp` and :mod:`pxp`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts import pxp, slp
from rasterhw.golden_model.experts.formats import Formats
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = ["ExpertsFrame", "render_frame", "equal_bounds", "slp_band_ops", "pxp_range_ops",
           "SLP_STAGES", "PXP_STAGES", "AJ_METHODS", "MODELS"]

SLP_STAGES = ("pl_read", "y_sort", "asl_build", "aj_setup", "asl_update", "l_sort", "x_merge",
              "block_lists", "dmm_p_write")
PXP_STAGES = ("range_clip", "start_values", "span_cull", "depth_search", "shadows", "smooth_shading",
              "anti_jagging", "dslb")
AJ_METHODS = ("none", "a", "b", "c")
MODELS = ("float", "bit")


@dataclass
class ExpertsFrame:
    """One frame through the machine."""

    width: int
    height: int
    model: str
    aj: str
    rgb8: np.ndarray            # (H, W, 3) display colour
    fields: np.ndarray          # (H*W, 4) R, G, B, I after A.J.
    tri_id: np.ndarray          # (H, W) visible triangle (index into the ScreenTriangles), -1 empty
    poly_id: np.ndarray         # (H, W)
    setup: slp.Setup
    records: slp.Records
    lines: dict                 # per-line SLP counts (slp.l_sort_x_merge)
    costs: dict                 # per-pixel PXP counts (pxp.pixel_costs)
    win: np.ndarray | None = None   # (H*W,) winning record per pixel, -1 empty
    shadowed: np.ndarray | None = None   # (H, W) in shadow (with shadows), else None
    aj_pixels: int = 0
    fragments: int = 0
    stats: dict = field(default_factory=dict)

    @property
    def covered(self) -> np.ndarray:
        return self.tri_id >= 0


def render_frame(tris: ScreenTriangles, *, model: str = "float", aj: str = "none",
                 fmt: Formats | None = None, shadows=None) -> ExpertsFrame:
    """Run the SLP and PXP stages over a frame (see the module docstring).

    ``shadows``: :class:`shadow.ShadowFaces` of the scene (our Crow shadow polygons) or None.
    """
    if model not in MODELS:
        raise RasterhwError(f"experts: model must be one of {', '.join(MODELS)}, not {model!r}")
    if aj not in AJ_METHODS:
        raise RasterhwError(f"experts: aj must be one of {', '.join(AJ_METHODS)}, not {aj!r}")
    W, H = int(tris.width), int(tris.height)
    st = slp.set_up(tris, bit=model == "bit", fmt=fmt)
    rec = slp.asl_update(st, W)
    lines = slp.l_sort_x_merge(rec, H)
    fr = pxp.fragments(st, rec, W)
    win, k, zwin = pxp.depth_search(st, fr, W * H)
    inten = pxp.smooth_shading(st, rec, win, W)
    sh = None
    if shadows is not None:
        from rasterhw.golden_model.experts.shadow import SHADOW_ATTEN, SHADOW_ATTEN_Q8
        sh = pxp.shadow_count(st, rec, win, zwin, shadows, W)
        s_ = sh["shadowed"]
        inten[s_] = (inten[s_] * SHADOW_ATTEN_Q8) >> 8 if st.bit else inten[s_] * SHADOW_ATTEN
    fields = pxp.pixel_fields(st, rec, win, inten)
    info = None
    if aj != "none":
        fields, info = pxp.anti_jagging(st, rec, win, fields, W, H, aj)
    costs = pxp.pixel_costs(st, rec, win, k, W, H, aj, info, None if sh is None else sh["cost"])
    tri_id = np.where(win >= 0, st.keep[rec.tri[np.maximum(win, 0)]], -1).reshape(H, W)
    poly = np.where(win >= 0, st.poly[rec.tri[np.maximum(win, 0)]], -1).reshape(H, W)
    return ExpertsFrame(width=W, height=H, model=model, aj=aj, rgb8=pxp.to_rgb8(st, fields, H, W),
                        fields=fields, tri_id=tri_id, poly_id=poly, setup=st, records=rec, lines=lines,
                        costs=costs, win=win, shadowed=None if sh is None else sh["shadowed"].reshape(H, W), aj_pixels=info["pixels"] if info else 0, fragments=fr["F"],
                        stats={"sat_dzdx": st.sat_dzdx, "sat_didx": st.sat_didx,
                               "triangles": int(tris.n_triangles), "kept": st.n,
                               "crossings": crossings(rec, win, W, H),
                               "aj_routine_ops": int(info["ops"].sum()) if info else 0,
                               **({} if sh is None else {"shadowed_pixels": int(sh["shadowed"].sum()),
                                                         "shadow_segments": sh["segments"],
                                                         "shadow_triangles": sh.get("triangles", 0)})})


def crossings(rec: slp.Records, win: np.ndarray, W: int, H: int) -> int:
    """Visible-surface changes inside both segments (neither ends nor starts there): where
    interpenetrating faces cross on a scan line."""
    w2 = win.reshape(H, W)
    a, b = w2[:, :-1], w2[:, 1:]
    yy, xx = np.nonzero((a != b) & (a >= 0) & (b >= 0))
    ra, rb = a[yy, xx], b[yy, xx]
    inside = (rec.c1[ra] > xx) & (rec.c0[rb] < xx + 1)
    return int(np.count_nonzero(inside))


def equal_bounds(n: int, parts: int) -> np.ndarray:
    """Boundaries ``0 = b0 < ... < b_parts = n`` of equal contiguous parts (the static split)."""
    if isinstance(parts, bool) or not isinstance(parts, (int, np.integer)) or not 1 <= parts <= n:
        raise RasterhwError(f"experts: number of parts must be an integer in 1..{n}, not {parts!r}")
    return (np.arange(parts + 1) * n) // parts


def slp_band_ops(fr: ExpertsFrame, bands: np.ndarray, pn: int) -> list[dict[str, int]]:
    """SLP operations of each band ``[bands[s], bands[s+1])``, by stage."""
    out = []
    for s in range(len(bands) - 1):
        y0, y1 = int(bands[s]), int(bands[s + 1])
        if y1 <= y0:
            raise RasterhwError(f"experts: band {s} is empty ({y0}..{y1})")
        out.append(slp.slp_line_ops(fr.setup, fr.lines, (y0, y1), aj=fr.aj, pn=pn))
    return out


def slp_line_costs(fr: ExpertsFrame, pn: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-line SLP operations ``(continuing, band_start)``: a line in the middle of a band, and
    the same line as a band's first (ASL built for every active segment). Y-sort and set-up are
    charged to the line each triangle enters the band on. Sum over a band = :func:`slp_band_ops`
    less the PL read and band tests, which are per band."""
    st, ln, H = fr.setup, fr.lines, fr.height
    per_tri = (3 * slp.SLP_OPS["y_sort_per_edge"] + 3 * slp.SLP_OPS["edge_setup_per_edge"]
               + slp.SLP_OPS["plane_setup_per_triangle"] + 2 * slp.SLP_OPS["start_per_edge"])
    if fr.aj != "none":
        per_tri += 3 * slp.SLP_OPS["aj_slopes_per_edge"] + (3 * slp.SLP_OPS["aj_perp_per_edge"] if fr.aj == "b" else 0)
    from rasterhw.golden_model.experts.formats import ASB_WORDS
    enter_tris = np.bincount(st.r0, minlength=H)[:H]
    mid = np.bincount(st.rmid[(st.rmid > st.r0) & (st.rmid <= st.r1)], minlength=H)[:H]
    common = ln["m"] + pn + ASB_WORDS * ln["m"] + 2 * pn + slp.SLP_OPS["mid_reload"] * mid
    cont = (common + per_tri * enter_tris + slp.SLP_OPS["update_per_segment"] * ln["survive"]
            + ln["lsort"] + ln["xmerge"])
    # on a band's first line the short side's edge is chosen directly: no reload
    start = common - slp.SLP_OPS["mid_reload"] * mid + per_tri * ln["m"] + ln["xmerge_start"]
    return cont.astype(np.int64), start.astype(np.int64)


def _prefix(fr: ExpertsFrame, stages) -> np.ndarray:
    tot = np.zeros((fr.height, fr.width), np.int64)
    for s in stages:
        if s in fr.costs:
            tot += fr.costs[s]
    return np.concatenate([np.zeros((fr.height, 1), np.int64), np.cumsum(tot, axis=1)], axis=1)


def pxp_range_ops(fr: ExpertsFrame, bounds: np.ndarray, stages=PXP_STAGES) -> np.ndarray:
    """PXP operations of every (line, range): ``bounds`` is (Pn + 1,) or (H, Pn + 1) pixel boundaries.

    Returns (H, Pn). Exact: the per-pixel counts plus, at each range start, the extra work for
    segments that began left of it (clip, start value, span entry) and for a shading run cut by it.
    """
    H = fr.height
    b = np.broadcast_to(np.asarray(bounds, dtype=np.int64), (H, np.shape(bounds)[-1]))
    P = _prefix(fr, stages)
    rows = np.arange(H)[:, None]
    cost = P[rows, b[:, 1:]] - P[rows, b[:, :-1]]
    a = np.minimum(b[:, :-1], fr.width - 1)
    nonempty = b[:, 1:] > b[:, :-1]
    extra_c = sum(v for s, v in pxp.CROSS_OPS.items() if s in stages)
    extra_m = sum(v for s, v in pxp.MIDRUN_OPS.items() if s in stages)
    extra = extra_c * fr.costs["_cross"][rows, a] + extra_m * fr.costs["_midrun"][rows, a]
    return cost + np.where(nonempty & (b[:, :-1] > 0), extra, 0)


def stage_totals(fr: ExpertsFrame, *, sn: int = 1, pn: int = 1) -> dict[str, int]:
    """Whole-frame operations by stage for an equal static Sn x Pn partition."""
    bands = equal_bounds(fr.height, sn)
    tot: dict[str, int] = {}
    for d in slp_band_ops(fr, bands, pn):
        for k, v in d.items():
            tot[k] = tot.get(k, 0) + v
    rb = equal_bounds(fr.width, pn)
    for s in PXP_STAGES:
        if s in fr.costs:
            tot[s] = int(pxp_range_ops(fr, rb, (s,)).sum())
    return tot


def pxp_range_cycles(fr: ExpertsFrame, bounds: np.ndarray, *, aj: str | None = None) -> np.ndarray:
    """Resolve-side cycles of the PXP HDL for every (line, range), (H, Pn), from per-pixel counts.

    ``G + 1 + 2 (segments reaching [glo, ghi)) + 2 (fragments in [glo, ghi)) + 1`` -- the
    ``pxp_cycles.resolve_cycles`` of each range's clipped ASL plus its hand-over cycle, without
    expanding the lists (``G``: the range, with A.J. its guard pixels too). The finish-time
    counter the SLP reads when the drain keeps up.
    """
    aj = fr.aj if aj is None else aj
    H, W = fr.height, fr.width
    b = np.broadcast_to(np.asarray(bounds, dtype=np.int64), (H, np.shape(bounds)[-1]))
    lo, hi = b[:, :-1], b[:, 1:]
    if aj == "c":
        glo, ghi = np.maximum(lo - 1, 0), np.minimum(hi + 1, W)
    else:
        glo, ghi = lo, hi
    rows = np.arange(H)[:, None]
    pc, ps = _cycle_prefix(fr)
    frag = pc[rows, ghi] - pc[rows, glo]
    segs = ps[rows, ghi] - ps[rows, glo] + np.where(glo > 0, fr.costs["_cross"][rows, np.minimum(glo, W - 1)], 0)
    return (ghi - glo) + 1 + 2 * segs + 2 * frag + 1


def _cycle_prefix(fr: ExpertsFrame) -> tuple[np.ndarray, np.ndarray]:
    """Prefix sums along each line of the cover count and of the segment starts."""
    H = fr.height
    ds = fr.costs["depth_search"]
    cover = np.where(ds > 0, (ds + 1) // 2, 0)      # depth search counts 2k - 1 per pixel
    starts = fr.costs["start_values"] // 3           # 3 per segment starting at the pixel
    z = np.zeros((H, 1), np.int64)
    return np.concatenate([z, np.cumsum(cover, axis=1)], axis=1), np.concatenate([z, np.cumsum(starts, axis=1)], axis=1)
