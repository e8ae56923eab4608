"""The Sn x Pn machine in time: bands, ranges, DMM/DSLB double buffers, load balancing at both levels.

Times are in *operation times*: one 16-bit operation of an SLP or a PXP (the counts of
:mod:`model`). The paper gives no clock, so this is the unit; :mod:`cost` and the report turn it
into the paper's Q.

Pipeline (seed 000, 3.2 "ホスト計算機、SLP、PXPの処理のオーバラップ"): the host writes the next
frame's PL into DMM/S while the SLPs read the current one; an SLP writes line k's ASL into one
bank of DMM/P while its PXPs read line k-1 from the other; a PXP writes line k into one DSLB bank
while the other drains line k-1 to the group's frame buffer. With banks ``k mod 2``::

    slp_start[k] = max(slp_end[k-1], pxp_end_all[k-2])        # DMM/P bank free
    pxp_start[k,p] = max(slp_end[k], pxp_end[k-1,p], drain_end[k-2])   # ASL ready, DSLB bank free
    drain_start[k] = max(pxp_end_all[k], drain_end[k-1])       # one FB per SLP group

A drain costs ``fb_cost`` op times per pixel (our assumption: the paper only says the FB is slow,
"アクセス時間の短縮をそれほど望めない"; default 0.25, a 64-bit FB word of four pixels).

Load balancing (3.3): SLP bands are set "ホスト計算機がPLをブロードキャストする時点" -- from the PL
(``"pl"``: the host's estimate, segments per line from every polygon's y extent), or frame to
frame from the SLP groups' finish times with method i or ii; PXP ranges are set per line from the
previous line's finish-time counters:

* method i, "各PXPの処理時間に逆比例した領域分割": new width proportional to ``width / time``;
* method ii, "所要時間が一定の閾値を越えたPXPに対して、その分担領域を縮少して、逆に早く処理が終了した
  PXPから順に縮少分に相等する領域を割当てる": a processor over the threshold
  (``mean * (1 + 2**-theta_shift)``, shifts only when the count is a power of two) gives up
  ``width >> shrink_shift`` pixels; the chunks, latest first, go to the earliest finishers in
  order. Ranges stay contiguous: only the widths move.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import ExpertsFrame, equal_bounds, slp_line_costs

__all__ = ["Balance", "rebalance", "band_estimate", "run_parallel", "ParallelResult", "RANGE_METHODS",
           "BAND_METHODS"]

RANGE_METHODS = ("static", "i", "ii")
BAND_METHODS = ("equal", "pl", "i", "ii")


@dataclass(frozen=True)
class Balance:
    theta_shift: int = 3      # threshold = mean * (1 + 1/8)
    shrink_shift: int = 3     # give up width / 8
    fb_cost: float = 0.25     # op times per pixel drained from a DSLB to the FB


def _widths_to_bounds(w: np.ndarray) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(w)])


def _round_widths(x: np.ndarray, total: int) -> np.ndarray:
    """Real widths -> integers >= 1 summing to ``total`` (cumulative rounding)."""
    x = np.maximum(np.asarray(x, dtype=np.float64), 1e-9)
    cum = np.rint(np.cumsum(x) / x.sum() * total).astype(np.int64)
    w = np.diff(np.concatenate([[0], cum]))
    # at least one each, taken from the widest
    while (w < 1).any():
        i, j = int(np.argmin(w)), int(np.argmax(w))
        w[i] += 1
        w[j] -= 1
    return w


def rebalance(widths: np.ndarray, times: np.ndarray, method: str, bal: Balance = Balance()) -> np.ndarray:
    """Next widths from the current widths and finish times (method ``"i"`` or ``"ii"``)."""
    widths = np.asarray(widths, dtype=np.int64)
    times = np.asarray(times, dtype=np.float64)
    total = int(widths.sum())
    if method == "static":
        return widths
    if method == "i":
        return _round_widths(widths / np.maximum(times, 1e-9), total)
    if method == "ii":
        w = widths.copy()
        thr = times.mean() * (1 + 2.0 ** -bal.theta_shift)
        late = [int(p) for p in np.argsort(-times, kind="stable") if times[p] > thr and w[p] > 1]
        early = [int(p) for p in np.argsort(times, kind="stable") if times[p] <= thr]
        for p, q in zip(late, early, strict=False):
            give = max(int(w[p]) >> bal.shrink_shift, 1)
            give = min(give, int(w[p]) - 1)
            w[p] -= give
            w[q] += give
        return w
    raise RasterhwError(f"experts: balancing method must be one of {', '.join(RANGE_METHODS)}, not {method!r}")


def band_estimate(fr: ExpertsFrame) -> np.ndarray:
    """The host's per-line load estimate from the PL alone: polygons whose y extent covers the line."""
    st = fr.setup
    d = np.zeros(fr.height + 1, np.int64)
    np.add.at(d, st.r0, 1)
    np.add.at(d, st.r1 + 1, -1)
    return np.cumsum(d)[:fr.height] + 1   # +1: an empty line still costs a little


def _bands_from_load(load: np.ndarray, sn: int) -> np.ndarray:
    cum = np.concatenate([[0], np.cumsum(load, dtype=np.float64)])
    targets = cum[-1] * np.arange(1, sn) / sn
    cuts = np.searchsorted(cum, targets)
    b = np.concatenate([[0], cuts, [load.size]]).astype(np.int64)
    for i in range(1, sn):                          # strictly increasing, the last bound kept at the
        b[i] = max(b[i], b[i - 1] + 1)              # frame's end (it was pushed past it: issue 47)
    for i in range(sn - 1, 0, -1):
        b[i] = min(b[i], b[i + 1] - 1)
    return b


@dataclass
class ParallelResult:
    sn: int
    pn: int
    band_method: str
    range_method: str
    bands: np.ndarray            # (Sn + 1,)
    pxp_time: np.ndarray         # (H, Pn) each PXP's time on each line
    slp_time: np.ndarray         # (H,) the line's SLP time (in its band)
    group_time: np.ndarray       # (Sn,) finish time of each SLP group's frame
    frame_time: float            # max over groups (the frame's time)
    pxp_busy: np.ndarray         # (Sn, Pn) summed PXP time per processor
    slp_busy: np.ndarray         # (Sn,) summed SLP time
    ranges: np.ndarray | None = None   # (H, Pn + 1) the PXP range boundaries used on each line

    def line_imbalance(self) -> np.ndarray:
        """max / mean PXP time, per line."""
        t = self.pxp_time
        return t.max(axis=1) / np.maximum(t.mean(axis=1), 1e-9)

    def imbalance(self) -> float:
        """sum over lines of the slowest PXP / sum over lines of the mean PXP (>= 1)."""
        t = self.pxp_time
        return float(t.max(axis=1).sum() / t.mean(axis=1).sum())


def _group(fr: ExpertsFrame, y0: int, y1: int, pn: int, range_method: str, bal: Balance, P: np.ndarray,
           cont: np.ndarray, start: np.ndarray, pl_cost: int, cyc_tables=None):
    W = fr.width
    cross, midrun = fr.costs["_cross"], fr.costs["_midrun"]
    from rasterhw.golden_model.experts.pxp import CROSS_OPS, MIDRUN_OPS
    extra_c = sum(CROSS_OPS.values())
    extra_m = sum(MIDRUN_OPS.values())
    widths = np.diff(equal_bounds(W, pn))
    n = y1 - y0
    tp = np.zeros((n, pn))
    tb = np.zeros((n, pn + 1), np.int64)
    ts = np.zeros(n)
    s_end = np.zeros(n)
    p_end = np.zeros((n, pn))
    d_end = np.zeros(n)
    t0 = float(pl_cost)    # the SLP reads the PL (DMM/S) before its first line
    for k in range(n):
        y = y0 + k
        b = _widths_to_bounds(widths)
        tb[k] = b
        a = b[:-1]
        if cyc_tables is None:
            c = P[y, b[1:]] - P[y, a]
            inner = a > 0
            c = c + np.where(inner, extra_c * cross[y, np.minimum(a, W - 1)]
                             + extra_m * midrun[y, np.minimum(a, W - 1)], 0)
        else:  # PXP HDL cycles: the block's finish-time counters (pxp_cycles.schedule, per PXP)
            pc, ps, guard = cyc_tables
            glo = np.maximum(a - guard, 0)
            ghi = np.minimum(b[1:] + guard, W)
            segs = ps[y, ghi] - ps[y, glo] + np.where(glo > 0, cross[y, np.minimum(glo, W - 1)], 0)
            r = (ghi - glo) + 1 + 2 * segs + 2 * (pc[y, ghi] - pc[y, glo])
            if k == 0:
                hs, hfree = np.zeros(pn, np.int64), np.zeros(pn, np.int64)
            h = np.maximum(hs + r, hfree)
            c = h - hs + 1
            drain = np.where(guard > 0, 3 * (ghi - glo) + (ghi == b[1:]), 2 * (b[1:] - a))
            hfree = h + drain + 1
            hs = h + 1
        tp[k] = c
        ts[k] = start[y] if k == 0 else cont[y]
        s_start = max(s_end[k - 1] if k else t0, p_end[k - 2].max() if k >= 2 else 0.0)
        s_end[k] = s_start + ts[k]
        ps = np.maximum(s_end[k], p_end[k - 1] if k else 0.0)
        if k >= 2:
            ps = np.maximum(ps, d_end[k - 2])
        p_end[k] = ps + c
        d_start = max(p_end[k].max(), d_end[k - 1] if k else 0.0)
        d_end[k] = d_start + bal.fb_cost * W
        widths = rebalance(widths, c, range_method, bal)
    return tp, ts, float(d_end[-1]), tb


def run_parallel(fr: ExpertsFrame, sn: int, pn: int, *, band_method: str = "equal", range_method: str = "static",
                 bal: Balance = Balance(), frames: int = 1, bands: np.ndarray | None = None,
                 pxp_unit: str = "ops") -> ParallelResult:
    """Time one frame on Sn SLP groups of Pn PXPs (``frames`` > 1: repeat the frame, the SLP bands
    adapting frame to frame with band methods i / ii; the last frame is returned).

    ``pxp_unit="cycles"``: PXP times are the PXP HDL's resolve cycles per line (its finish-time
    counter, :func:`model.pxp_range_cycles`) instead of counted operations; the SLP stays in ops.
    """
    if pxp_unit not in ("ops", "cycles"):
        raise RasterhwError(f"experts: pxp_unit must be ops or cycles, not {pxp_unit!r}")
    if range_method not in RANGE_METHODS:
        raise RasterhwError(f"experts: range method must be one of {', '.join(RANGE_METHODS)}, not {range_method!r}")
    if band_method not in BAND_METHODS:
        raise RasterhwError(f"experts: band method must be one of {', '.join(BAND_METHODS)}, not {band_method!r}")
    H, W = fr.height, fr.width
    equal_bounds(W, pn)
    if bands is None:
        bands = equal_bounds(H, sn) if band_method != "pl" else _bands_from_load(band_estimate(fr), sn)
    from rasterhw.golden_model.experts.model import PXP_STAGES, _prefix
    P = _prefix(fr, PXP_STAGES)
    tables = None
    if pxp_unit == "cycles":
        from rasterhw.golden_model.experts.model import _cycle_prefix
        tables = (*_cycle_prefix(fr), 1 if fr.aj == "c" else 0)
    cont, start = slp_line_costs(fr, pn)
    pl_cost = (13 + 2) * fr.setup.n
    for f in range(max(frames, 1)):
        tp = np.zeros((H, pn))
        rb = np.zeros((H, pn + 1), np.int64)
        ts = np.zeros(H)
        gt = np.zeros(sn)
        for s in range(sn):
            y0, y1 = int(bands[s]), int(bands[s + 1])
            a, b_, g, bb = _group(fr, y0, y1, pn, range_method, bal, P, cont, start, pl_cost, tables)
            tp[y0:y1], ts[y0:y1], gt[s], rb[y0:y1] = a, b_, g, bb
        if f + 1 < frames and band_method in ("i", "ii"):
            bands = _widths_to_bounds(rebalance(np.diff(bands), gt, band_method, bal))
    busy = np.stack([tp[int(bands[s]):int(bands[s + 1])].sum(axis=0) for s in range(sn)])
    sb = np.array([ts[int(bands[s]):int(bands[s + 1])].sum() + pl_cost for s in range(sn)])
    return ParallelResult(sn=sn, pn=pn, band_method=band_method, range_method=range_method, bands=np.asarray(bands),
                          pxp_time=tp, slp_time=ts, group_time=gt, frame_time=float(gt.max()), pxp_busy=busy,
                          slp_busy=sb, ranges=rb)
