"""Recursive pixel search on sparse rasters against the reference rasteriser and brute force."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import random_triangles, rasterise
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.screen import snap
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave, sparse_render

_CACHE: dict = {}


def _scene(name: str):
    if name not in _CACHE:
        tris = run_geometry(build_scene(name), 512, 512)
        _CACHE[name] = (tris, rasterise(tris))
    return _CACHE[name]


@pytest.mark.parametrize("matrix", ["2x2", "4x4", "8x8"])
@pytest.mark.parametrize("scene", ["c300", "sp27", "sp8"])
def test_union_equals_reference_one_processor_per_pixel(scene, matrix):
    tris, ref = _scene(scene)
    f = sparse_render(tris, matrix)
    p, q = parse_matrix(matrix)
    # coverage and the visible polygon, depth and colour bit for bit, serial Z-buffer writes
    assert np.array_equal(f.tri_id, ref.tri_id)
    assert np.array_equal(f.depth, ref.depth)
    assert np.array_equal(f.to_rgb8(), ref.to_rgb8())
    assert f.fragments == ref.fragments
    assert f.pixels_written == ref.pixels_written
    # every covered pixel written by exactly processor (x mod p, y mod q), nobody else
    yy, xx = np.mgrid[0:512, 0:512]
    owner = (yy % q) * p + (xx % p)
    covered = ref.tri_id >= 0
    assert np.array_equal(f.writer[covered], owner[covered])
    assert (f.writer[~covered] == -1).all()
    fx, fy, fp, ft = (f.stats[k] for k in ("frag_x", "frag_y", "frag_proc", "frag_tri"))
    assert np.array_equal(fp, (fy % q) * p + fx % p)
    key = (ft * 512 + fy) * 512 + fx
    assert np.unique(key).size == key.size  # no pixel of a triangle found twice
    # level bookkeeping: four tests per window entering a level
    assert f.windows[-1] == f.fragments
    assert np.array_equal(f.tests[1:], 4 * f.windows[:-1])
    assert np.array_equal(f.windows_per_proc.sum(axis=0), f.windows)
    assert f.windows[0] == f.triangles * p * q


def _brute_counts(xy, W, H, p, q, alpha, beta, test):
    """Windows per level passing the test, by evaluating every window of every processor at its
    four corners straight from the vertices (no increments, float64); ``exact`` adds the
    triangle's bounding box."""
    n = sparse_geometry(W, H, p, q)
    sub = 256.0
    counts = np.zeros(n + 1, dtype=np.int64)
    for t in range(xy.shape[0]):
        X, Y = snap(xy[t, :, 0]), snap(xy[t, :, 1])
        area = (X[2] - X[1]) * (Y[0] - Y[1]) - (Y[2] - Y[1]) * (X[0] - X[1])
        if area == 0:
            continue
        s = np.sign(area)
        edges = []
        for i0, i1 in ((1, 2), (2, 0), (0, 1)):
            dx, dy = X[i1] - X[i0], Y[i1] - Y[i0]
            tl = (s * dy < 0) or (s * dy == 0 and s * dx > 0)
            edges.append((X[i0], Y[i0], dx, dy, 0 if tl else 1))

        def E(e, px, py, s=s):
            xa, ya, dx, dy, _ = e
            return s * (dx * (py - ya) - dy * (px - xa))

        counts[0] += p * q
        for a in range(p):
            for b in range(q):
                for i in range(1, n + 1):
                    N = 1 << (n - i)
                    j = np.arange(1 << i)
                    gx, gy = np.meshgrid(j, j, indexing="xy")
                    if i < n:  # window rectangle in sub-pixel units: sample span plus aperture
                        x0 = (p * gx * N + a + 0.5 - alpha / 2) * sub
                        x1 = (p * (gx * N + N - 1) + a + 0.5 + alpha / 2) * sub
                        y0 = (q * gy * N + b + 0.5 - beta / 2) * sub
                        y1 = (q * (gy * N + N - 1) + b + 0.5 + beta / 2) * sub
                        ok = np.ones(gx.shape, dtype=bool)
                        for e in edges:
                            m = np.maximum.reduce([E(e, x0, y0), E(e, x1, y0), E(e, x0, y1), E(e, x1, y1)])
                            ok &= m >= e[4]
                        if test == "exact":
                            ok &= (x1 >= X.min()) & (x0 <= X.max()) & (y1 >= Y.min()) & (y0 <= Y.max())
                    else:  # pixel centres
                        cx, cy = (p * gx + a + 0.5) * sub, (q * gy + b + 0.5) * sub
                        ok = np.ones(gx.shape, dtype=bool)
                        for e in edges:
                            ok &= E(e, cx, cy) >= e[4]
                    counts[i] += int(ok.sum())
    return counts


@pytest.mark.parametrize("test", ["exact", "edges"])
@pytest.mark.parametrize("matrix,size,alpha", [("2x2", (16, 16), 2), ("4x2", (32, 16), 1), ("1x1", (8, 8), 2),
                                               ("4x4", (32, 32), 0)])
def test_window_counts_match_brute_force(matrix, size, alpha, test):
    W, H = size
    tris = random_triangles(W, H, 25, mean_area=12.0, seed=11)
    p, q = parse_matrix(matrix)
    f = sparse_render(tris, matrix, alpha=alpha, beta=alpha, test=test)
    assert np.array_equal(f.windows, _brute_counts(np.asarray(tris.xy), W, H, p, q, alpha, alpha, test))


def test_exact_test_never_counts_more_than_edges_only():
    tris = random_triangles(128, 128, 200, mean_area=30.0, seed=3)
    fe = sparse_render(tris, "4x4", test="exact")
    fo = sparse_render(tris, "4x4", test="edges")
    assert np.all(fe.windows <= fo.windows) and fe.windows[2:-1].sum() < fo.windows[2:-1].sum()
    assert np.array_equal(fe.tri_id, fo.tri_id)


def test_aperture_does_not_change_the_image():
    tris = random_triangles(64, 64, 60, mean_area=40.0, seed=5)
    ref = rasterise(tris)
    for al in (0, 1, 2, 5):
        f = sparse_render(tris, "4x4", alpha=al, beta=al)
        assert np.array_equal(f.tri_id, ref.tri_id)


def test_interleave_is_the_video_controller_map():
    local = np.arange(2 * 4 * 3 * 3).reshape(2, 4, 3, 3)  # q=2, p=4, N=3
    full = interleave(local)
    for y in range(6):
        for x in range(12):
            assert full[y, x] == local[y % 2, x % 4, y // 2, x // 4]


def test_fixed_point_depth_within_tolerance():
    tris, ref = _scene("sp27")
    f = sparse_render(tris, "4x4", depth="fixed")
    assert np.array_equal(f.tri_id >= 0, ref.tri_id >= 0)  # coverage is exact in both layers
    assert np.count_nonzero(f.tri_id != ref.tri_id) <= 10  # depth near-ties only


@pytest.mark.parametrize("matrix", ["3x3", "0x4", "4x0", "4", "4x4x4", "axb", (4, 6), (2.0, 2), "128x128"])
def test_bad_matrix(matrix):
    tris = random_triangles(64, 64, 3, seed=1)
    with pytest.raises(RasterhwError):
        sparse_render(tris, matrix)


@pytest.mark.parametrize("size,matrix", [((510, 510), "4x4"),   # does not divide
                                         ((512, 256), "4x4"),   # non-square sparse raster
                                         ((384, 384), "4x4"),   # 96: not a power of two
                                         ((4, 4), "4x4"),       # n = 0
                                         ((2, 2), "2x2")])
def test_bad_raster(size, matrix):
    tris = random_triangles(*size, 3, mean_area=2.0, seed=1)
    with pytest.raises(RasterhwError):
        sparse_render(tris, matrix)


def test_bad_options():
    tris = random_triangles(64, 64, 3, seed=1)
    with pytest.raises(RasterhwError):
        sparse_render(tris, "4x4", alpha=-1)
    with pytest.raises(RasterhwError):
        sparse_render(tris, "4x4", depth="double")
    with pytest.raises(RasterhwError):
        sparse_render(tris, "4x4", test="bbox")


def test_non_square_matrix_on_matching_raster():
    tris = random_triangles(256, 128, 80, mean_area=60.0, seed=2)
    f = sparse_render(tris, "4x2")
    assert f.n == 6
    assert np.array_equal(f.tri_id, rasterise(tris).tri_id)


def test_a_big_search_shows_a_bar_on_a_terminal_and_nothing_in_a_pipe(monkeypatch, capsys):
    """Issue 33 (low): a 64x64 matrix ran a minute in silence. Past BIG_RECORDS root records the
    search draws a bar per level on a terminal; logs and pipes get nothing."""
    import sys

    from rasterhw.golden_model.sparse import search

    tris = random_triangles(64, 64, 20, mean_area=60.0, seed=3)
    monkeypatch.setattr(search, "BIG_RECORDS", 1)
    search.sparse_render(tris, "2x2")
    assert "records, level" not in capsys.readouterr().err          # not a terminal: silent
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    search.sparse_render(tris, "2x2")
    err = capsys.readouterr().err
    assert "sparse 2x2" in err and "records, level" in err
