"""The span PXP (ours, after the paper's steps): span cull and depth search per span (Watkins), not a per-pixel Z-buffer.

Seed 000, section 4: the PXP's stages are "iv) スキャン・ラインをスパンに分割し、そのスパン内に
現われる範囲のセグメントを抽出する《span cull》" and "v) iv)で抽出したセグメントに応じてデプス・
サーチを行ない、可視セグメントを決定する《depth search》"; section 2.2: "セグメントという「広がり」を
持った単位で可視/不可視を判定するので、一旦可視セグメントが決定されればその中では一様な計算で各画素の
値を決めることができる (span coherence)", with Watkins [8] as the algorithm's reference.

For every PXP range ``[lo, hi)`` of every line (:func:`span_pxp`):

* **range clip**: each segment of the line that reaches the range is clipped to it
  (``a = max(c0, lo)``, ``b = min(c1, hi - 1)``); its z at ``a`` is its **start value**.
* **span cull**: the range is cut at every clipped segment's ends (``a`` and ``b + 1``) and at
  ``lo``, ``hi`` (Watkins' spans: between two cuts the set of segments present does not change);
  every span gets the segments present in it. Empty spans are background.
* **depth search** per span with ``k >= 2`` segments (``k = 1``: that segment is visible, no
  search). Rule (ours; the paper gives none beyond "デプス・サーチ"): z of every segment at the
  span's left and right pixel; ``S`` = the nearest at the left pixel by the machine's comparator
  (16-bit key, ties to the lower ASB address -- :func:`pxp.depth_search`'s rule); then, for every
  other segment ``B``, a guarded test that ``S`` stays nearest over the whole span from its two
  end depths (z is linear along the line, so a difference with the same sign at both ends keeps
  it in between). If every test holds, the span is ``S``'s. Otherwise the order of the end depths
  flips (or is too close to call), two segments cross inside the span: **halve** the span at
  ``m = (l + r + 1) >> 1`` and search both halves; a one-pixel span takes ``S``. Watkins splits
  at the crossing point, which needs a division; the PXP has a multiplier and no divider
  ("PXPにおいても ... 乗算器を装備"; the reciprocal ROM is the SLP's), so it halves (a shift).
* The guarded test (exact, so the image equals the per-pixel depth search's on every scene):
  bit model, ``zr`` the Q16.4 running z (exactly linear in the pixel, see :mod:`pxp`):
  ``zr_S <= zr_B`` at both ends when ``S``'s address is lower (ties go to S); else
  ``zr_S + 16 <= zr_B``, ``zr_B >= 16`` and ``zr_S < 65535 * 16`` at both ends (the 16-bit keys
  then differ at every pixel between, clamping included). Float model: ``z_S <= z_B - 1e-9`` at
  both ends (the per-pixel float z is the linear z within ~1e-13).

Operations (one 16-bit operation each; :data:`SPAN_OPS`) counted as the spans are executed:

* range clip 1 and start value 3 per clipped segment (as in :mod:`pxp`);
* span cull: per clipped segment 2 (enter and leave the span set), per span ``1 + k`` (the
  span's right end: the next segment start against each present segment's end);
* depth search, per span searched (halves included): ``2k`` z values (a multiply-add from the
  start value each), ``k - 1`` compares for ``S`` at the left pixel, ``2(k - 1)`` guarded tests:
  ``5k - 3``; a one-pixel span ``2k - 1`` (z and compare, as the per-pixel search).

**Operation-count model** (:func:`span_cycles` in this module; it is *not* what the span PXP HDL is
cycle-exact against -- that is ``golden_model/experts/span_cycles.py``, which counts the HDL's own
steps): one operation per cycle on a 16-bit datapath with one multiplier and one comparator (the paper's PXP:
"乗算器を装備", a microprogrammed 16-bit processor), so the cycles of one range of one line are
its counted operations of every PXP stage (range clip, start values, span cull, depth search,
smooth shading, A.J., DSLB write; the last three from :func:`pxp.pixel_costs` of the same visible
segments) plus 1 for the end-of-line token.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import DZ_FRAC, X_FRAC, Z_BITS
from rasterhw.golden_model.experts.pxp import PXP_OPS
from rasterhw.golden_model.experts.slp import Records, Setup

__all__ = ["SPAN_OPS", "SPAN_STAGES", "SpanResult", "span_pxp", "span_cycles", "FLOAT_GUARD"]

SPAN_STAGES = ("range_clip", "start_values", "span_cull", "depth_search")
SPAN_OPS = {
    "range_clip_per_segment": PXP_OPS["range_clip_per_segment"],
    "start_per_segment": PXP_OPS["start_per_segment"],
    "span_cull_per_segment": 2,      # enters the span set, leaves it
    "span_cull_per_span": 1,         # + k: the span's right end against each present segment's end
}
#: float model: a difference of end depths smaller than this is "too close to call" (halve)
FLOAT_GUARD = 1e-9
_ZMAX_RUN = ((1 << Z_BITS) - 1) << DZ_FRAC


@dataclass
class SpanResult:
    """The span PXP over a frame for one range partition."""

    win: np.ndarray            # (H*W,) winning record per pixel, -1 empty
    ops: dict                  # stage -> (H, P) operations per line and range
    counts: dict               # totals: spans, searched spans, halvings, pairs, ...
    bounds: np.ndarray         # (H, P + 1)

    def total(self, stages=SPAN_STAGES) -> int:
        return int(sum(int(self.ops[s].sum()) for s in stages))


def _z(st: Setup, rec: Records, r: np.ndarray, col: np.ndarray):
    """(compare key, linear z) of records ``r`` at pixels ``col``: the per-pixel formula of
    :func:`pxp.fragments`, so one-pixel results are the per-pixel search's bit for bit."""
    t = rec.tri[r]
    if st.bit:
        xc = (col << X_FRAC) + (1 << (X_FRAC - 1))
        zrun = (rec.zl[r] << DZ_FRAC) + (((xc - rec.xl[r]) * st.dzdx[t]) >> X_FRAC)
        return np.clip(zrun >> DZ_FRAC, 0, (1 << Z_BITS) - 1).astype(np.float64), zrun
    z = rec.zl[r] + (col + 0.5 - rec.xl[r]) * st.dzdx[t]
    return z, z


def _stays_nearest(bit: bool, zs_l, zb_l, zs_r, zb_r, s_lower):
    """The guarded test: S nearer than B at every pixel of the span (see the module docstring)."""
    if not bit:
        return (zs_l <= zb_l - FLOAT_GUARD) & (zs_r <= zb_r - FLOAT_GUARD)
    lower = (zs_l <= zb_l) & (zs_r <= zb_r)
    g = 1 << DZ_FRAC
    higher = ((zs_l + g <= zb_l) & (zs_r + g <= zb_r) & (zb_l >= g) & (zb_r >= g)
              & (zs_l < _ZMAX_RUN) & (zs_r < _ZMAX_RUN))
    return np.where(s_lower, lower, higher)


def _bounds2d(bounds, W: int, H: int) -> np.ndarray:
    b = np.asarray([0, W] if bounds is None else bounds, dtype=np.int64)
    if b.ndim not in (1, 2) or b.shape[-1] < 2 or (b.ndim == 2 and b.shape[0] != H):
        raise RasterhwError("experts: range bounds must be (P + 1,) or (H, P + 1) pixel boundaries")
    b = np.broadcast_to(b, (H, b.shape[-1]))
    if np.any(b[:, 0] != 0) or np.any(b[:, -1] != W) or np.any(np.diff(b, axis=1) < 0):
        raise RasterhwError(f"experts: range bounds must rise from 0 to {W}")
    return np.ascontiguousarray(b)


def span_pxp(st: Setup, rec: Records, W: int, H: int, bounds=None) -> SpanResult:
    """Run range clip, span cull and depth search of every PXP range of every line.

    ``bounds``: (P + 1,) or (H, P + 1) range boundaries (default: one PXP, the whole line).
    Vectorised over all ranges of the frame; the depth search halves level by level.
    """
    B = _bounds2d(bounds, W, H)
    P = B.shape[1] - 1
    U = H * P
    ok = np.flatnonzero(rec.c1 >= rec.c0)
    row, c0, c1 = rec.row[ok], rec.c0[ok], rec.c1[ok]
    # range clip: the ranges each segment reaches
    flat = (np.arange(H)[:, None] * (W + 1) + B).ravel()
    i0 = np.searchsorted(flat, row * (W + 1) + c0, "right") - 1
    i1 = np.searchsorted(flat, row * (W + 1) + c1, "right") - 1
    n = i1 - i0 + 1
    pr = np.repeat(ok, n)                                   # piece -> record
    ii = np.repeat(i0, n) + (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n))
    prow = rec.row[pr]
    j = ii - prow * (P + 1)
    lo, hi = B[prow, j], B[prow, j + 1]
    a = np.maximum(rec.c0[pr], lo)
    b = np.minimum(rec.c1[pr], hi - 1)
    nonempty = a <= b                                        # an empty range between: no piece
    pr, a, b = pr[nonempty], a[nonempty], b[nonempty]
    pu = (prow * P + j)[nonempty]                            # piece -> unit (line, range)
    # span cull: cuts at every unit's ends and every piece's ends
    ulo, uhi = B[:, :-1].ravel(), B[:, 1:].ravel()
    uid = np.arange(U)
    M = W + 1
    K = np.unique(np.concatenate([uid * M + ulo, uid * M + uhi, pu * M + a, pu * M + b + 1]))
    ku, kx = K // M, K % M
    is_span = np.zeros(K.size, bool)
    is_span[:-1] = (ku[1:] == ku[:-1]) & (kx[1:] > kx[:-1])
    s0 = np.searchsorted(K, pu * M + a)
    s1 = np.searchsorted(K, pu * M + b + 1)
    m = s1 - s0
    pp = np.repeat(np.arange(pr.size), m)                    # (piece, span) pairs
    ps = np.repeat(s0, m) + (np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m))
    k = np.bincount(ps, minlength=K.size)
    sl = kx
    sr = np.zeros(K.size, np.int64)
    sr[:-1] = kx[1:] - 1
    spans = np.flatnonzero(is_span)

    ops = {s: np.zeros(U, np.int64) for s in SPAN_STAGES}
    np.add.at(ops["range_clip"], pu, SPAN_OPS["range_clip_per_segment"])
    np.add.at(ops["start_values"], pu, SPAN_OPS["start_per_segment"])
    np.add.at(ops["span_cull"], pu, SPAN_OPS["span_cull_per_segment"])
    np.add.at(ops["span_cull"], ku[spans], SPAN_OPS["span_cull_per_span"] + k[spans])

    win = np.full(H * W, -1, np.int64)
    srow = ku // P

    def fill(rows, ls, rs, recs):
        cnt = rs - ls + 1
        base = np.repeat(rows * W + ls, cnt)
        off = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        win[base + off] = np.repeat(recs, cnt)

    one = spans[k[spans] == 1]
    pone = np.flatnonzero(k[ps] == 1)
    fill(srow[ps[pone]], sl[ps[pone]], sr[ps[pone]], pr[pp[pone]])
    # depth search on spans with k >= 2, halving where the end depths do not settle it
    multi = k[ps] >= 2
    tid_of_span = np.full(K.size, -1, np.int64)
    tsp = spans[k[spans] >= 2]
    tid_of_span[tsp] = np.arange(tsp.size)
    tl, tr, tu = sl[tsp], sr[tsp], ku[tsp]
    qt, qr = tid_of_span[ps[multi]], pr[pp[multi]]           # (task, record) pairs
    searched = halvings = pairs = 0
    while tl.size:
        kk = np.bincount(qt, minlength=tl.size)
        keyl, zl_ = _z(st, rec, qr, tl[qt])
        _, zr_ = _z(st, rec, qr, tr[qt])
        o = np.lexsort((qr, keyl, qt))
        first = np.ones(o.size, bool)
        first[1:] = qt[o][1:] != qt[o][:-1]
        S = np.empty(tl.size, np.int64)
        S[qt[o[first]]] = qr[o[first]]
        isS = qr == S[qt]
        zsl = np.empty(tl.size, zl_.dtype)
        zsr = np.empty(tl.size, zr_.dtype)
        zsl[qt[isS]], zsr[qt[isS]] = zl_[isS], zr_[isS]
        good = isS | _stays_nearest(st.bit, zsl[qt], zl_, zsr[qt], zr_, S[qt] < qr)
        bad = np.bincount(qt, weights=(~good).astype(np.float64), minlength=tl.size) > 0
        onepx = tl == tr
        done = onepx | ~bad
        cost = np.where(onepx, 2 * kk - 1, 5 * kk - 3)
        np.add.at(ops["depth_search"], tu, cost)
        searched += tl.size
        pairs += qt.size
        fill(tu[done] // P, tl[done], tr[done], S[done])
        split = np.flatnonzero(~done)
        halvings += split.size
        if not split.size:
            break
        mid = (tl[split] + tr[split] + 1) >> 1
        newid = np.full(tl.size, -1, np.int64)
        newid[split] = np.arange(split.size)
        keep = newid[qt] >= 0
        q2, r2 = newid[qt[keep]], qr[keep]
        ns = split.size
        tl = np.concatenate([tl[split], mid])
        tr = np.concatenate([mid - 1, tr[split]])
        tu = np.concatenate([tu[split], tu[split]])
        qt = np.concatenate([q2, q2 + ns])
        qr = np.concatenate([r2, r2])
    counts = {"segments": int(pr.size), "spans": int(spans.size), "spans_k2": int(tsp.size),
              "spans_k1": int(one.size), "searched": int(searched), "halvings": int(halvings),
              "search_pairs": int(pairs), "span_pairs": int(k[spans].sum())}
    return SpanResult(win=win, ops={s: v.reshape(H, P) for s, v in ops.items()}, counts=counts, bounds=B)


def span_cycles(fr, sp: SpanResult) -> np.ndarray:
    """Cycles of every (line, range) of the span PXP, (H, P): one operation per cycle (see the
    module docstring) -- its span stages, plus smooth shading, A.J. and the DSLB write of the
    same ranges from the frame's per-pixel counts, plus 1 for the end-of-line token.

    ``fr`` must be an :class:`model.ExpertsFrame` whose visible segments are ``sp.win``'s."""
    from rasterhw.golden_model.experts.model import pxp_range_ops
    if not np.array_equal(fr.win, sp.win):
        raise RasterhwError("experts: span PXP and frame disagree on the visible segments")
    tail = tuple(s for s in ("smooth_shading", "anti_jagging", "dslb") if s in fr.costs)
    return sum(sp.ops[s] for s in SPAN_STAGES) + pxp_range_ops(fr, sp.bounds, tail) + 1
