"""SNU Gouraud scan converter (golden_model/snu/gouraud.py): coverage, values, order, errors."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.snu import gouraud as g


def make(xy, colour=None, zq=None, w=16, h=16, **kw) -> ScreenTriangles:
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 3, 2)
    t = xy.shape[0]
    colour = np.full((t, 3, 3), 0.5) if colour is None else np.asarray(colour, float).reshape(t, 3, 3)
    zq = np.full((t, 3), 1000) if zq is None else np.asarray(zq).reshape(t, 3)
    kw.setdefault("z_far_is_zero", True)
    return ScreenTriangles(width=w, height=h, xy=xy, z=np.zeros((t, 3)), zq=zq.astype(np.int64),
                           colour=colour, poly_id=np.arange(t), **kw)


def random_scene(seed, t, w, h, spread):
    rng = np.random.default_rng(seed)
    c = rng.uniform(0, 1, (t, 1, 2)) * [w, h]
    xy = np.clip(c + rng.normal(0, spread, (t, 3, 2)), 0, [w, h])
    return make(xy, rng.uniform(0, 1, (t, 3, 3)), rng.integers(0, 1 << 24, (t, 3)), w, h)


def coverage(stream, w, h):
    img = np.zeros(w * h, dtype=np.int64)
    np.add.at(img, stream.addr, 1)
    return img.reshape(h, w)


# ------------------------------------------------------------------ coverage


def test_right_triangle_pixel_count():
    # Legs of 8 px on pixel edges: row r has centres x + 0.5 < 8 - (r + 0.5), i.e. 7 - r pixels;
    # the hypotenuse is a right edge, so centres on it (x + y = 8) are out: 7+6+...+1 = 28.
    s = g.scan_convert(make([[0, 0], [8, 0], [0, 8]]))
    img = coverage(s, 16, 16)
    expect = np.zeros((16, 16), dtype=np.int64)
    for r in range(7):
        expect[r, : 7 - r] = 1
    assert len(s) == 28
    assert np.array_equal(img, expect)


def _exact_cover(tri_xy, w, h):
    """Independent check: exact rational edge functions with the top-left rule."""
    p = [(Fraction(x), Fraction(y)) for x, y in tri_xy]
    area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
    if area == 0:
        return set()
    if area < 0:  # make it clockwise on screen (y down): interior to the right of each edge
        p = [p[0], p[2], p[1]]
    out = set()
    for row in range(h):
        for col in range(w):
            cx, cy = Fraction(2 * col + 1, 2), Fraction(2 * row + 1, 2)
            ok = True
            for a, b in ((p[0], p[1]), (p[1], p[2]), (p[2], p[0])):
                e = (b[0] - a[0]) * (cy - a[1]) - (b[1] - a[1]) * (cx - a[0])
                top = a[1] == b[1] and b[0] > a[0]  # horizontal, interior below
                left = b[1] < a[1]  # going up on screen: interior to its right
                if e < 0 or (e == 0 and not (top or left)):
                    ok = False
                    break
            if ok:
                out.add(row * w + col)
    return out


def test_coverage_equals_exact_top_left_rule():
    # Vertices on a 1/4-px grid, many centres exactly on edges and vertices.
    rng = np.random.default_rng(7)
    w, h = 12, 10
    xy = rng.integers(0, 4 * 12, (40, 3, 2)) / 4.0
    xy[:, :, 1] = np.minimum(xy[:, :, 1], h)
    xy[:5] = np.round(xy[:5]) + 0.5  # vertices exactly on pixel centres
    s = g.scan_convert(make(xy, w=w, h=h))
    tri = g.setup_spans(make(xy, w=w, h=h))["tri"]
    per_tri = np.repeat(tri, g.setup_spans(make(xy, w=w, h=h))["n"])
    for t in range(len(xy)):
        got = set(s.addr[per_tri == t].tolist())
        assert got == _exact_cover(xy[t], w, h), f"triangle {t}: {xy[t].tolist()}"


def test_shared_edges_cover_once():
    # A fan of 8 triangles around an off-grid centre plus a quad split on its diagonal: every
    # pixel of the union is written exactly once.
    cx, cy = 10.25, 9.75
    ring = [(2, 2), (10.5, 1.5), (19, 2), (19, 10.5), (19, 18), (10.5, 18.5), (2, 18), (1.5, 10.5)]
    fan = [[ring[i], ring[(i + 1) % 8], (cx, cy)] for i in range(8)]
    quad = [[(20, 1), (30, 1), (30, 12)], [(20, 1), (30, 12), (20, 12)]]
    s = g.scan_convert(make(fan + quad, w=32, h=20))
    img = coverage(s, 32, 20)
    assert img.max() == 1
    assert img[1:12, 20:30].sum() == 10 * 11  # the quad is exactly its 110 pixel centres
    inside = img[2:18, 2:19]
    assert inside.min() == 1  # no gaps in the fan's interior box


def test_winding_and_vertex_order_do_not_change_coverage():
    t = random_scene(3, 50, 40, 30, 6)
    a = g.scan_convert(t)
    xy = t.xy[:, [2, 1, 0]]
    b = g.scan_convert(make(xy, t.colour[:, [2, 1, 0]], t.zq[:, [2, 1, 0]], 40, 30))
    assert np.array_equal(a.addr, b.addr)


def test_zero_area_and_off_screen_triangles_write_nothing():
    s = g.scan_convert(make([[[1, 1], [5, 5], [9, 9]], [[-20, -20], [-10, -20], [-10, -5]],
                             [[3, 3], [3, 3], [3, 3]]]))
    assert len(s) == 0
    s.validate()


def test_clipped_to_the_frame():
    s = g.scan_convert(make([[-5, -5], [30, -5], [-5, 30]], w=16, h=16))
    img = coverage(s, 16, 16)
    assert img.max() == 1 and img.sum() == len(s)
    assert img[0, 0] == 1 and img[15, 15] == 0


# ------------------------------------------------------------------ values and order


@pytest.mark.parametrize("rot", [0, 1, 2])
def test_vertex_colour_and_z_exact(rot):
    # The vertex at pixel centre (2.5, 2.5) is on a top edge and a left edge: it is covered and
    # must get exactly its own colour and Z, whichever slot it is in.
    pts = np.array([[2.5, 2.5], [13.5, 2.5], [2.5, 11.5]])
    cols = np.array([[17, 200, 3], [250, 0, 128], [90, 91, 255]]) / 255.0
    zq = np.array([12_345_678, 16_000_000, 5])
    idx = np.roll(np.arange(3), rot)
    s = g.scan_convert(make(pts[idx], cols[idx], zq[idx]))
    hit = np.flatnonzero(s.addr == 2 * 16 + 2)
    assert hit.size == 1
    k = hit[0]
    assert s.rgb[k] == (17 << 16) | (200 << 8) | 3
    assert s.z[k] == 12_345_678


def test_stream_validates_order_and_pipes():
    t = random_scene(5, 300, 96, 64, 8)
    s = g.scan_convert(t)
    s.validate(n_pipes=2)
    spans = g.setup_spans(t)
    tri = np.repeat(spans["tri"], spans["n"])
    assert np.all(np.diff(tri) >= 0)  # triangles in submission order
    assert np.array_equal(s.pipe, tri % 2)  # dealt alternately
    for t_id in np.unique(tri)[:50]:
        a = s.addr[tri == t_id]
        assert np.all(np.diff(a) > 0)  # top to bottom, left to right
    s3 = g.scan_convert(t, n_pipes=3)
    assert np.array_equal(s3.pipe, tri % 3)


def test_deterministic():
    t = random_scene(11, 200, 64, 48, 10)
    a, b = g.scan_convert(t), g.scan_convert(t)
    for f in ("addr", "rgb", "z", "pipe"):
        assert getattr(a, f).tobytes() == getattr(b, f).tobytes()


def test_inner_loop_equals_literal_loop_and_closed_form():
    # One pixel at a time in plain Python from the set-up's span accumulators, and the closed
    # form start + k * increment: both must give the converter's stream bit for bit.
    t = random_scene(13, 25, 48, 40, 9)
    f = 16
    spans = g.setup_spans(t, frac_bits=f)
    out = []
    for i in range(spans["n"].size):
        regs = {"addr": int(spans["row"][i] * 48 + spans["col"][i]), "count": int(spans["n"][i])}
        inc = {"addr": 1, "count": -1}
        for c, name in enumerate(("r", "g", "b", "z")):
            regs[name], inc[name] = int(spans["acc"][i, c]), int(spans["inc"][i, c])
        while regs["count"] != 0:
            out.append((regs["addr"], ((regs["r"] >> f) << 16) | ((regs["g"] >> f) << 8) | (regs["b"] >> f),
                        regs["z"] >> f))
            for name in ("addr", "r", "g", "b", "z", "count"):
                regs[name] += inc[name]
    s = g.scan_convert(t, frac_bits=f)
    assert len(out) == len(s) > 500
    assert [o[0] for o in out] == s.addr.tolist()
    assert [o[1] for o in out] == s.rgb.tolist()
    assert [o[2] for o in out] == s.z.tolist()
    span, k = g._expand(spans)
    zc = (spans["acc"][span, 3] + k * spans["inc"][span, 3]) >> f
    assert np.array_equal(zc, s.z)


def test_inner_loop_is_counted_as_it_runs():
    t = random_scene(13, 25, 48, 40, 9)
    counts: dict = {}
    s = g.scan_convert(t, counts=counts)
    spans = g.setup_spans(t)
    assert counts["pixels"] == len(s) == int(spans["n"].sum())
    assert counts["spans"] == int(np.count_nonzero(spans["n"] > 0))
    for k in g.EXECUTED:  # every executed operation runs once per pixel written
        assert counts[k] == len(s), k
    ops = g.inner_loop_ops(counts)
    assert (ops["add"], ops["mem"], ops["branch"], ops["total"]) == (6, 1, 1, 8)
    empty: dict = {}
    g.scan_convert(random_scene(1, 0, 16, 16, 4), counts=empty)
    assert empty["pixels"] == 0 and empty["store"] == 0
    with pytest.raises(RasterhwError, match="at least one pixel"):
        g.inner_loop_ops(empty)


# ------------------------------------------------------------------ tolerance vs float


@pytest.mark.parametrize("spread,seed", [(8, 1), (200, 2)])
def test_within_one_lsb_of_float_twin(spread, seed):
    w, h = 320, 240
    t = random_scene(seed, 150 if spread < 50 else 12, w, h, spread)
    a, b = g.scan_convert(t), g.scan_convert_float(t)
    d = g.stream_difference(a, b)
    assert d["pixels"] > 5000
    assert max(d["max_abs"].values()) <= 1
    assert d["exact_fraction"] > 0.99
    assert g.error_bound_lsb(16, w, h) < 0.01


def test_too_few_fraction_bits_break_the_tolerance():
    # Large triangles over 1280x1024 with 8 fraction bits (Q8.8, the literal "16-bit integer")
    # drift by more than one step: the paper's reason for keeping enough precision.
    rng = np.random.default_rng(2)
    xy = rng.uniform(0, 1, (6, 3, 2)) * [1280, 1024]
    t = make(xy, rng.uniform(0, 1, (6, 3, 3)), rng.integers(0, 1 << 24, (6, 3)), 1280, 1024)
    d = g.stream_difference(g.scan_convert(t, frac_bits=8), g.scan_convert_float(t))
    assert max(d["max_abs"].values()) > 1
    d16 = g.stream_difference(g.scan_convert(t, frac_bits=16), g.scan_convert_float(t))
    assert max(d16["max_abs"].values()) <= 1


def test_matches_float_reference_when_available():
    ref = pytest.importorskip("rasterhw.golden_model.reference")
    assert ref.SUBPIXEL == 1 << g.SUBPIXEL_BITS
    # Non-overlapping triangles (a jittered grid mesh) so the reference's winners are the
    # coverage itself.
    rng = np.random.default_rng(4)
    w, h, n = 64, 48, 8
    gx, gy = np.meshgrid(np.linspace(0, w, n + 1), np.linspace(0, h, n + 1))
    jit = rng.uniform(-1.5, 1.5, gx.shape + (2,))
    jit[0, :, 1] = jit[-1, :, 1] = jit[:, 0, 0] = jit[:, -1, 0] = 0
    P = np.stack([gx, gy], axis=-1) + jit
    tris = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = P[i, j], P[i, j + 1], P[i + 1, j + 1], P[i + 1, j]
            tris += [[a, b, c], [a, c, d]]
    t = len(tris)
    sc = make(np.array(tris), rng.uniform(0, 1, (t, 3, 3)), rng.integers(0, 1 << 24, (t, 3)), w, h)
    frame = ref.rasterise(sc)
    s = g.scan_convert(sc)
    spans = g.setup_spans(sc)
    tri = np.repeat(spans["tri"], spans["n"])
    tri_map = np.full(w * h, -1)
    tri_map[s.addr] = tri
    assert np.array_equal(tri_map.reshape(h, w), frame.tri_id)
    rgb = frame.to_rgb8().reshape(-1, 3)[s.addr].astype(np.int64)
    ours = np.stack([s.rgb >> 16, (s.rgb >> 8) & 255, s.rgb & 255], axis=1)
    assert np.abs(ours - rgb).max() <= 1
    fl = g.scan_convert_float(sc)
    ours_f = np.stack([fl.rgb >> 16, (fl.rgb >> 8) & 255, fl.rgb & 255], axis=1)
    assert np.mean(np.all(ours_f == rgb, axis=1)) > 0.999


# ------------------------------------------------------------------ bad input


@pytest.mark.parametrize("kw,match", [
    ({"frac_bits": 7}, "frac_bits"),
    ({"frac_bits": 29}, "frac_bits"),
    ({"frac_bits": True}, "frac_bits"),
    ({"n_pipes": 0}, "n_pipes"),
    ({"n_pipes": 1.5}, "n_pipes"),
])
def test_bad_parameters(kw, match):
    with pytest.raises(RasterhwError, match=match):
        g.scan_convert(make([[0, 0], [8, 0], [0, 8]]), **kw)


def test_bad_input():
    good = [[0, 0], [8, 0], [0, 8]]
    with pytest.raises(RasterhwError, match="z_far_is_zero"):
        g.scan_convert(make(good, z_far_is_zero=False))
    with pytest.raises(RasterhwError, match="NaN"):
        g.scan_convert(make([[0, np.nan], [8, 0], [0, 8]]))
    with pytest.raises(RasterhwError, match="colour"):
        g.scan_convert(make(good, colour=np.full(9, 1.5)))
    with pytest.raises(RasterhwError, match="zq"):
        g.scan_convert(make(good, zq=[0, 1 << 24, 5]))
    with pytest.raises(RasterhwError, match="magnitude"):
        g.scan_convert(make([[0, 0], [1e9, 0], [0, 8]]))
    bad = make(good)
    bad.zq = np.zeros((2, 3), dtype=np.int64)
    with pytest.raises(RasterhwError, match="shape"):
        g.scan_convert(bad)
    with pytest.raises(RasterhwError, match="ScreenTriangles"):
        g.scan_convert("not triangles")
    with pytest.raises(RasterhwError, match="z_far_is_zero"):
        g.scan_convert_float(make(good, z_far_is_zero=False))
