"""The Scan Line Processor (SLP) stages: Y-sort, band clip, ASL build and update, L-sort, X-merge.

Seed 000, 3.1-3.2 and 4: the SLP takes the Polygon List (PL) the host broadcasts, keeps the
triangles that reach its band of scan lines ("一種のクリッピング処理をSLPが分担"), builds the
Active Segment List (ASL) for its first line and updates it line by line with constant
increments (scan-line coherence). Its three sorting stages are the paper's:

* **Y-sort** -- "表示面に含まれるすべての稜線を、y_min ... をキーとしてバケットソートする";
* **X-merge** -- "1スキャン・ライン内に現われるセグメントを、その左稜線の xs 座標値をキーとして、
  マージソートする" (the segments that enter on a line are merge-sorted and merged in);
* **L-sort** -- "スキャン・ラインの更新に伴い進入、退出するセグメントと ... リストとをバブルソートする"
  (after the increments the surviving list may be out of order where segments cross).

How z and i step down an edge (decision; the ASB of fig. 3.2 has no dz/dy or di/dy): the SLP keeps
the edge increments dz/dy and di/dy of every edge in its own edge records (eq. (1'):
``i_AB(k) = i_a + (k - y_a) di_AB/dy``, the same for z) and steps x, z and i of the *left* edge
and x of the right edge itself; the ASB it sends carries the results (xL, zL, iL), (xR, ...) for
the line. The PXP never steps down an edge: it only needs dz/dx and di/dx along the line.

Everything here is vectorised over (triangle, scan line) *records*: record r is triangle
``tri[r]`` on line ``row[r]``. The values of a record do not depend on where a band starts: the
multiplier start value at a band's first line equals the stepped value bit for bit (the
multiplier product ``(Yc - Y0) * inc >> 6`` moves by exactly ``inc`` per line, ``Yc`` moving by
64), so one frame-wide computation serves every partition; the *counts* do depend on the bands
and are counted per line and per band.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import (
    ACC_EXTRA,
    MAX_SIDE,
    SLOPE_FRAC,
    X_FRAC,
    Z_BITS,
    Formats,
    rom_div,
    sat,
)
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap

__all__ = ["Setup", "Records", "set_up", "y_sort", "asl_update", "l_sort_x_merge", "slp_line_ops",
           "SLP_OPS"]

#: Operations the SLP performs, per item (16-bit operations; a 32-bit add counts 2).
SLP_OPS = {
    "pl_read_per_triangle": 13,      # 3 x (x, y, z, i) + R/G/B word: every SLP reads the whole PL
    "band_test_per_triangle": 2,     # y_min <= band end, y_max >= band start
    "y_sort_per_edge": 3,            # which end is top, bucket index, link into the bucket
    "edge_setup_per_edge": 6,        # dX, dY, ROM 1/dY, dx/dy, dz/dy, di/dy
    "plane_setup_per_triangle": 19,  # eq. (3) for z and i: 6 sub, den 2 mul + 1 sub, ROM, 2 x (2 mul + 1 sub), 2 mul
    "start_per_edge": 10,            # Yc - Y0, then x, z, i: mul + 32-bit add (3 each)
    "mid_reload": 10,                # the short side switches edge at the middle vertex
    "update_per_segment": 8,         # xL, zL, iL, xR: four 32-bit adds
    "leave_per_segment": 1,          # unlink
    "aj_slopes_per_edge": 2,         # ROM 1/dX and dy/dx (only with A.J.)
    "aj_perp_per_edge": 4,           # method (b): s*s, +1, sqrt ROM, 1/. (only with --aj b)
}


@dataclass
class Setup:
    """Per-triangle set-up for the kept (non-degenerate, on-screen) triangles."""

    bit: bool
    fmt: Formats
    grid: int              # coordinate units per pixel: 256 (float model) or 64 (bit model)
    keep: np.ndarray       # index into the ScreenTriangles of each kept triangle
    X: np.ndarray          # (3, K) vertex x sorted top (a), middle (b), bottom (c), grid units
    Y: np.ndarray          # (3, K)
    Z: np.ndarray          # (3, K) float z or Q16.0
    Iv: np.ndarray          # (3, K) float intensity in [0, 1] or the i word
    long_left: np.ndarray  # (K,) the long edge a->c is the left edge
    r0: np.ndarray         # first and last scan line, clipped to the frame
    r1: np.ndarray
    rmid: np.ndarray       # first line on the b->c short edge
    dzdx: np.ndarray       # eq. (3) for z: float or sQ11.4
    didx: np.ndarray       # eq. (3) for i: float or the di/dx word
    hue: np.ndarray        # (K, 3) float hue in [0, 1] (max channel 1) or 3-bit R, G, B
    poly: np.ndarray       # (K,) poly_id
    sat_dzdx: int = 0
    sat_didx: int = 0
    order: np.ndarray | None = None  # (K, 3): sorted vertex r (top, middle, bottom) is PL vertex order[k, r]


    @property
    def n(self) -> int:
        return int(self.keep.size)


def _hue_intensity(col: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lit vertex colours (T, 3, 3) -> hue (T, 3) with max channel 1 and intensity (T, 3).

    Decision (the paper separates "色相" and "輝度" "S.S.のための計算量を軽減するため"): a vertex's
    intensity is its brightest channel; the triangle's hue is the intensity-weighted mean of its
    vertex colours, normalised. Exact for white lights and one colour per face (our scenes).
    """
    inten = col.max(axis=2)
    tot = inten.sum(axis=1)
    hue = col.sum(axis=1) / np.where(tot > 0, tot, 1.0)[:, None]
    m = hue.max(axis=1)
    hue = np.where(m[:, None] > 0, hue / np.where(m > 0, m, 1.0)[:, None], 1.0)
    return hue, inten


def set_up(tris: ScreenTriangles, *, bit: bool, fmt: Formats | None = None) -> Setup:
    """Triangle set-up as the SLP does it for its band (edge increments and eq. (3)).

    Float model: vertices on the shared 1/256 px grid (:func:`rasterhw.golden_model.screen.snap`),
    z and i in float64. Bit model: vertices in Q10.6 (round half up), z in Q16.0, i in the
    i word, increments through the reciprocal ROM (:func:`formats.rom_div`).
    """
    fmt = fmt or Formats()
    xy, z, col = tris.validate(max_coord=1023.0)
    W, H = int(tris.width), int(tris.height)
    if W > MAX_SIDE or H > MAX_SIDE:
        raise RasterhwError(f"experts: frame {W}x{H} does not fit the Q10.6 coordinates (at most {MAX_SIDE} px a side)")
    hue, inten = _hue_intensity(col)
    if bit:
        g = 1 << X_FRAC
        X = np.floor(xy[:, :, 0] * g + 0.5).astype(np.int64)
        Y = np.floor(xy[:, :, 1] * g + 0.5).astype(np.int64)
        Z = np.minimum(np.rint(z * (1 << Z_BITS)), (1 << Z_BITS) - 1).astype(np.int64)
        Iv = np.rint(inten * fmt.i_max * (1 << fmt.i_frac)).astype(np.int64)
    else:
        g = 1 << SUBPIXEL_BITS
        X, Y = snap(xy[:, :, 0]).astype(np.int64), snap(xy[:, :, 1]).astype(np.int64)
        Z, Iv = z.astype(np.float64), inten.astype(np.float64)
    # vertices top (a), middle (b), bottom (c): stable sort on y
    order = np.argsort(Y, axis=1, kind="stable")
    take = lambda a: np.take_along_axis(a, order, axis=1).T  # noqa: E731  (3, T)
    X, Y, Z, Iv = take(X), take(Y), take(Z), take(Iv)
    cross = (X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0])
    half = g // 2
    r0 = -((half - Y[0]) // g)                 # first row with centre >= y_top
    r1 = -((half - Y[2]) // g) - 1             # last row with centre < y_bottom
    rmid = -((half - Y[1]) // g)
    r0c, r1c = np.maximum(r0, 0), np.minimum(r1, H - 1)
    keep = np.flatnonzero((cross != 0) & (r1c >= r0c))
    X, Y, Z, Iv = X[:, keep], Y[:, keep], Z[:, keep], Iv[:, keep]
    cr = cross[keep]
    # eq. (3) with a, b, c = top, middle, bottom. As printed, the second terms carry (y_a - y_c);
    # that is wrong (i = y would get a non-zero di/dx): the plane's gradient needs (y_a - y_b).
    den = (Y[1] - Y[2]) * (X[0] - X[1]) - (Y[0] - Y[1]) * (X[1] - X[2])
    nz = (Y[1] - Y[2]) * (Z[0] - Z[1]) - (Y[0] - Y[1]) * (Z[1] - Z[2])
    ni = (Y[1] - Y[2]) * (Iv[0] - Iv[1]) - (Y[0] - Y[1]) * (Iv[1] - Iv[2])
    sdz = sdi = 0
    if bit:
        # den is Q.12, nz Q.6 x z: dz/dx = 64 nz / den z per px; in Q.4: shift 10
        dzr = rom_div(nz, den, 6 + 4)
        dir_ = rom_div(ni, den, 6)
        dzdx, didx = sat(dzr, 16), sat(dir_, 16)
        sdz, sdi = int(np.count_nonzero(dzdx != dzr)), int(np.count_nonzero(didx != dir_))
        hq = np.rint(hue[keep] * 7).astype(np.int64)
    else:
        dzdx = nz / den * g
        didx = ni / den * g
        hq = hue[keep]
    return Setup(bit=bit, fmt=fmt, grid=g, keep=keep, X=X, Y=Y, Z=Z, Iv=Iv, long_left=cr > 0,
                 r0=r0c[keep], r1=r1c[keep], rmid=rmid[keep], dzdx=dzdx, didx=didx, hue=hq,
                 poly=np.asarray(tris.poly_id, dtype=np.int64)[keep], sat_dzdx=sdz, sat_didx=sdi,
                 order=order[keep])


def y_sort(st: Setup, band: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, dict]:
    """Y-sort: bucket sort of the band's triangles by their first line in the band.

    Returns ``(tri_order, bucket_start, ops)``: kept-triangle indices in bucket order (stable,
    so PL order within a bucket) and, per line of the band, the index of its bucket's first
    entry (length ``lines + 1``). Ops: band test for every PL triangle (the broadcast
    overhead), 3 per edge for the triangles in the band.
    """
    y0, y1 = band
    inb = np.flatnonzero((st.r1 >= y0) & (st.r0 < y1))
    first = np.maximum(st.r0[inb], y0) - y0
    counts = np.bincount(first, minlength=y1 - y0)
    order = inb[np.argsort(first, kind="stable")]
    start = np.concatenate([[0], np.cumsum(counts)])
    ops = {"pl_read": SLP_OPS["pl_read_per_triangle"] * st.n,
           "y_sort": SLP_OPS["band_test_per_triangle"] * st.n + 3 * SLP_OPS["y_sort_per_edge"] * inb.size}
    return order, start, ops


@dataclass
class Records:
    """One record per (triangle, scan line): what the ASL holds for the line (ASB fields)."""

    tri: np.ndarray        # kept-triangle index
    row: np.ndarray
    c0: np.ndarray         # first and last covered pixel (top-left rule), frame-clipped; c1 < c0 if empty
    c1: np.ndarray
    xl: np.ndarray         # ASB xL, xR: float px or Q10.6
    xr: np.ndarray
    zl: np.ndarray         # ASB zL, iL at the left edge point
    il: np.ndarray
    sl: np.ndarray         # left / right edge dx/dy: float or sQ7.8
    sr: np.ndarray
    ql: np.ndarray         # left / right dy/dx: float or sQ7.8 (A.J. method (c))
    qr: np.ndarray
    first: np.ndarray      # index of each kept triangle's first record (records are triangle-major)


def _accumulate(A0, dA, Y0, dY, Yc, extra: int):
    """The SLP's edge accumulator at line centre Yc: the start value plus the increment per line.

    ``extra``: fraction bits kept beyond the 16-bit word (``Datapath.acc_extra``). Ours keeps 16
    (a Q.22 increment, up to 40 bits); the paper's 16-bit datapath keeps none: the increment is
    one 16-bit word (saturated) and the accumulator is the ASB word itself.
    """
    inc = rom_div(dA, dY, X_FRAC + extra)                  # per line (one line = 64 units)
    if extra == 0:
        inc = sat(inc, 16)
    return ((A0 << extra) + (((Yc - Y0) * inc) >> X_FRAC)) >> extra


def _edge_at(X0, Y0, X1, Y1, Yc, g, bit, extra: int = ACC_EXTRA):
    """x of the edge (X0, Y0)->(X1, Y1) at line centre Yc: exact rational parts or the SLP accumulator."""
    dX, dY = X1 - X0, Y1 - Y0
    if bit:
        return _accumulate(X0, dX, Y0, dY, Yc, extra), None   # ASB word, Q10.6 (floor)
    num = (Yc - Y0) * dX + X0 * dY                          # x = num / dY (grid units), exact
    return num, dY


def _attr_at(A0, A1, Y0, Y1, Yc, g, bit, extra: int = ACC_EXTRA):
    """z or i of the edge at line centre Yc (eq. (1')); a 16-bit accumulator saturates to 0..65535."""
    if bit:
        a = _accumulate(A0, A1 - A0, Y0, Y1 - Y0, Yc, extra)
        return sat(a, 16, signed=False) if extra == 0 else a
    return A0 + (Yc - Y0) * ((A1 - A0) / (Y1 - Y0))


def asl_update(st: Setup, W: int) -> Records:
    """ASL build and update for every line: x, z, i of the left edge and x of the right edge.

    The bit model steps the SLP's 32-bit accumulators (computed in closed form, which is the
    same integer as the stepped sum, see the module docstring) and truncates to the ASB words;
    the float model keeps x as an exact rational on the 1/256 grid, so its spans are exactly the
    reference rasteriser's, and z, i in float64.
    """
    g, bit = st.grid, st.bit
    nrow = st.r1 - st.r0 + 1
    tri = np.repeat(np.arange(st.n), nrow)
    first = np.cumsum(nrow) - nrow
    row = np.repeat(st.r0 - first, nrow) + np.arange(int(nrow.sum()))
    Yc = row * g + g // 2
    X, Y, Z, Iv = (a[:, tri] for a in (st.X, st.Y, st.Z, st.Iv))
    upper = Yc < Y[1]                                       # short side on a->b, else b->c
    sa = np.where(upper, 0, 1)
    sb = sa + 1
    ar = np.arange(tri.size)
    Xs0, Ys0, Xs1, Ys1 = X[sa, ar], Y[sa, ar], X[sb, ar], Y[sb, ar]
    ex = st.fmt.datapath.acc_extra
    longv = _edge_at(X[0], Y[0], X[2], Y[2], Yc, g, bit, ex)
    shortv = _edge_at(Xs0, Ys0, Xs1, Ys1, Yc, g, bit, ex)
    ll = st.long_left[tri]
    half = g // 2
    if bit:
        xl = np.where(ll, longv[0], shortv[0])
        xr = np.where(ll, shortv[0], longv[0])
        c0 = -((half - xl) // g)                              # centre >= xL
        c1 = -((half - xr) // g) - 1                          # centre < xR
    else:
        nl = np.where(ll, longv[0], shortv[0])
        dl = np.where(ll, longv[1], shortv[1])
        nr = np.where(ll, shortv[0], longv[0])
        dr = np.where(ll, shortv[1], longv[1])
        # centre g*c + half >= num/d  <=>  c >= (num - half d) / (g d), d > 0
        c0 = -((-(nl - half * dl)) // (g * dl))
        c1 = -((-(nr - half * dr)) // (g * dr)) - 1
        xl, xr = nl / dl / g, nr / dr / g
    c0 = np.maximum(c0, 0)
    c1 = np.minimum(c1, W - 1)
    # left-edge attributes
    lz0 = np.where(ll, Z[0], Z[sa, ar])
    lz1 = np.where(ll, Z[2], Z[sb, ar])
    li0 = np.where(ll, Iv[0], Iv[sa, ar])
    li1 = np.where(ll, Iv[2], Iv[sb, ar])
    ly0 = np.where(ll, Y[0], Ys0)
    ly1 = np.where(ll, Y[2], Ys1)
    zl = _attr_at(lz0, lz1, ly0, ly1, Yc, g, bit, ex)
    il = _attr_at(li0, li1, ly0, ly1, Yc, g, bit, ex)
    # slopes for A.J.
    dXl = np.where(ll, X[2] - X[0], Xs1 - Xs0)
    dYl = np.where(ll, Y[2] - Y[0], Ys1 - Ys0)
    dXr = np.where(ll, Xs1 - Xs0, X[2] - X[0])
    dYr = np.where(ll, Ys1 - Ys0, Y[2] - Y[0])
    if bit:
        sl, sr = sat(rom_div(dXl, dYl, SLOPE_FRAC), 16), sat(rom_div(dXr, dYr, SLOPE_FRAC), 16)
        ql = np.where(dXl == 0, (1 << 15) - 1, sat(rom_div(dYl, dXl, SLOPE_FRAC), 16))
        qr = np.where(dXr == 0, (1 << 15) - 1, sat(rom_div(dYr, dXr, SLOPE_FRAC), 16))
    else:
        sl, sr = dXl / dYl, dXr / dYr
        with np.errstate(divide="ignore"):
            ql, qr = dYl / dXl, dYr / dXr
    if not bit:
        zl = zl.astype(np.float64)
    return Records(tri=tri, row=row, c0=c0, c1=c1, xl=xl, xr=xr, zl=zl, il=il, sl=sl, sr=sr,
                   ql=ql, qr=qr, first=first)


def l_sort_x_merge(rec: Records, H: int) -> dict[str, np.ndarray]:
    """L-sort and X-merge counts for every line, from the ASL orders line to line.

    The ASL of a line is its records ordered by (xL, PL order). A line's segments that were
    active on the line before are bubble-sorted from their old order (L-sort: ``passes * (m - 1)``
    compares plus one exchange per inversion, plus one unlink per leaving segment); the entering
    ones are merge-sorted (``n ceil(log2 n)``) and merged in (``m + n - 1`` compares) (X-merge).
    Returns per-line arrays: ``m`` (ASL length), ``enter``, ``leave``, ``survive``,
    ``lsort``, ``xmerge``, and ``xmerge_start`` (X-merge of the whole list, for a band's first
    line).
    """
    key = rec.xl.astype(np.float64)
    order = np.lexsort((rec.tri, key, rec.row))
    rows = rec.row[order]
    bounds = np.searchsorted(rows, np.arange(H + 1))
    m = np.diff(bounds)
    enter = np.zeros(H, np.int64)
    leave = np.zeros(H, np.int64)
    lsort = np.zeros(H, np.int64)
    xmerge = np.zeros(H, np.int64)
    xstart = np.zeros(H, np.int64)
    prev_tri = np.zeros(0, np.int64)

    def msort(n):
        return int(n * np.ceil(np.log2(n))) if n >= 2 else 0

    for y in range(H):
        cur = rec.tri[order[bounds[y]:bounds[y + 1]]]
        mm = cur.size
        xstart[y] = msort(mm)
        surv_mask = np.isin(cur, prev_tri, assume_unique=True)
        ns = int(surv_mask.sum())
        enter[y] = mm - ns
        leave[y] = prev_tri.size - ns
        # L-sort of the survivors: their previous order vs the new order
        if ns >= 2:
            pos = {int(t): k for k, t in enumerate(prev_tri)}
            old = np.fromiter((pos[int(t)] for t in cur[surv_mask]), np.int64, ns)  # old rank in new order
            # element j (new order) is preceded in the old order by larger-new-rank elements
            gt = (old[None, :] < old[:, None])  # gt[i, j]: j before i in old order
            newr = np.arange(ns)
            inv_of = (gt & (newr[None, :] > newr[:, None])).sum(axis=1)
            swaps = int(inv_of.sum())
            passes = int(inv_of.max()) + 1 if swaps else 1
            lsort[y] = passes * (ns - 1) + swaps
        lsort[y] += SLP_OPS["leave_per_segment"] * leave[y]
        n_in = int(enter[y])
        xmerge[y] = msort(n_in) + (ns + n_in - 1 if ns and n_in else 0)
        prev_tri = cur
    return {"m": m, "enter": enter, "leave": leave, "survive": m - enter, "lsort": lsort,
            "xmerge": xmerge, "xmerge_start": xstart, "order": order, "bounds": bounds}


def slp_line_ops(st: Setup, lines: dict, band: tuple[int, int], *, aj: str, pn: int) -> dict[str, int]:
    """All SLP operations of one band, by stage (Y-sort ... DMM/P write)."""
    y0, y1 = band
    _, _, ops = y_sort(st, band)
    inb = (st.r1 >= y0) & (st.r0 < y1)
    nt = int(inb.sum())
    ops["asl_build"] = nt * (3 * SLP_OPS["edge_setup_per_edge"] + SLP_OPS["plane_setup_per_triangle"]
                             + 2 * SLP_OPS["start_per_edge"])
    mid = inb & (st.rmid > np.maximum(st.r0, y0)) & (st.rmid <= np.minimum(st.r1, y1 - 1))
    ops["asl_build"] += SLP_OPS["mid_reload"] * int(mid.sum())
    if aj != "none":
        ops["aj_setup"] = nt * 3 * SLP_OPS["aj_slopes_per_edge"]
        if aj == "b":
            ops["aj_setup"] += nt * 3 * SLP_OPS["aj_perp_per_edge"]
    sl = slice(y0 + 1, y1)
    ops["asl_update"] = SLP_OPS["update_per_segment"] * int(lines["survive"][sl].sum())
    ops["l_sort"] = int(lines["lsort"][sl].sum())
    ops["x_merge"] = int(lines["xmerge"][sl].sum()) + int(lines["xmerge_start"][y0])
    m = lines["m"][y0:y1]
    ops["block_lists"] = int(m.sum()) + (y1 - y0) * pn
    from rasterhw.golden_model.experts.formats import ASB_WORDS
    ops["dmm_p_write"] = ASB_WORDS * int(m.sum()) + 2 * pn * (y1 - y0)
    return ops
