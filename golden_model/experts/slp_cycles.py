"""The SLP HDL's golden side: its input words, its output words and its exact cycles.

``hdl/experts/slp.py`` (block ``experts-slp``) runs one band of the SLP's list work as
:mod:`slp_run` runs it -- Y-sort (bucket sort on the first line), per line the ASL update of each
segment's x_L and x_R (the edge accumulators of :mod:`slp`, one multiply per edge), L-sort (leave
test and bubble sort of the survivors), X-merge (bottom-up merge sort of the entering segments,
then merge into the survivors), and the block leading segment pointer and block boundary bucket
list of every PXP range (one walk of the finished ASL). This module gives its input (the band,
the PXP range bounds, the PL triangles with their set-up: the edges' start points and the
reciprocal-ROM increments of :func:`slp.rom_div`), and per line the words it must emit and the
cycles it must take, from the sorts actually run (:func:`slp_run.bubble_sort`,
:func:`slp_run.merge_sort`, :func:`slp_run.merge`, :func:`slp_run.block_lists`).

Cycles (every term; ``N`` PL triangles, ``L`` band lines, ``P`` ranges):

* band start: ``1`` (band word) ``+ L`` (clear the buckets) ``+ (P + 1)`` (range bounds) ``+ N``
  (one PL triangle a cycle: band test, bucket link; the Y-sort) ``+ 1`` (go);
* per line: ``1`` (start) ``+ m_prev`` (leave test and ASL update of every segment of the previous
  ASL) ``+ passes (n_s + 1)`` if ``n_s >= 2`` (bubble sort, one compare a cycle, one cycle to close a
  pass) ``+ 1 + n_e`` (walk the line's bucket, ASL update of each entering segment)
  ``+ levels (n_e + 1)`` (merge sort: one move a cycle, one cycle to set up a level)
  ``+ 1 + n_s + n_e`` (the final merge) ``+ walk + 1`` (end-of-line word), where the walk takes per
  segment 1 cycle (its ASL word), and if it has a pixel ``q + 1`` (range starts it passes, then the
  stop) ``+ k + 1`` (later ranges it reaches, then the stop).

The paper's datapath (``extra`` 0, ``Datapath.multipliers`` 1: "乗算器 ... を装備" per processor, seed
000 3.2) has **one** 16 x 16 multiplier, where ours has one per edge and attribute: each multiply
takes the multiplier for one cycle, so a segment's ASL update (x of its long edge, then of its short
edge) takes ``2`` cycles instead of 1 for every survivor and every entering segment (a leaving one
still takes 1: no multiply), and its ASL word ``2`` (z_L, then i_L as the word goes out): per line
``+ n_s + n_e + m`` cycles (:data:`MUL_CYCLES`).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import ACC_EXTRA, ADDR_BITS, SLOPE_FRAC, X_FRAC, sat
from rasterhw.golden_model.experts.slp import rom_div
from rasterhw.golden_model.experts.slp_run import (
    block_lists,
    bubble_sort,
    bucket_sort,
    merge,
    merge_sort,
)

__all__ = ["TRI_FIELDS", "KIND", "MUL_CYCLES", "tri_words", "asb", "band_run"]

TRI_FIELDS = ("t", "r0", "r1", "ll", "xa", "ya", "xb", "yb", "inc_ac", "inc_ab", "inc_bc",
              "za", "zb", "zinc_ac", "zinc_ab", "zinc_bc", "ia", "ib", "iinc_ac", "iinc_ab", "iinc_bc",
              "dzdx", "didx", "hue", "poly", "s_ac", "s_ab", "s_bc", "q_ac", "q_ab", "q_bc")
KIND = {"asl": 0, "lead": 1, "bucket": 2, "eol": 3}
_INC_MASK = (1 << 48) - 1
#: the paper's one multiplier: the extra cycle of each survivor's and entering segment's ASL update and
#: of each ASL word (``extra`` 0); ours: none
MUL_CYCLES = {0: 1, ACC_EXTRA: 0}


def tri_words(st) -> list[dict]:
    """The PL triangles as the SLP holds them after set-up: first and last line, which edge is left,
    the two upper vertices and the three edge increments (Q.22 per line, :func:`slp.rom_div`)."""
    if not st.bit:
        raise RasterhwError("experts: the SLP HDL's golden side needs the bit model")
    if st.n >= (1 << ADDR_BITS) - 1:
        raise RasterhwError(f"experts: {st.n} triangles do not fit the {ADDR_BITS}-bit PL order")
    X, Y = st.X.astype(np.int64), st.Y.astype(np.int64)
    ex = st.fmt.datapath.acc_extra
    sh = X_FRAC + ex

    def ainc(A, i, j):       # the paper's datapath (no extra fraction bits): one saturated 16-bit word
        d = Y[j] - Y[i]
        safe = np.where(d == 0, 1, d)
        v = np.where(d == 0, 0, rom_div(A[j] - A[i], safe, sh))
        return sat(v, 16) if ex == 0 else v

    def inc(i, j):
        return ainc(X, i, j)

    ac, ab, bc = inc(0, 2), inc(0, 1), inc(1, 2)
    Z, Iv = st.Z.astype(np.int64), st.Iv.astype(np.int64)
    zi = {f"{n}{i}{j}": ainc(A, i, j) for n, A in (("z", Z), ("i", Iv)) for i, j in ((0, 2), (0, 1), (1, 2))}
    # the A.J. slopes of each edge, sQ7.8 (slp.asl_update's rule), selected per line like x
    slopes, recips = {}, {}
    for e, (i, j) in (("ac", (0, 2)), ("ab", (0, 1)), ("bc", (1, 2))):
        dX, dY = X[j] - X[i], Y[j] - Y[i]
        slopes[e] = np.where(dY == 0, 0, sat(rom_div(dX, np.where(dY == 0, 1, dY), SLOPE_FRAC), 16))
        recips[e] = np.where(dX == 0, (1 << 15) - 1, sat(rom_div(dY, np.where(dX == 0, 1, dX), SLOPE_FRAC), 16))
    out = []
    for t in range(st.n):
        h = st.hue[t]
        out.append({"t": t, "r0": int(st.r0[t]), "r1": int(st.r1[t]), "ll": int(bool(st.long_left[t])),
                    "xa": int(X[0, t]), "ya": int(Y[0, t]), "xb": int(X[1, t]), "yb": int(Y[1, t]),
                    "inc_ac": int(ac[t]), "inc_ab": int(ab[t]), "inc_bc": int(bc[t]),
                    "za": int(Z[0, t]), "zb": int(Z[1, t]), "zinc_ac": int(zi["z02"][t]),
                    "zinc_ab": int(zi["z01"][t]), "zinc_bc": int(zi["z12"][t]),
                    "ia": int(Iv[0, t]), "ib": int(Iv[1, t]), "iinc_ac": int(zi["i02"][t]),
                    "iinc_ab": int(zi["i01"][t]), "iinc_bc": int(zi["i12"][t]),
                    "dzdx": int(st.dzdx[t]), "didx": int(st.didx[t]),
                    "hue": int((h[0] << 6) | (h[1] << 3) | h[2]), "poly": int(st.poly[t]),
                    **{f"{k}_{e}": int(v[e][t]) for k, v in (("s", slopes), ("q", recips)) for e in ("ac", "ab", "bc")}})
    return out


def _acc(a0: int, y0: int, inc: int, yc: int, extra: int) -> int:
    """An SLP edge accumulator at line centre ``yc`` (:func:`slp._accumulate`): ``extra`` fraction
    bits beyond the word (``Datapath.acc_extra``)."""
    return ((a0 << extra) + (((yc - y0) * inc) >> X_FRAC)) >> extra


def _x(tw: dict, y: int, extra: int = ACC_EXTRA) -> tuple[int, int]:
    """x_L, x_R (Q10.6) of triangle word ``tw`` on line ``y``: :func:`slp._edge_at`, bit model."""
    yc = (y << X_FRAC) + (1 << (X_FRAC - 1))

    def edge(x0, y0, inc):
        return _acc(x0, y0, inc, yc, extra)

    lng = edge(tw["xa"], tw["ya"], tw["inc_ac"])
    sht = edge(tw["xa"], tw["ya"], tw["inc_ab"]) if yc < tw["yb"] else edge(tw["xb"], tw["yb"], tw["inc_bc"])
    return (lng, sht) if tw["ll"] else (sht, lng)


def asb(tw: dict, y: int, extra: int = ACC_EXTRA) -> dict:
    """The ASB of triangle word ``tw`` on line ``y`` as the SLP writes it into the DMM/P: x_L, x_R,
    and z_L, i_L, the A.J. slopes of the left and right edges (the edge of each chosen as for x),
    with the triangle's dz/dx, di/dx, hue, PL index and polygon number."""
    yc = (y << X_FRAC) + (1 << (X_FRAC - 1))
    upper = yc < tw["yb"]

    def edge(a0, y0, inc):
        return _acc(a0, y0, inc, yc, extra)

    def left_right(pre, a, b):
        lng = edge(tw[a], tw["ya"], tw[f"{pre}inc_ac"])
        sht = edge(tw[a], tw["ya"], tw[f"{pre}inc_ab"]) if upper else edge(tw[b], tw["yb"], tw[f"{pre}inc_bc"])
        return (lng, sht) if tw["ll"] else (sht, lng)
    xl, xr = left_right("", "xa", "xb")
    zl, _ = left_right("z", "za", "zb")
    il, _ = left_right("i", "ia", "ib")
    if extra == 0:                    # a 16-bit accumulator saturates (slp._attr_at)
        zl, il = min(max(zl, 0), 0xFFFF), min(max(il, 0), 0xFFFF)
    es = "ab" if upper else "bc"
    le, re = ("ac", es) if tw["ll"] else (es, "ac")
    return {"xl": xl, "xr": xr, "zl": zl, "il": il, "dzdx": tw["dzdx"], "didx": tw["didx"], "hue": tw["hue"],
            "addr": tw["t"], "poly": tw["poly"], "sl": tw[f"s_{le}"], "ql": tw[f"q_{le}"], "sr": tw[f"s_{re}"],
            "qr": tw[f"q_{re}"]}


def band_run(tws: list[dict], band: tuple[int, int], bounds, *, width: int, guard: int = 0,
             extra: int = ACC_EXTRA) -> dict:
    """One band through the SLP: per line the ASL (PL indices in ASL order), the output words
    ``(kind, p, pos, t, y, ASB or None)`` in order, and cycles (:data:`__doc__`); ``start_cycles`` before line 0."""
    y0, y1 = band
    b = np.asarray(bounds, dtype=np.int64)
    P = len(b) - 1
    W = width
    r0 = np.array([tw["r0"] for tw in tws], np.int64)
    r1 = np.array([tw["r1"] for tw in tws], np.int64)
    buckets, _ = bucket_sort(r0, r1, band)
    glo = np.maximum(b[:-1] - guard, 0)
    ghi = np.minimum(b[1:] + guard, W)
    live = (ghi > glo) & (b[1:] > b[:-1])
    out = {"start_cycles": 1 + (y1 - y0) + (P + 1) + len(tws) + 1, "lines": [], "words": [], "line_cycles": [],
           "asl": []}
    prev: list[int] = []
    one = MUL_CYCLES[extra]
    for y in range(y0, y1):
        xs = {}
        cyc = 1 + len(prev)
        surv = [t for t in prev if r1[t] >= y]
        cyc += one * len(surv)
        for t in surv:
            xs[t] = _x(tws[t], y, extra)

        def key(t, xs=xs):
            return (xs[t][0], t)
        if len(surv) >= 2:
            surv, _, _, passes = bubble_sort(surv, key)
            cyc += passes * (len(surv) + 1)
        ent = list(buckets[y - y0])
        for t in ent:
            xs[t] = _x(tws[t], y, extra)
        cyc += 1 + len(ent) + one * len(ent)
        ne = len(ent)
        ent, _, _ = merge_sort(ent, key)
        levels = int(np.ceil(np.log2(ne))) if ne >= 2 else 0
        cyc += levels * (ne + 1)
        cur, _, _ = merge(surv, ent, key)
        cyc += 1 + len(cur)
        # the walk: the ASL word of every segment, leading pointers and bucket entries as found
        c0 = np.array([max((xs[t][0] + 31) >> X_FRAC, 0) for t in cur], np.int64)
        c1 = np.array([min(((xs[t][1] + 31) >> X_FRAC) - 1, W - 1) for t in cur], np.int64)
        words = []
        q = 0
        for pos, t in enumerate(cur):
            words.append((KIND["asl"], 0, pos, t, y, asb(tws[t], y, extra)))
            cyc += 1 + one
            a, e = int(c0[pos]), int(c1[pos])
            if e < a:
                continue
            while q < P and a >= glo[q]:
                if live[q] and a < ghi[q]:
                    words.append((KIND["lead"], q, pos, t, y, None))
                q += 1
                cyc += 1
            cyc += 1
            k = q
            while k < P and glo[k] <= e:
                if live[k]:
                    words.append((KIND["bucket"], k, pos, t, y, None))
                k += 1
                cyc += 1
            cyc += 1
        words.append((KIND["eol"], 0, 0, 0, y, None))
        cyc += 1
        lead, bk, _ = block_lists(list(range(len(cur))), c0, c1, b, guard=guard, width=W)
        assert lead == [next((w[2] for w in words if w[0] == 1 and w[1] == p), -1) for p in range(P)]
        assert bk == [[w[2] for w in words if w[0] == 2 and w[1] == p] for p in range(P)]
        out["words"] += words
        out["line_cycles"].append(cyc)
        out["asl"].append(cur)
        prev = cur
    out["cycles"] = out["start_cycles"] + sum(out["line_cycles"])
    return out
