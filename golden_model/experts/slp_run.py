"""The SLP's sorts, run: Y-sort, L-sort, X-merge, ASL update and the PXPs' block lists.

:mod:`slp` computes the ASL of every line in closed form and prices the sorts from their
inputs; this module *runs* them, one band at a time, as an SLP would, and counts every compare,
move and exchange it executes (seed 000, section 4):

* **Y-sort** "すべての稜線を、y_min ... をキーとしてバケットソートする": every PL triangle (the host
  broadcasts the whole PL to every SLP) gets the band test (2 compares); one in the band gets
  its bucket, its first line in the band (1 compare against the band start, 1 subtract), and is
  linked at the bucket's tail (1 move). PL order is kept within a bucket. We bucket triangles,
  not edges: one ASB (segment) per triangle per line.
* **L-sort** "進入、退出するセグメントと ... リストとをバブルソートする": on every line after the band's
  first, each segment of the previous ASL is tested for leaving (1 compare) and unlinked if it
  left (1 move); the survivors, their x stepped (ASL update, priced in :mod:`slp`), are
  bubble-sorted on (xL, PL order): passes over the whole list until one pass exchanges nothing,
  1 compare per neighbour pair, 1 per exchange.
* **X-merge** "1スキャン・ライン内に現われるセグメントを、その左稜線のxs座標値をキーとして、マージ
  ソートする": the line's bucket (the entering segments; on the band's first line every segment
  of the line) is merge-sorted bottom-up (1 compare per decision, 1 move per element placed at
  every level) and merged into the survivors (the same).
* **Block lists** (fig. 3.2, our reading in docs/experts.md): walking the finished ASL once,
  the **block leading segment pointer** of each PXP range is the first segment (in ASL order)
  whose first pixel lies in the range, and the **block boundary bucket list** of a range holds
  the segments that start left of it and reach into it (with A.J. for the range widened by the
  guard pixel each side). Per segment: 1 compare (has it a pixel?), 2 compares per range start it
  passes (and 1 move when it becomes that range's leading segment), 1 to stop; per later range it
  reaches: 1 compare and 1 move (link into that range's bucket); 1 compare to stop.

The sorted lists are the ASL of :func:`slp.l_sort_x_merge` (tested), and the executed counts
sit beside its priced ones in the report (comparison only; the report's SLP rows are these).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.slp import Records, Setup

__all__ = ["merge", "merge_sort", "bubble_sort", "bucket_sort", "block_lists", "SlpBand", "run_band",
           "run_bands", "SORT_STAGES"]

SORT_STAGES = ("y_sort", "l_sort", "x_merge", "block_lists")


def merge(x: list, y: list, key) -> tuple[list, int, int]:
    """Merge two sorted lists (stable: ``x`` first on equal keys). Returns (list, compares, moves)."""
    i = j = c = 0
    out = []
    while i < len(x) and j < len(y):
        c += 1
        if key(y[j]) < key(x[i]):
            out.append(y[j])
            j += 1
        else:
            out.append(x[i])
            i += 1
    out.extend(x[i:])
    out.extend(y[j:])
    return out, c, len(out)


def merge_sort(items: list, key) -> tuple[list, int, int]:
    """Bottom-up merge sort. Returns (sorted list, compares, moves)."""
    a = list(items)
    n = len(a)
    c = m = 0
    w = 1
    while w < n:
        out = []
        for i in range(0, n, 2 * w):
            part, ci, mi = merge(a[i:i + w], a[i + w:i + 2 * w], key)
            out.extend(part)
            c += ci
            m += mi
        a = out
        w *= 2
    return a, c, m


def bubble_sort(items: list, key) -> tuple[list, int, int, int]:
    """Bubble sort, whole passes until one exchanges nothing. Returns (list, compares, exchanges, passes)."""
    a = list(items)
    n = len(a)
    c = s = p = 0
    while True:
        p += 1
        swapped = False
        for i in range(n - 1):
            c += 1
            if key(a[i + 1]) < key(a[i]):
                a[i], a[i + 1] = a[i + 1], a[i]
                s += 1
                swapped = True
        if not swapped:
            return a, c, s, p


def bucket_sort(first: np.ndarray, last: np.ndarray, band: tuple[int, int]) -> tuple[list[list[int]], dict]:
    """Y-sort: bucket the items (PL order) by their first line in ``band``. Returns (buckets, ops)."""
    y0, y1 = band
    buckets: list[list[int]] = [[] for _ in range(y1 - y0)]
    ops = {"compares": 0, "arith": 0, "moves": 0}
    for t in range(len(first)):
        ops["compares"] += 2
        if int(last[t]) >= y0 and int(first[t]) < y1:
            ops["compares"] += 1
            ops["arith"] += 1
            buckets[max(int(first[t]), y0) - y0].append(t)
            ops["moves"] += 1
    return buckets, ops


def block_lists(asl: list[int], c0: np.ndarray, c1: np.ndarray, bounds: np.ndarray, *, guard: int = 0,
                width: int | None = None) -> tuple[list[int], list[list[int]], dict]:
    """Leading pointer (ASL position or -1) and bucket list (ASL positions) of every range.

    ``asl``: record ids in ASL order (their first pixels ``c0`` rise); ``bounds``: (P + 1,).
    ``guard``: the lists are for ``[max(lo - guard, 0), min(hi + guard, width))`` -- with A.J. the
    PXP resolves one guard pixel each side, so neighbouring lists overlap. One walk of the ASL: a
    segment is the leading one of every range whose start it is the first to reach (if it starts
    before that range's end), and goes into the bucket of every later range that starts after it
    and no later than its last pixel."""
    b = np.asarray(bounds, dtype=np.int64)
    P = len(b) - 1
    W = int(b[-1]) if width is None else width
    glo = np.maximum(b[:-1] - guard, 0).tolist()
    ghi = np.minimum(b[1:] + guard, W).tolist()
    live = [ghi[p] > glo[p] and b[p + 1] > b[p] for p in range(P)]
    lead = [-1] * P
    buckets: list[list[int]] = [[] for _ in range(P)]
    c = m = 0
    q = 0
    for pos, r in enumerate(asl):
        a, e = int(c0[r]), int(c1[r])
        c += 1
        if e < a:
            continue
        while q < P and a >= glo[q]:
            c += 2
            if live[q] and a < ghi[q]:
                lead[q] = pos
                m += 1
            q += 1
        c += 1
        k = q
        while k < P and glo[k] <= e:
            c += 1
            if live[k]:
                buckets[k].append(pos)
                m += 1
            k += 1
        c += 1
    return lead, buckets, {"compares": c, "moves": m}


@dataclass
class SlpBand:
    """One band through the SLP: its ASLs, block lists and executed operations."""

    band: tuple[int, int]
    asl: list[list[int]]                       # per line: record ids in ASL order
    lead: list[list[int]] = field(default_factory=list)      # per line: leading pointer per range
    buckets: list[list[list[int]]] = field(default_factory=list)
    ops: dict = field(default_factory=dict)    # stage -> executed operations
    detail: dict = field(default_factory=dict)  # compares / moves / exchanges by stage
    per_line: dict = field(default_factory=dict)


def run_band(st: Setup, rec: Records, band: tuple[int, int], bounds=None, *, W: int = 512, guard: int = 0) -> SlpBand:
    """Run the SLP's sorts over one band; ``bounds`` (P + 1,) PXP ranges for the block lists
    (``guard``: pixels each side the PXPs resolve beyond their ranges, 1 with A.J. (c))."""
    y0, y1 = band
    if not 0 <= y0 < y1:
        raise RasterhwError(f"experts: band must be 0 <= start < end, not {band!r}")
    b = np.asarray([0, W] if bounds is None else bounds, dtype=np.int64)
    xl = rec.xl.tolist()
    first, r0, r1 = rec.first, st.r0, st.r1

    def rid(t: int, y: int) -> int:
        return int(first[t] + (y - r0[t]))

    buckets, yo = bucket_sort(r0, r1, band)
    d = {"y_sort_compares": yo["compares"], "y_sort_arith": yo["arith"], "y_sort_moves": yo["moves"],
         "l_sort_leave_tests": 0, "l_sort_unlinks": 0, "l_sort_compares": 0, "l_sort_exchanges": 0,
         "x_merge_compares": 0, "x_merge_moves": 0, "block_compares": 0, "block_moves": 0}
    nl = y1 - y0
    pl = {k: np.zeros(nl, np.int64) for k in ("l_sort", "x_merge", "block_lists", "passes")}
    out = SlpBand(band=band, asl=[])
    prev: list[int] = []
    for y in range(y0, y1):
        def key(t, y=y):
            return (xl[rid(t, y)], t)
        ls = 0
        surv: list[int] = []
        if y > y0:
            for t in prev:
                d["l_sort_leave_tests"] += 1
                ls += 1
                if int(r1[t]) >= y:
                    surv.append(t)
                else:
                    d["l_sort_unlinks"] += 1
                    ls += 1
            surv, c, s, p = bubble_sort(surv, key)
            d["l_sort_compares"] += c
            d["l_sort_exchanges"] += s
            ls += c + s
            pl["passes"][y - y0] = p
        ent, c1_, m1 = merge_sort(buckets[y - y0], key)
        cur, c2, m2 = merge(surv, ent, key)
        d["x_merge_compares"] += c1_ + c2
        d["x_merge_moves"] += m1 + m2
        pl["l_sort"][y - y0] = ls
        pl["x_merge"][y - y0] = c1_ + c2 + m1 + m2
        recs = [rid(t, y) for t in cur]
        out.asl.append(recs)
        lead, bk, bo = block_lists(recs, rec.c0, rec.c1, b, guard=guard, width=W)
        out.lead.append(lead)
        out.buckets.append(bk)
        d["block_compares"] += bo["compares"]
        d["block_moves"] += bo["moves"]
        pl["block_lists"][y - y0] = bo["compares"] + bo["moves"]
        prev = cur
    out.detail = d
    out.ops = {"y_sort": d["y_sort_compares"] + d["y_sort_arith"] + d["y_sort_moves"],
               "l_sort": d["l_sort_leave_tests"] + d["l_sort_unlinks"] + d["l_sort_compares"] + d["l_sort_exchanges"],
               "x_merge": d["x_merge_compares"] + d["x_merge_moves"],
               "block_lists": d["block_compares"] + d["block_moves"]}
    out.per_line = pl
    return out


def run_bands(fr, bands: np.ndarray, bounds=None, *, guard: int = 0) -> list[SlpBand]:
    """:func:`run_band` for every band ``[bands[s], bands[s+1])`` of an :class:`model.ExpertsFrame`."""
    return [run_band(fr.setup, fr.records, (int(bands[s]), int(bands[s + 1])), bounds, W=fr.width, guard=guard)
            for s in range(len(bands) - 1)]
