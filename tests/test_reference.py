"""The float reference rasteriser against the brute-force check, plus the fill rule, Gouraud
colour, determinism and the image-compare helpers."""

from __future__ import annotations

import numpy as np
import pytest
from brute import brute_coverage, brute_visible
from rasterhw.golden_model import reference
from rasterhw.golden_model.compare import compare_images, diff_image, write_diff_png
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import Frame, benchmark, random_triangles, rasterise
from rasterhw.golden_model.screen import ScreenTriangles

W, H = 32, 24


@pytest.fixture(params=["numpy", "numba"])
def engine(request, monkeypatch):
    """Run the test on the NumPy specification and on the numba fast path (RASTERHW_REFERENCE)."""
    if request.param == "numba":
        pytest.importorskip("numba")
    monkeypatch.setenv(reference.ENGINE_ENV, request.param)
    assert reference.choose_engine() == request.param
    return request.param


@pytest.fixture
def numpy_engine(monkeypatch):
    """The NumPy code's own internals (chunks, the pool) are under test: force that engine."""
    monkeypatch.setenv(reference.ENGINE_ENV, "numpy")


def make_tris(xy, z=None, colour=None, *, width=W, height=H) -> ScreenTriangles:
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 3, 2)
    t = xy.shape[0]
    if z is None:
        z = np.full((t, 3), 0.5)
    if colour is None:
        colour = np.full((t, 3, 3), 0.5)
    z = np.asarray(z, dtype=np.float64).reshape(t, 3)
    zq = np.rint(z * ((1 << 24) - 1)).astype(np.int64)
    return ScreenTriangles(width=width, height=height, xy=xy, z=z, zq=zq,
                           colour=np.asarray(colour, dtype=np.float64).reshape(t, 3, 3),
                           poly_id=np.arange(t, dtype=np.int64) + 100)


def random_scene(seed: int) -> ScreenTriangles:
    """20-60 triangles on a 32x24 frame built to hit the fill rule's ties: vertices on pixel
    centres, on pixel corners and anywhere (some off screen), shared by several triangles;
    triangles that share an edge (on either side of it), exact duplicates, zero-area ones."""
    rng = np.random.default_rng(seed)
    nv = 40
    kind = rng.integers(0, 3, nv)
    pts = rng.random((nv, 2)) * [W + 8, H + 8] - 4
    grid = np.stack([rng.integers(-2, W + 2, nv), rng.integers(-2, H + 2, nv)], axis=1).astype(float)
    pts = np.where(kind[:, None] == 0, grid + 0.5, np.where(kind[:, None] == 1, grid, pts))
    vz = rng.random(nv)  # a shared vertex has one depth
    vcol = rng.random((nv, 3))
    idx = []
    for _ in range(int(rng.integers(20, 61))):
        r = rng.random()
        if idx and r < 0.3:  # share an edge with an earlier triangle
            a, b, _c = idx[int(rng.integers(len(idx)))]
            idx.append((b, a, int(rng.integers(nv))))
        elif idx and r < 0.35:  # exact duplicate: a depth tie everywhere
            idx.append(idx[int(rng.integers(len(idx)))])
        elif r < 0.42:  # zero area: a repeated vertex
            a, b = (int(v) for v in rng.integers(nv, size=2))
            idx.append((a, b, a))
        else:
            idx.append(tuple(int(v) for v in rng.choice(nv, 3, replace=False)))
    idx = np.array(idx)
    xy = pts[idx]
    # Zero area without a repeated vertex: three collinear pixel centres.
    xy[-1] = [[3.5, 4.5], [7.5, 8.5], [11.5, 12.5]]
    return make_tris(xy, vz[idx], vcol[idx])


def cover_each(tris: ScreenTriangles) -> np.ndarray:
    """(T, H, W) coverage by the reference, one triangle at a time."""
    out = np.zeros((tris.n_triangles, tris.height, tris.width), dtype=bool)
    for t in range(tris.n_triangles):
        one = make_tris(tris.xy[t:t + 1], width=tris.width, height=tris.height)
        out[t] = rasterise(one).tri_id >= 0
    return out


@pytest.mark.parametrize("seed", range(6))
def test_matches_brute_force(seed, engine):
    tris = random_scene(seed)
    frame = rasterise(tris)
    cov = brute_coverage(tris)
    assert cov.any(), "scene covers nothing: the test would prove nothing"
    np.testing.assert_array_equal(cover_each(tris), cov)
    tri_id, depth, written = brute_visible(tris)
    np.testing.assert_array_equal(frame.tri_id, tri_id)
    np.testing.assert_array_equal(frame.depth, depth)
    assert frame.fragments == int(cov.sum())
    assert frame.pixels_written == written
    assert frame.pixels_covered == int((tri_id >= 0).sum())
    assert frame.pixels_covered <= frame.pixels_written <= frame.fragments
    np.testing.assert_array_equal(frame.poly_id, np.where(tri_id >= 0, tri_id + 100, -1))


@pytest.mark.parametrize("threads", [2, 3])
def test_row_bands_in_threads_equal_one_band(threads, monkeypatch, engine):
    """Frames rendered as row bands in threads: bit for bit the one-band frame and counts, and
    the brute-force answer (bands forced on small frames here; by default from 256 x 256)."""
    tris = random_triangles(256, 256, 900, mean_area=90, seed=7)
    assert len(reference._bands(256, 256, tris.n_triangles)) == reference.THREADS   # the default path
    monkeypatch.setattr(reference, "THREADS", 1)
    one = rasterise(tris)
    monkeypatch.setattr(reference, "THREADS", threads)
    monkeypatch.setattr(reference, "_exec", None)   # a pool of this size
    banded = rasterise(tris)
    assert len(reference._bands(256, 256, tris.n_triangles)) == threads
    for name in ("colour", "depth", "tri_id", "poly_id"):
        np.testing.assert_array_equal(getattr(one, name), getattr(banded, name))
    assert (one.fragments, one.pixels_written, one.pixels_covered) == \
        (banded.fragments, banded.pixels_written, banded.pixels_covered)
    monkeypatch.setattr(reference, "THREAD_MIN_PIXELS", 1)
    monkeypatch.setattr(reference, "THREAD_MIN_TRIANGLES", 1)
    for seed in range(3):
        tris = random_scene(seed)
        frame = rasterise(tris)
        tri_id, depth, written = brute_visible(tris)
        np.testing.assert_array_equal(frame.tri_id, tri_id)
        np.testing.assert_array_equal(frame.depth, depth)
        assert frame.pixels_written == written
    monkeypatch.setattr(reference, "_exec", None)


def test_horizontal_edges_match_brute_force(engine):
    """Horizontal top and bottom edges, on pixel centres and off them, in both windings: a
    horizontal edge admits a whole row or none of it, whatever the sign of its zero slope."""
    rng = np.random.default_rng(5)
    xy = []
    for _ in range(60):
        y = int(rng.integers(1, H - 1)) + float(rng.choice([0.5, 0.0, 0.3]))
        xa, xb = sorted(rng.random(2) * (W + 4) - 2)
        tri = [[xa, y], [xb, y], [rng.random() * (W + 4) - 2, rng.random() * (H + 4) - 2]]
        xy.append(tri[::-1] if rng.random() < 0.5 else tri)
    tris = make_tris(xy, rng.random((60, 3)))
    cov = brute_coverage(tris)
    assert cov.sum() > 500
    np.testing.assert_array_equal(cover_each(tris), cov)
    tri_id, depth, written = brute_visible(tris)
    frame = rasterise(tris)
    np.testing.assert_array_equal(frame.tri_id, tri_id)
    np.testing.assert_array_equal(frame.depth, depth)
    assert frame.pixels_written == written


def test_random_scenes_hit_the_ties():
    """The generator really produces on-edge centres, shared edges and zero-area triangles."""
    tris = random_scene(1)
    xy = reference.snap(tris.xy)
    area = ((xy[:, 1, 0] - xy[:, 0, 0]) * (xy[:, 2, 1] - xy[:, 0, 1])
            - (xy[:, 1, 1] - xy[:, 0, 1]) * (xy[:, 2, 0] - xy[:, 0, 0]))
    assert (area == 0).sum() >= 2
    on_centre = (xy % 256 == 128).all(axis=2)
    assert on_centre.sum() >= 10


def test_chunked_equals_unchunked(monkeypatch, numpy_engine):
    tris = random_triangles(96, 64, 300, mean_area=60, seed=3)
    whole = rasterise(tris)
    monkeypatch.setattr(reference, "CHUNK_CANDIDATES", 200)
    parts = rasterise(tris)
    for name in ("colour", "depth", "tri_id", "poly_id"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(parts, name))
    assert (whole.fragments, whole.pixels_written) == (parts.fragments, parts.pixels_written)


def test_later_calls_do_not_touch_earlier_frames(monkeypatch, engine):
    """Scratch memory is reused between calls; returned frames must not be part of it."""
    a_tris = random_triangles(96, 64, 300, mean_area=60, seed=3)
    a = rasterise(a_tris)
    keep = {name: getattr(a, name).copy() for name in ("colour", "depth", "tri_id", "poly_id")}
    rasterise(random_triangles(96, 64, 300, mean_area=60, seed=4), background=(0.1, 0.2, 0.3))
    monkeypatch.setattr(reference, "CHUNK_CANDIDATES", 16)  # chunks bigger than the pool
    small = rasterise(a_tris)
    rasterise(random_triangles(512, 512, 1800, seed=1))  # a frame with huge-page outputs
    for name, arr in keep.items():
        np.testing.assert_array_equal(getattr(a, name), arr)
        np.testing.assert_array_equal(getattr(small, name), arr)


def test_quad_split_covers_each_pixel_once(engine):
    # Corners on pixel centres: the top and left sides are in, the bottom and right out.
    x0, y0, x1, y1 = 2.5, 3.5, 10.5, 9.5
    for diag in (0, 1):
        if diag == 0:
            xy = [[x0, y0], [x1, y0], [x1, y1], [x0, y0], [x1, y1], [x0, y1]]
        else:
            xy = [[x0, y0], [x1, y0], [x0, y1], [x1, y0], [x1, y1], [x0, y1]]
        cov = cover_each(make_tris(xy)).sum(axis=0)
        expect = np.zeros((H, W), dtype=int)
        expect[3:9, 2:10] = 1
        np.testing.assert_array_equal(cov, expect)


def test_jittered_mesh_covers_whole_frame_exactly_once(engine):
    rng = np.random.default_rng(7)
    nx, ny = 9, 7
    gx, gy = np.meshgrid(np.linspace(-2, W + 2, nx), np.linspace(-2, H + 2, ny))
    pts = np.stack([gx, gy], axis=-1)
    inner = (slice(1, -1), slice(1, -1))
    # Inner vertices: half on pixel centres, half anywhere.
    jit = rng.random(pts[inner].shape) * 3 - 1.5
    snapped = np.floor(pts[inner] + jit) + 0.5
    pts[inner] = np.where(rng.random(pts[inner].shape[:-1] + (1,)) < 0.5, snapped, pts[inner] + jit)
    tri = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = pts[j, i], pts[j, i + 1], pts[j + 1, i + 1], pts[j + 1, i]
            if (i + j) % 2:
                tri += [[a, b, c], [a, c, d]]
            else:
                tri += [[a, b, d], [b, c, d]]
    tris = make_tris(np.array(tri))
    cov = cover_each(tris).sum(axis=0)
    np.testing.assert_array_equal(cov, np.ones((H, W), dtype=int))
    frame = rasterise(tris)
    assert frame.fragments == frame.pixels_covered == W * H


def test_fan_has_no_gaps_or_double_cover(engine):
    cx, cy = 15.5, 11.5  # fan centre on a pixel centre
    ang = np.linspace(0, 2 * np.pi, 13)[:-1] + 0.1
    rim = np.stack([cx + 9 * np.cos(ang), cy + 9 * np.sin(ang)], axis=1)
    rim = np.floor(rim) + 0.5  # rim vertices on pixel centres too
    xy = [[[cx, cy], rim[i], rim[(i + 1) % len(rim)]] for i in range(len(rim))]
    cov = cover_each(make_tris(xy)).sum(axis=0)
    assert cov.max() == 1
    # Every centre strictly inside the (convex) rim polygon is covered.
    cols, rows = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    inside = np.ones((H, W), dtype=bool)
    for i in range(len(rim)):
        (ax, ay), (bx, by) = rim[i], rim[(i + 1) % len(rim)]
        inside &= (bx - ax) * (rows - ay) - (by - ay) * (cols - ax) > 0
    assert inside.sum() > 100
    assert np.all(cov[inside] == 1)


def test_winding_does_not_matter_and_ties_go_to_the_first(engine):
    xy = np.array([[[4.5, 2.5], [20.0, 6.3], [7.1, 19.5]]])
    fwd = rasterise(make_tris(xy))
    rev = rasterise(make_tris(xy[:, ::-1]))
    np.testing.assert_array_equal(fwd.tri_id >= 0, rev.tri_id >= 0)
    # An exact duplicate is an exact depth tie at every pixel. (The reversed copy is not: its
    # weights are summed in another order, so its depth may differ in the last bit.)
    both = rasterise(make_tris(np.concatenate([xy, xy]), colour=[[[1, 0, 0]] * 3, [[0, 1, 0]] * 3]))
    assert set(np.unique(both.tri_id)) == {-1, 0}
    assert both.pixels_written == both.pixels_covered  # the second copy never passes the strict test
    assert both.fragments == 2 * both.pixels_covered


def test_nearer_triangle_wins_whatever_the_order(engine):
    big = [[0, 0], [40, 0], [0, 40]]
    for order in ((0.2, 0.8), (0.8, 0.2)):
        f = rasterise(make_tris([big, big], z=[[order[0]] * 3, [order[1]] * 3]))
        winner = int(np.argmin(order))
        assert set(np.unique(f.tri_id)) - {-1} == {winner}
        assert f.pixels_written == (f.pixels_covered if winner == 0 else 2 * f.pixels_covered)


def test_gouraud_colour_at_vertices_and_inside(engine):
    xy = [[5.5, 5.5], [25.5, 5.5], [5.5, 20.5]]  # v0 is on a top and a left edge: covered
    col = [[0.1, 0.7, 0.3], [0.9, 0.2, 0.4], [0.25, 0.5, 1.0]]
    z = [0.3, 0.6, 0.9]
    f = rasterise(make_tris(xy, z=z, colour=col))
    assert f.tri_id[5, 5] == 0
    np.testing.assert_array_equal(f.colour[5, 5], col[0])
    assert f.depth[5, 5] == z[0]
    assert f.tri_id[5, 25] == -1 and f.tri_id[20, 5] == -1  # on right / bottom edges
    # Inside: the linear interpolation of the vertex colours.
    px, py = 10.5, 9.5
    w1 = (px - 5.5) / 20.0
    w2 = (py - 5.5) / 15.0
    expect = (1 - w1 - w2) * np.array(col[0]) + w1 * np.array(col[1]) + w2 * np.array(col[2])
    np.testing.assert_allclose(f.colour[9, 10], expect, rtol=0, atol=1e-12)
    assert f.depth[9, 10] == pytest.approx((1 - w1 - w2) * 0.3 + w1 * 0.6 + w2 * 0.9, abs=1e-12)
    # Background where empty.
    g = rasterise(make_tris(xy, colour=col), background=(0.2, 0.4, 0.6))
    np.testing.assert_array_equal(g.colour[0, 0], [0.2, 0.4, 0.6])
    assert g.depth[0, 0] == np.inf and g.tri_id[0, 0] == -1 and g.poly_id[0, 0] == -1


def test_deterministic_bytes(engine):
    a = rasterise(random_triangles(64, 48, 120, mean_area=40, seed=11))
    b = rasterise(random_triangles(64, 48, 120, mean_area=40, seed=11))
    for name in ("colour", "depth", "tri_id", "poly_id"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes()
    assert a.to_rgb8().tobytes() == b.to_rgb8().tobytes()
    c = rasterise(random_triangles(64, 48, 120, mean_area=40, seed=12))
    assert a.to_rgb8().tobytes() != c.to_rgb8().tobytes()


def test_random_triangles_counts(engine):
    tris = random_triangles(128, 96, 200, mean_area=50, seed=2)
    f = rasterise(tris)
    assert f.pixels_covered <= f.pixels_written <= f.fragments
    assert 0.5 * 200 * 50 < f.fragments < 1.5 * 200 * 50  # about mean_area px per triangle
    assert f.colour.shape == (96, 128, 3) and f.depth.shape == (96, 128)
    assert f.tri_id.dtype == np.int64 and f.poly_id.dtype == np.int64


def test_offscreen_and_empty(engine):
    f = rasterise(make_tris([[-30, -30], [-10, -30], [-30, -10]]))
    assert f.fragments == 0 and f.pixels_covered == 0
    e = rasterise(make_tris(np.zeros((0, 3, 2))))
    assert e.pixels_covered == 0 and np.all(e.depth == np.inf)


def test_to_rgb8_rounds_half_up_and_clamps(tmp_path):
    colour = np.array([[[0.5 / 255, 1.49 / 255, -0.2], [1.3, 254.5 / 255, 1.0]]])
    fr = Frame(colour=colour, depth=np.zeros((1, 2)), tri_id=np.zeros((1, 2), np.int64),
               poly_id=np.zeros((1, 2), np.int64), fragments=0, pixels_written=0, pixels_covered=0)
    np.testing.assert_array_equal(fr.to_rgb8(), [[[1, 1, 0], [255, 255, 255]]])
    from PIL import Image

    fr.save_png(tmp_path / "f.png")
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "f.png")), fr.to_rgb8())


@pytest.mark.parametrize("bad, match", [
    (dict(xy=np.full((1, 3, 2), np.nan)), "NaN"),
    (dict(xy=np.array([[[0, 0], [1e6, 0], [0, 1]]])), "more than"),
    (dict(xy=np.zeros((1, 4, 2))), "xy must be"),
    (dict(z=np.zeros((1, 2))), "z must be"),
    (dict(width=0), "width"),
])
def test_bad_input_raises(bad, match):
    tris = make_tris([[1, 1], [5, 1], [1, 5]])
    for k, v in bad.items():
        setattr(tris, k, v)
    with pytest.raises(RasterhwError, match=match):
        rasterise(tris)


def test_bad_background_raises():
    with pytest.raises(RasterhwError, match="background"):
        rasterise(make_tris([[1, 1], [5, 1], [1, 5]]), background=(1, 2))


def test_benchmark_reports():
    r = benchmark(random_triangles(64, 64, 50, seed=1), repeat=3)
    assert r["repeat"] == 3 and 0 < r["min_s"] <= r["median_s"]
    assert r["peak_bytes"] > 64 * 64 * 8  # at least the depth buffer
    assert r["fragments"] > 0


def test_compare_images(tmp_path):
    a = np.zeros((4, 5, 3), dtype=np.uint8)
    a[...] = 100
    b = a.copy()
    assert compare_images(a, b) == {"pixels": 20, "differing_pixels": 0, "any_difference_pixels": 0,
                                    "max_abs_diff": [0, 0, 0], "tolerance": 0}
    b[1, 2, 1] = 103
    b[3, 4] = [90, 100, 100]
    r = compare_images(a, b)
    assert r["differing_pixels"] == 2 and r["max_abs_diff"] == [10, 3, 0]
    r = compare_images(a, b, tolerance=3)
    assert r["differing_pixels"] == 1 and r["any_difference_pixels"] == 2
    d = diff_image(a, b)
    assert d.dtype == np.uint8 and d.shape == a.shape
    np.testing.assert_array_equal(d[1, 2], [255, 0, 255])
    np.testing.assert_array_equal(d[0, 0], [25, 25, 25])
    write_diff_png(a, b, tmp_path / "d.png")
    from PIL import Image

    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "d.png")), d)
    with pytest.raises(RasterhwError, match="size"):
        compare_images(a, b[:3])
    with pytest.raises(RasterhwError, match="tolerance"):
        compare_images(a, b, tolerance=-1)
