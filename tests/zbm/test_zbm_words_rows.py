"""ZB/M words as packed rows (issue 51: no Python int per word on a warm ``sim zbm``): the vectorised
``edge_pair_rows`` and ``merge_rows`` equal their specifications ``edge_pair_words`` and
``merge_words`` word for word, bad values raise the specification's error, and ``compare`` counts
packed rows as it counts ints."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.words import (
    edge_pair_rows,
    edge_pair_words,
    merge_rows,
    merge_words,
    rows_to_samples,
)
from rasterhw.sim.packed import as_ints
from rasterhw.sim.testbench import Expected, Run, compare


@pytest.mark.parametrize("mode", [F.MODE_COLOUR, F.MODE_MAPPING])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_edge_pair_rows_equal_the_words(mode, seed):
    tris = ref.random_triangles(64, 48, 30, mean_area=120, seed=seed)
    if mode == F.MODE_MAPPING:
        tris.uv = np.random.default_rng(seed).random((tris.n_triangles, 3, 2))
    eps = G.edge_pairs(tris, mode=mode)
    rows = edge_pair_rows(eps)
    assert rows.dtype == np.uint8 and rows.shape == (F.EP_WORDS * len(eps) + 1, F.EP_WORD_BITS // 8)
    assert as_ints(rows) == edge_pair_words(eps)
    # the extremes of every slot (signed 56 bits) and of the header fields
    lo, hi = -(1 << (F.SLOT_BITS - 1)), (1 << (F.SLOT_BITS - 1)) - 1
    for name, v in (("x", hi), ("dxdy", lo), ("len", hi), ("dlendy", -1)):
        getattr(eps, name)[0] = v
    eps.val[1], eps.ddy[1], eps.ddx[1] = lo, hi, -1
    eps.y[2], eps.h[2] = (1 << 9) - 1, (1 << 10) - 1
    assert as_ints(edge_pair_rows(eps)) == edge_pair_words(eps)
    empty = eps.take(np.arange(0))
    assert as_ints(edge_pair_rows(empty)) == edge_pair_words(empty) == [0]


@pytest.mark.parametrize("field,value", [("ddx", 1 << 55), ("val", -(1 << 55) - 1), ("h", 1 << 10), ("y", -1)])
def test_edge_pair_rows_refuse_what_the_words_refuse(field, value):
    eps = G.edge_pairs(ref.random_triangles(32, 32, 4, mean_area=60, seed=5))
    arr = getattr(eps, field)
    arr[(0, 0) if arr.ndim == 2 else 0] = value
    with pytest.raises(RasterhwError) as want:
        edge_pair_words(eps)
    with pytest.raises(RasterhwError) as got:
        edge_pair_rows(eps)
    assert str(got.value) == str(want.value)


def test_merge_rows_equal_the_words_and_split_back():
    rng = np.random.default_rng(7)
    s0 = rng.integers(0, 1 << 63, (5, 12), dtype=np.int64).astype(np.uint64) * np.uint64(2) + np.uint64(1)
    s1 = ~s0
    rows = merge_rows(s0[:, 1::3], s1[:, 1::3])
    assert rows.shape == (20, 16) and as_ints(rows) == merge_words(s0[:, 1::3], s1[:, 1::3])
    a, b = rows_to_samples(rows)
    assert np.array_equal(a, s0[:, 1::3].ravel()) and np.array_equal(b, s1[:, 1::3].ravel())


def test_compare_counts_packed_rows_as_it_counts_ints():
    rng = np.random.default_rng(3)
    rows = rng.integers(0, 256, (40, 16), dtype=np.uint8)
    ints = as_ints(rows)
    bad = rows.copy()
    bad[[2, 17], [15, 0]] ^= 1            # two words, one bit each (the lowest and the highest byte)
    short = rows[:37]
    for want in (rows, ints):
        assert compare(Expected({"o": want}), Run("x", {"o": rows}, {}))["mismatches"] == 0
        assert compare(Expected({"o": want}), Run("x", {"o": as_ints(rows)}, {}))["mismatches"] == 0
        assert compare(Expected({"o": want}), Run("x", {"o": bad}, {}))["mismatches"] == 2
        assert compare(Expected({"o": want}), Run("x", {"o": as_ints(bad)}, {}))["mismatches"] == 2
        assert compare(Expected({"o": want}), Run("x", {"o": short}, {}))["mismatches"] == 3
        assert compare(Expected({"o": want}), Run("x", {}, {}))["mismatches"] == 40


def test_given_segments_give_the_same_frames():
    """``chain_frame(..., segments=)`` and ``render_zbm_float(..., segs=)`` (a one-unit scene run
    generates the segments once for both) equal what they compute themselves; a segment list per
    unit is required."""
    tris = ref.random_triangles(48, 40, 25, mean_area=90, seed=9)
    eps = G.edge_pairs(tris)
    segs = G.segment_generator(eps, 40, width=48)
    a, b = G.chain_frame([eps], 48, 40), G.chain_frame([eps], 48, 40, segments=[segs])
    assert all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("z", "a", "c", "tag"))
    fa, fb = G.render_zbm_float(tris), G.render_zbm_float(tris, segs=segs)
    assert all(np.array_equal(fa[k], fb[k]) for k in ("rgb", "z", "tag"))
    with pytest.raises(RasterhwError, match="segment lists"):
        G.chain_frame([eps, eps], 48, 40, segments=[segs])
