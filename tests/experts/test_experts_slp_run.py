"""The SLP's sorts as they run: results sorted, executed counts against independent counts, the
ASL they build against the closed-form one, the block lists against the PXP's segment selection."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts import slp_run
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene


@cache
def _frame(name: str):
    return render_frame(run_geometry(build_scene(name), 512, 512, z_bits=16), model="bit")


def _inversions(a) -> int:
    return sum(1 for i in range(len(a)) for j in range(i + 1, len(a)) if a[j] < a[i])


@pytest.mark.parametrize("seed", range(5))
def test_sorts_sort_and_count_what_they_do(seed):
    rng = np.random.default_rng(seed)
    keys = rng.integers(0, 12, int(rng.integers(0, 40))).tolist()
    idx = list(range(len(keys)))
    key = keys.__getitem__
    want = sorted(idx, key=lambda i: (keys[i], i))            # stable
    out, c, m = slp_run.merge_sort(idx, key)
    assert out == want
    n = len(keys)
    assert c <= n * int(np.ceil(np.log2(n))) if n > 1 else c == 0
    assert m == (n * int(np.ceil(np.log2(n))) if n > 1 else 0)   # every element placed at every level
    out, c, s, p = slp_run.bubble_sort(idx, key)
    assert out == want
    assert s == _inversions(keys)                              # one exchange per inversion
    assert c == p * max(n - 1, 0)
    # a nearly sorted list (what the L-sort sees): one exchange, two passes
    near = sorted(idx, key=key)
    if n >= 3 and keys[near[0]] != keys[near[1]]:
        near[0], near[1] = near[1], near[0]
        assert slp_run.bubble_sort(near, key)[1:] == (2 * (n - 1), 1, 2)


def test_bucket_sort_keeps_pl_order_in_a_bucket_and_counts():
    first = np.array([5, 2, 5, 0, 9, 3])
    last = np.array([6, 4, 8, 1, 12, 3])
    b, ops = slp_run.bucket_sort(first, last, (2, 8))
    assert b[0] == [1] and b[3] == [0, 2] and b[1] == [5] and sum(map(len, b)) == 4
    assert ops == {"compares": 2 * 6 + 4, "arith": 4, "moves": 4}


@pytest.mark.parametrize("name", ["experts-tilt-1000", "experts-uneven"])
def test_run_slp_builds_the_asl_and_its_counts_meet_the_priced_ones(name):
    f = _frame(name)
    ln = f.lines
    runs = slp_run.run_bands(f, equal_bounds(512, 4), equal_bounds(512, 8))
    for r in runs:
        y0, y1 = r.band
        for y in range(y0, y1):
            assert r.asl[y - y0] == ln["order"][ln["bounds"][y]:ln["bounds"][y + 1]].tolist()
        d = r.detail
        # comparison only: the bubble sort's executed compares + exchanges + unlinks are the
        # inversion-and-pass count slp.l_sort_x_merge prices; the merge sort does fewer compares
        # than the n ceil(log2 n) it prices
        assert d["l_sort_compares"] + d["l_sort_exchanges"] + d["l_sort_unlinks"] == int(ln["lsort"][y0 + 1:y1].sum())
        assert d["x_merge_compares"] <= int(ln["xmerge"][y0 + 1:y1].sum()) + int(ln["xmerge_start"][y0])
        assert d["l_sort_exchanges"] > 0 and d["x_merge_moves"] > 0
    assert sum(r.detail["y_sort_moves"] for r in runs) == sum(
        int(((f.setup.r1 >= a) & (f.setup.r0 < b)).sum()) for a, b in zip(equal_bounds(512, 4), equal_bounds(512, 4)[1:], strict=False))


@pytest.mark.parametrize("guard", [0, 1])
def test_block_lists_hand_each_pxp_exactly_its_segments(guard):
    """Bucket list + the segments from the leading pointer on (while they start in the range)
    are the segments that reach the range -- what the PXP's range clip needs, nothing more; with
    the A.J. guard pixel, exactly the segments the PXP HDL's bench hands it today."""
    from rasterhw.golden_model.experts.pxp_cycles import line_segments
    f = _frame("experts-tilt-1000")
    rec = f.records
    rng = np.random.default_rng(3)
    cuts = np.sort(rng.integers(0, 513, 6))
    bounds = np.concatenate([[0], cuts, [512]])
    (r,) = slp_run.run_bands(f, np.array([100, 164]), bounds, guard=guard)
    seen = 0
    for y in range(100, 164):
        asl = r.asl[y - 100]
        for p in range(len(bounds) - 1):
            if bounds[p + 1] == bounds[p]:
                assert r.lead[y - 100][p] == -1 and not r.buckets[y - 100][p]
                continue
            lo, hi = max(bounds[p] - guard, 0), min(bounds[p + 1] + guard, 512)
            want = {q for q in asl if rec.c1[q] >= rec.c0[q] and rec.c1[q] >= lo and rec.c0[q] <= hi - 1}
            if guard and y % 8 == 0:
                hdl = {s["addr"] for s in line_segments(f, y, int(bounds[p]), int(bounds[p + 1]), aj="c")}
                assert hdl == {int(rec.tri[q]) for q in want}
            got = {asl[i] for i in r.buckets[y - 100][p]}
            assert all(rec.c0[q] < lo for q in got)
            pos = r.lead[y - 100][p]
            if pos >= 0:
                while pos < len(asl) and rec.c0[asl[pos]] < hi:
                    if rec.c1[asl[pos]] >= rec.c0[asl[pos]]:
                        got.add(asl[pos])
                    pos += 1
            assert got == want, (y, p)
            seen += len(want)
    assert seen > 1000


def test_bad_band_is_refused():
    f = _frame("experts-tilt-1000")
    with pytest.raises(RasterhwError, match="band"):
        slp_run.run_band(f.setup, f.records, (10, 10))
