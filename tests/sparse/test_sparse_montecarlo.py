"""Monte-Carlo window counts against brute force, integral geometry and formula (1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse import montecarlo as mc
from rasterhw.golden_model.sparse import theory as th


def _brute(poly, Px, Py, hx, hy, test):
    """Lattice windows passing the test for each polygon, by projecting the window corners on
    every axis. ``exact``: separating axes (edge normals and x, y; both sides of each).
    ``edges``: a window is rejected only when it lies wholly outside one edge."""
    out = []
    corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    for P in poly:
        e = np.roll(P, -1, 0) - P
        nrm = np.stack([e[:, 1], -e[:, 0]], 1)
        span = max(hx, hy) * 100 + Px + Py  # sliver spikes of the edges-only region reach far
        js = np.arange(math.floor((P[:, 0].min() - span) / Px), math.ceil((P[:, 0].max() + span) / Px) + 1)
        ls = np.arange(math.floor((P[:, 1].min() - span) / Py), math.ceil((P[:, 1].max() + span) / Py) + 1)
        cx, cy = np.meshgrid(js * Px, ls * Py)
        c = np.stack([cx.ravel(), cy.ravel()], 1)  # (C, 2)
        R = c[:, None, :] + corners[None]  # (C, 4, 2)
        ok = np.ones(c.shape[0], dtype=bool)
        for k in range(P.shape[0]):
            rr = R @ nrm[k]
            pp = P @ nrm[k]
            ok &= ~(rr.min(1) > pp.max())  # wholly outside edge k
            if test == "exact":
                ok &= ~(rr.max(1) < pp.min())
        if test == "exact":
            for ax in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
                rr, pp = R @ ax, P @ ax
                ok &= ~((rr.min(1) > pp.max()) | (rr.max(1) < pp.min()))
        out.append(int(ok.sum()))
    return np.array(out)


@pytest.mark.parametrize("test", ["exact", "edges"])
def test_counts_match_brute_force(test):
    poly, off = mc.rectangles(7.0, 40, seed=3)
    tri, toff = mc.triangles_from_scene(np.asarray(random_triangles(64, 64, 30, mean_area=10.0, seed=4).xy), 40, seed=5)
    for P, o in ((poly, off), (tri, toff)):
        placed = P + o[:, None, :] * 8.0
        for Px, Py, hx, hy in ((4.0, 4.0, 1.0, 1.0), (8.0, 4.0, 3.5, 2.5), (2.0, 2.0, 0.5, 0.5)):
            got = mc.count_windows(placed, Px, Py, hx, hy, test=test)
            assert np.array_equal(got, _brute(placed, Px, Py, hx, hy, test))


def test_exact_mean_is_the_filtered_area():
    # integral geometry: a convex body of area S and perimeter U at uniform rotation meets
    # (S + (a + b) U / pi + a b) / (Px Py) windows of a x b on average
    S, M = 40.0, 4000
    poly, off = mc.rectangles(S, M, seed=7)
    U = 2 * (math.sqrt(5 * S) + math.sqrt(S / 5))
    r = mc.level_counts(poly, off, 6, 4, test="exact")
    for i in range(1, 7):
        Px, Py, hx, hy = mc.level_geometry(i, 6, 4, 4, 2.0, 2.0)
        a, b = 2 * hx, 2 * hy
        expect = (S + (a + b) * U / math.pi + a * b) / (Px * Py)
        assert abs(r.mean[i] - expect) <= 1.5 * r.half95[i] + 1e-9


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_measured_at_or_below_formula_for_the_paper_shapes(k):
    p, n = 1 << k, 10 - k
    for S in (1.0, 25.0, 400.0):
        poly, off = mc.rectangles(S, 1500, seed=k)
        r = mc.level_counts(poly, off, n, p, test="exact")
        f = th.windows(S, n, p)
        assert np.all(r.lo[1:] <= f[1:] * 1.01)  # small sample here: the interval's low end


def test_edges_only_counts_at_least_exact():
    poly, off = mc.rectangles(30.0, 500, seed=2)
    for i in (1, 3, 5):
        g = mc.level_geometry(i, 6, 4, 4, 2.0, 2.0)
        placed = poly + off[:, None, :] * 128
        assert np.all(mc.count_windows(placed, *g, test="edges") >= mc.count_windows(placed, *g, test="exact"))


def test_real_triangles_at_or_below_formula():
    xy = np.asarray(random_triangles(512, 512, 300, mean_area=80.0, seed=9).xy)
    tri, off = mc.triangles_from_scene(xy, 2000, seed=1)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    S = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    U = np.linalg.norm(tri - np.roll(tri, -1, 1), axis=2).sum(1)
    L = U / (2 * np.sqrt(math.pi * S))
    n, p = 7, 4
    formula = np.mean([th.windows(s, n, p, L=ell) for s, ell in zip(S, L, strict=True)], axis=0)
    r = mc.level_counts(tri, off, n, p, test="exact")
    assert np.all(r.lo[1:] <= formula[1:] * 1.01)


def test_s_k_measured_matches_integral_geometry():
    # w_n = (S + 4 alpha L sqrt(S / pi) + alpha^2) / 4^k for random rotations: solve for k = 3
    L, al, k = th.L_RECT_5_1, 2.0, 3
    b = 4 * al * L / math.sqrt(math.pi)
    x = (-b + math.sqrt(b * b + 4 * (4.0 ** k - al * al))) / 2
    S, lo, hi = mc.s_k_measured(k, M=3000, seed=4)
    assert lo <= x * x <= hi
    assert S > th.s_k(k)  # the formula is an upper bound on w, so its S_k is lower
    assert mc.s_k_measured(1, M=500)[0] == 0.0


def test_bad_input():
    poly, _ = mc.rectangles(3.0, 4, seed=0)
    with pytest.raises(RasterhwError):
        mc.count_windows(poly, 2.0, 2.0, 1.0, 1.0, test="bbox")
    with pytest.raises(RasterhwError):
        mc.level_counts(poly[:1], np.zeros((1, 2)), 4, 2)
    with pytest.raises(RasterhwError):
        mc.triangles_from_scene(np.zeros((3, 3, 2)), 5)
