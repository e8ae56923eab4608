"""The paper's PXP (span cull + depth search per span) against the per-pixel depth search, and an
independent plain-Python statement of its rule and its operation counts."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts import span
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.screen import ScreenTriangles


@cache
def _frame(name: str, model: str):
    return render_frame(run_geometry(build_scene(name), 512, 512, z_bits=16), model=model)


def _random_tris(seed: int, n: int = 40, W: int = 64, H: int = 24, levels: int = 0) -> ScreenTriangles:
    """Random overlapping, tilted triangles; ``levels`` > 0 puts every z on a coarse grid, so
    faces share depths (ties) and nearly share them (16-bit key ties in the bit model)."""
    rng = np.random.default_rng(seed)
    c = rng.uniform([0, 0], [W, H], (n, 1, 2))
    xy = c + rng.uniform(-W / 3, W / 3, (n, 3, 2))
    z = rng.uniform(0.2, 0.8, (n, 1)) + rng.uniform(-0.1, 0.1, (n, 3))
    if levels:
        z = np.round(z * levels) / levels
    col = np.repeat(rng.uniform(0.2, 1.0, (n, 1, 3)), 3, axis=1)
    return ScreenTriangles(width=W, height=H, xy=xy, z=z, zq=np.rint(z * 65535).astype(np.int64), colour=col,
                           poly_id=np.arange(n))


def _random_bounds(rng, W: int, H: int, P: int) -> np.ndarray:
    cuts = np.sort(rng.integers(0, W + 1, (H, P - 1)), axis=1)
    return np.concatenate([np.zeros((H, 1), np.int64), cuts, np.full((H, 1), W)], axis=1)


@pytest.mark.parametrize("name", ["experts-tilt-1000", "experts-tilt-2000", "experts-1000", "experts-solids",
                                  "experts-uneven"])
@pytest.mark.parametrize("model", ["float", "bit"])
def test_span_pxp_gives_the_per_pixel_search_image(name, model):
    f = _frame(name, model)
    for pn in (1, 8):
        sp = span.span_pxp(f.setup, f.records, f.width, f.height, equal_bounds(f.width, pn))
        assert np.array_equal(sp.win, f.win), (pn, np.count_nonzero(sp.win != f.win))
    if name.startswith("experts-tilt"):
        assert sp.counts["halvings"] > 0        # faces cross inside spans: the halving ran


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("model", ["float", "bit"])
def test_span_pxp_on_random_scenes_ties_and_ranges(seed, model):
    rng = np.random.default_rng(100 + seed)
    tris = _random_tris(seed, levels=8 if seed % 2 else 0)
    f = render_frame(tris, model=model)
    for b in (None, equal_bounds(64, 3), _random_bounds(rng, 64, 24, 5)):
        sp = span.span_pxp(f.setup, f.records, 64, 24, b)
        assert np.array_equal(sp.win, f.win)


def test_tie_rule_lower_asb_address_wins_in_both_orders():
    """Two identical coplanar triangles: the one submitted first (lower ASB address) is visible,
    whichever it is, in the span PXP as in the per-pixel search."""
    xy = np.array([[[2.0, 1.0], [60.0, 3.0], [20.0, 22.0]]] * 2)
    z = np.array([[0.3, 0.5, 0.4]] * 2)
    for order in ((0, 1), (1, 0)):
        col = np.array([[[1.0, 0, 0]] * 3, [[0, 1.0, 0]] * 3])[list(order)]
        tris = ScreenTriangles(width=64, height=24, xy=xy, z=z, zq=np.rint(z * 65535).astype(np.int64),
                               colour=col, poly_id=np.arange(2))
        for model in ("float", "bit"):
            f = render_frame(tris, model=model)
            sp = span.span_pxp(f.setup, f.records, 64, 24)
            vis = sp.win[sp.win >= 0]
            assert vis.size > 100
            assert set(f.records.tri[vis].tolist()) == {0}, (order, model)
            assert np.array_equal(sp.win, f.win)


def test_the_guarded_test_is_what_makes_it_exact(monkeypatch):
    """Accepting the left-end winner for the whole span (no guarded test, no halving) gets the
    crossing faces of the tilted scene wrong: the image check can fail."""
    f = _frame("experts-tilt-1000", "bit")
    monkeypatch.setattr(span, "_stays_nearest", lambda bit, *a: np.ones(np.shape(a[0]), bool))
    sp = span.span_pxp(f.setup, f.records, f.width, f.height)
    assert np.count_nonzero(sp.win != f.win) > 100
    assert sp.counts["halvings"] == 0


def _reference(f, bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plain-Python statement of the span PXP: per line and range, cut, cull, search, halve.
    Returns (win, span cull ops, depth search ops) with ops as (H, P)."""
    st, rec, W, H = f.setup, f.records, f.width, f.height
    P = bounds.shape[1] - 1
    win = np.full(H * W, -1, np.int64)
    cull = np.zeros((H, P), np.int64)
    deep = np.zeros((H, P), np.int64)

    def z(r, c):
        t = rec.tri[r]
        if st.bit:
            zr = (int(rec.zl[r]) << 4) + ((((c << 6) + 32) - int(rec.xl[r])) * int(st.dzdx[t]) >> 6)
            return min(max(zr >> 4, 0), 65535), zr
        v = rec.zl[r] + (c + 0.5 - rec.xl[r]) * st.dzdx[t]
        return v, v

    def stays(s, b, x0, r):
        (_, sl), (_, bl), (_, sr), (_, br) = z(s, x0), z(b, x0), z(s, r), z(b, r)
        if not st.bit:
            return sl <= bl - 1e-9 and sr <= br - 1e-9
        if s < b:
            return sl <= bl and sr <= br
        return sl + 16 <= bl and sr + 16 <= br and bl >= 16 and br >= 16 and max(sl, sr) < 65535 * 16

    for y in range(H):
        segs = [r for r in np.flatnonzero(rec.row == y) if rec.c1[r] >= rec.c0[r]]
        for p in range(P):
            lo, hi = int(bounds[y, p]), int(bounds[y, p + 1])
            if hi <= lo:
                continue
            pieces = [(r, max(int(rec.c0[r]), lo), min(int(rec.c1[r]), hi - 1)) for r in segs]
            pieces = [q for q in pieces if q[1] <= q[2]]
            cull[y, p] += 2 * len(pieces)
            cuts = sorted({lo, hi} | {a for _, a, _ in pieces} | {b + 1 for _, _, b in pieces})
            todo = []
            for x0, nxt in zip(cuts, cuts[1:], strict=False):
                present = [r for r, a, b in pieces if a <= x0 and b >= nxt - 1]
                cull[y, p] += 1 + len(present)
                if len(present) == 1:
                    win[y * W + x0:y * W + nxt] = present[0]
                elif present:
                    todo.append((x0, nxt - 1, present))
            while todo:
                x0, r, present = todo.pop()
                k = len(present)
                s = min(present, key=lambda q, x0=x0: (z(q, x0)[0], q))
                if x0 == r:
                    deep[y, p] += 2 * k - 1
                    win[y * W + x0] = s
                    continue
                deep[y, p] += 5 * k - 3
                if all(b == s or stays(s, b, x0, r) for b in present):
                    win[y * W + x0:y * W + r + 1] = s
                else:
                    m = (x0 + r + 1) >> 1
                    todo += [(x0, m - 1, present), (m, r, present)]
    return win, cull, deep


@pytest.mark.parametrize("seed", range(4))
def test_span_pxp_counts_against_a_plain_python_reference(seed):
    rng = np.random.default_rng(seed)
    for model in ("float", "bit"):
        f = render_frame(_random_tris(10 + seed, levels=16 if seed % 2 else 0), model=model)
        b = _random_bounds(rng, 64, 24, 4)
        sp = span.span_pxp(f.setup, f.records, 64, 24, b)
        win, cull, deep = _reference(f, b)
        assert np.array_equal(sp.win, win)
        assert np.array_equal(sp.ops["span_cull"], cull)
        assert np.array_equal(sp.ops["depth_search"], deep)
        assert sp.ops["depth_search"].sum() > 0


def test_span_work_depends_on_depth_order():
    """experts-1000 and experts-tilt-1000 share their screen triangles (the tilt only lifts
    vertices along their eye rays): the span PXP's work differs, by the halvings at crossings."""
    flat, tilt = _frame("experts-1000", "bit"), _frame("experts-tilt-1000", "bit")
    a = span.span_pxp(flat.setup, flat.records, 512, 512, equal_bounds(512, 8))
    b = span.span_pxp(tilt.setup, tilt.records, 512, 512, equal_bounds(512, 8))
    assert a.counts["halvings"] == 0 and b.counts["halvings"] > 1000
    assert b.ops["depth_search"].sum() > a.ops["depth_search"].sum()
    assert not np.array_equal(span.span_cycles(flat, a), span.span_cycles(tilt, b))


def test_span_cycles_are_the_counted_operations_plus_the_token():
    f = _frame("experts-tilt-1000", "bit")
    sp = span.span_pxp(f.setup, f.records, 512, 512, equal_bounds(512, 4))
    cyc = span.span_cycles(f, sp)
    from rasterhw.golden_model.experts.model import pxp_range_ops
    rest = pxp_range_ops(f, equal_bounds(512, 4), ("smooth_shading", "dslb"))
    assert cyc.shape == (512, 4)
    assert np.array_equal(cyc - 1 - rest, sum(sp.ops[s] for s in span.SPAN_STAGES))
    other = _frame("experts-tilt-2000", "bit")
    with pytest.raises(RasterhwError, match="disagree"):
        span.span_cycles(other, sp)


@pytest.mark.parametrize("bounds", [[1, 512], [0, 300, 200, 512], [0, 511], [[0, 512]] * 3, [7]])
def test_bad_range_bounds_are_refused(bounds):
    f = _frame("experts-solids", "bit")
    with pytest.raises(RasterhwError, match="bounds"):
        span.span_pxp(f.setup, f.records, 512, 512, bounds)
