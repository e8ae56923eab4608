"""Golden geometry pipeline (golden_model/pipeline.py) and its operation counts."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.opcount import OpCounter
from rasterhw.golden_model.pipeline import (
    SPEC_LUT_SIZE,
    STAGES,
    backface_cull,
    clip,
    fan_triangulate,
    frame_setup,
    light,
    normal_transform,
    normalise,
    perspective_divide,
    run_geometry,
    screen_map,
    vertex_transform,
)
from rasterhw.golden_model.scene import Camera, Light, Material, Scene
from rasterhw.golden_model.snu.table1 import paper_comparison
from rasterhw.golden_model.triangle_ops import ops_per_triangle

# Eye at the origin looking down -z: view space = world space.
EYE0 = Camera(
    eye=(0.0, 0.0, 0.0),
    target=(0.0, 0.0, -1.0),
    up=(0.0, 1.0, 0.0),
    fovy_deg=90.0,
    near=2.0,
    far=100.0,
)


def make_scene(pos, *, normals=None, colours=None, camera=EYE0, **kw) -> Scene:
    pos = np.asarray(pos, dtype=float)
    if pos.ndim == 2:
        pos = pos[None]
    p, k = pos.shape[:2]
    nrm = (
        np.tile([0.0, 0.0, 1.0], (p, k, 1))
        if normals is None
        else np.asarray(normals, float).reshape(p, k, 3)
    )
    col = (
        np.full((p, k, 3), 0.5) if colours is None else np.asarray(colours, float).reshape(p, k, 3)
    )
    return Scene(
        name="t", positions=pos, normals=nrm, colours=col, nverts=np.full(p, k), camera=camera, **kw
    )


# ----------------------------------------------------------------------------- transforms
def test_vertex_transform_matches_hand_computation():
    m = np.arange(16, dtype=float).reshape(4, 4) - 5.0
    p = np.array([[1.0, 2.0, 3.0], [-0.5, 0.25, 4.0]])
    got = vertex_transform(p, m)
    # row r: m[r,0] x + m[r,1] y + m[r,2] z + m[r,3] (w fixed at 1)
    x, y, z = 1.0, 2.0, 3.0
    assert got[0].tolist() == [
        -5 * x - 4 * y - 3 * z - 2,
        -1 * x + 0 * y + 1 * z + 2,
        3 * x + 4 * y + 5 * z + 6,
        7 * x + 8 * y + 9 * z + 10,
    ]
    np.testing.assert_allclose(got[1], m @ np.array([-0.5, 0.25, 4.0, 1.0]))


def test_view_projection_by_hand():
    # 90 degree fov, aspect 2: f = 1, x scaled by 1/2; w = -z_eye; z = 0 at near, w at far.
    cam = Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fovy_deg=90.0, near=1.0, far=9.0)
    sc = make_scene([[0, 0, 0], [1, 0, 0], [0, 1, 0]], camera=cam)
    mvp = frame_setup(sc, 200, 100).mvp
    c = vertex_transform(np.array([[1.0, 2.0, 0.0], [0.0, 0.0, 4.0], [0.0, 0.0, -4.0]]), mvp)
    a, b = 9.0 / (1.0 - 9.0), 9.0 * 1.0 / (1.0 - 9.0)
    np.testing.assert_allclose(c[0], [0.5, 2.0, a * -5 + b, 5.0])
    np.testing.assert_allclose(c[1], [0.0, 0.0, 0.0, 1.0], atol=1e-12)  # on the near plane
    np.testing.assert_allclose(c[2], [0.0, 0.0, 9.0, 9.0])  # on the far plane


def test_normal_transform_and_normalise():
    m = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    n = np.array([[1.0, 0.0, 0.0], [0.0, 3.0, 4.0]])
    t = normal_transform(n, m)
    np.testing.assert_array_equal(t, [[0.0, 1.0, 0.0], [-3.0, 0.0, 8.0]])
    u = normalise(np.array([[3.0, 0.0, 4.0], [1e-3, -2e-3, 2e-3], [7.0, 7.0, 7.0]]))
    np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(u[0], [0.6, 0.0, 0.8])
    np.testing.assert_allclose(u[1], [1 / 3, -2 / 3, 2 / 3])


# ----------------------------------------------------------------------------- lighting
def test_light_reduces_to_vector_zbuffer_formula_with_ks_zero():
    rng = np.random.default_rng(7)
    L = np.array([0.3, -1.0, -0.5])  # travel direction, not unit length
    ia, k = 0.15, 0.7
    sc = make_scene(
        [[0, 0, -5], [1, 0, -5], [0, 1, -5]],
        lights=(Light(direction=tuple(L)),),
        ambient=(ia, ia, ia),
        material=Material(ka=1.0, kd=k, ks=0.0),
    )
    lighting = frame_setup(sc, 64, 64).lighting  # the eye looks down -z: eye space = world
    N = rng.normal(size=(200, 3)) * rng.uniform(0.1, 5.0, (200, 1))
    base = rng.uniform(0.0, 1.0, (200, 3))
    got = light(normalise(N), base, lighting)
    ndl = -(N @ L) / (np.linalg.norm(N, axis=1) * np.linalg.norm(L))
    want = np.where(ndl[:, None] > 0, ia + k * ndl[:, None], ia) * base
    assert np.any(ndl > 0) and np.any(ndl <= 0)
    np.testing.assert_allclose(got, np.minimum(want, 1.0), rtol=1e-13, atol=1e-15)


def test_light_specular_uses_lookup_table():
    sc = make_scene(
        [[0, 0, -5], [1, 0, -5], [0, 1, -5]],
        lights=(Light(direction=(0.0, 0.0, -1.0)),),  # from behind the eye: H = (0, 0, 1)
        ambient=(0.0, 0.0, 0.0),
        material=Material(ka=0.0, kd=0.0, ks=0.5, shininess=8),
    )
    lighting = frame_setup(sc, 64, 64).lighting
    ang = np.linspace(0.0, 1.5, 50)
    n = np.stack([np.sin(ang), np.zeros_like(ang), np.cos(ang)], axis=1)
    got = light(n, np.ones((50, 3)), lighting)[:, 0]
    assert got[0] == 0.5  # N = H: the table's last entry is exactly 1
    want = 0.5 * np.cos(ang) ** 8
    # nearest of SPEC_LUT_SIZE entries: error <= half a step times the slope 8 cos^7
    assert np.max(np.abs(got - want)) <= 0.5 * 8 * 0.5 / (SPEC_LUT_SIZE - 1) + 1e-12
    assert np.all(np.diff(got) <= 0)


# ----------------------------------------------------------------------------- culling
def test_backface_cull_known_pair():
    tri = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]]  # CCW seen from the eye
    # A big triangle with a corner behind the eye (w < 0) is still judged correctly.
    behind = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 3.0, 10.0]]
    sc = make_scene([tri, tri[::-1], behind, behind[::-1]])
    mvp = frame_setup(sc, 64, 64).mvp
    c = vertex_transform(sc.positions.reshape(-1, 3), mvp).reshape(4, 3, 4)
    assert c[2, 2, 3] < 0 and c[3, 0, 3] < 0
    assert backface_cull(c).tolist() == [True, False, True, False]
    t = run_geometry(sc, 64, 64)
    assert t.stats["polygons_culled"] == 2
    assert set(t.poly_id.tolist()) == {0, 2}


# ----------------------------------------------------------------------------- clipping
# Triangle in the plane y = -1 below the eye, pointing back past the eye. With near = 2
# and a 90-degree square view volume its visible part is {-5 <= z <= -2, |x| <= -z}: a
# trapezoid with half-widths 2 and 5 and height 3, area (4 + 10) / 2 * 3 = 21 in (x, z).
CUT_TRI = [[0.0, -1.0, 1.0], [10.0, -1.0, -5.0], [-10.0, -1.0, -5.0]]


def _clip_tri(pos):
    sc = make_scene(pos)
    setup = frame_setup(sc, 100, 100)
    c = vertex_transform(sc.positions[0], setup.mvp)
    # attribute: a linear function of the eye-space position (must stay exact)
    attr = (sc.positions[0] @ np.array([0.05, 0.0, -0.1]) + 0.3)[:, None]
    corners = np.concatenate([c, attr], axis=1)[None]
    ops = OpCounter()
    out, n, cut = clip(corners, np.array([3]), setup.near, ops=ops)
    return out[0, : n[0]], cut[0], ops


def test_clip_near_and_sides_area_and_inside():
    v, cut, _ = _clip_tri(CUT_TRI)
    assert cut and len(v) == 4
    x, y, z, w = v[:, 0], v[:, 1], v[:, 2], v[:, 3]
    eps = 1e-12 * np.abs(w).max()
    assert np.all(np.abs(x) <= w + eps) and np.all(np.abs(y) <= w + eps)
    assert np.all(z >= -eps) and np.all(z <= w + eps)
    # back to eye space: x_eye = x_clip (f = 1, aspect 1), z_eye = -w
    xe, ze = x, -w
    area = 0.5 * abs(np.dot(xe, np.roll(ze, -1)) - np.dot(ze, np.roll(xe, -1)))
    assert area == pytest.approx(21.0, rel=1e-12)
    # the linear attribute is still the same linear function at the new corners
    np.testing.assert_allclose(v[:, 4], 0.05 * xe - 0.1 * ze + 0.3, rtol=1e-12)


def test_clip_leaves_inside_polygon_alone_and_drops_outside_one():
    inside = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]]
    v, cut, ops = _clip_tri(inside)
    assert not cut and len(v) == 3
    assert ops.as_dict()["unstaged"]["cmp"] == 18 and ops.as_dict()["unstaged"]["total"] == 18
    v, cut, _ = _clip_tri([[p[0] + 50.0, p[1], p[2]] for p in inside])
    assert len(v) == 0


def test_huge_coordinates_are_clipped_without_warnings():
    rng = np.random.default_rng(3)
    pos = rng.uniform(-1e12, 1e12, (500, 3, 3))
    pos[:, 0] = rng.uniform(-1.0, 1.0, (500, 3)) + [0.0, 0.0, -10.0]  # one corner in view
    sc = make_scene(
        pos, camera=Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), near=0.1, far=1e14)
    )
    with warnings.catch_warnings(), np.errstate(all="raise"):
        warnings.simplefilter("error")
        t = run_geometry(sc, 320, 200)
    assert t.stats["polygons_drawn"] > 100 and t.stats["polygons_cut"] == t.stats["polygons_drawn"]
    assert np.all(np.isfinite(t.xy)) and np.all(np.isfinite(t.z))
    assert t.xy[..., 0].min() >= 0 and t.xy[..., 0].max() <= 320
    assert t.xy[..., 1].min() >= 0 and t.xy[..., 1].max() <= 200
    assert t.z.min() >= 0 and t.z.max() <= 1
    assert t.zq.min() >= 0 and t.zq.max() < 2**24


# ----------------------------------------------------------------------------- screen mapping
def test_screen_map_corners_and_y_down():
    ndc = np.array([[-1.0, 1.0, 0.0], [1.0, -1.0, 1.0], [0.0, 0.0, 0.5]])
    xy, z, zq = screen_map(ndc, 640, 480, z_bits=24)
    np.testing.assert_array_equal(xy, [[0, 0], [640, 480], [320, 240]])
    np.testing.assert_array_equal(z, [0.0, 1.0, 0.5])
    assert zq.tolist() == [0, 2**24 - 1, 2**23]


@pytest.mark.parametrize("bits", [1, 8, 24, 32])
def test_zq_quantise_and_flip(bits):
    ndc = np.array([[0, 0, 0.0], [0, 0, 1.0], [0, 0, 0.25], [0, 0, 0.75]])
    top = 2**bits - 1
    q = [0, top, min(round(0.25 * 2**bits), top), min(round(0.75 * 2**bits), top)]
    assert screen_map(ndc, 8, 8, z_bits=bits)[2].tolist() == q
    assert screen_map(ndc, 8, 8, z_bits=bits, z_far_is_zero=True)[2].tolist() == [
        top - v for v in q
    ]


def test_perspective_divide():
    c = np.array([[2.0, -4.0, 1.0, 4.0], [0.5, 0.5, 0.5, 0.5]])
    np.testing.assert_array_equal(perspective_divide(c), [[0.5, -1.0, 0.25], [1.0, 1.0, 1.0]])


def test_run_geometry_end_to_end_depth_and_fan_order():
    # A quad facing the eye at distance d, and a back-facing triangle in between.
    d, near, far = 10.0, 2.0, 100.0
    quad = [[-1.0, -1.0, -d], [1.0, -1.0, -d], [1.0, 1.0, -d], [-1.0, 1.0, -d]]
    back = [[0.0, 0.0, -5.0], [0.0, 0.5, -5.0], [0.5, 0.0, -5.0], [0.5, 0.0, -5.0]]
    sc = Scene(
        name="t",
        positions=np.array([back, quad, quad]),
        normals=np.tile([0.0, 0.0, 1.0], (3, 4, 1)),
        colours=np.full((3, 4, 3), 0.5),
        nverts=np.array([3, 4, 4]),
        camera=EYE0,
    )
    t = run_geometry(sc, 100, 100, z_bits=16, z_far_is_zero=True)
    assert t.stats == {
        "polygons_in": 3,
        "polygons_culled": 1,
        "polygons_clipped_away": 0,
        "polygons_drawn": 2,
        "polygons_cut": 0,
        "triangles": 4,
    }
    assert t.poly_id.tolist() == [1, 1, 2, 2]
    # fan (0,1,2), (0,2,3) in screen space (y down): quad corner -1,-1 -> pixel (45, 55)
    np.testing.assert_allclose(t.xy[0], [[45, 55], [55, 55], [55, 45]])
    np.testing.assert_allclose(t.xy[1], [[45, 55], [55, 45], [45, 45]])
    z_want = far * (d - near) / (d * (far - near))
    np.testing.assert_allclose(t.z, z_want, rtol=1e-14)
    assert np.all(t.zq == 2**16 - 1 - min(round(z_want * 2**16), 2**16 - 1))
    np.testing.assert_allclose(
        t.colour, 0.5 * (0.2 + 0.8 * frame_setup(sc, 100, 100).lighting.to_light[0, 2])
    )


def test_fan_triangulate():
    idx, poly = fan_triangulate(np.array([3, 0, 5]))
    assert poly.tolist() == [0, 2, 2, 2]
    assert idx.tolist() == [[0, 1, 2], [3, 4, 5], [3, 5, 6], [3, 6, 7]]


# ----------------------------------------------------------------------------- op counts
def expected_per_triangle(*, lights=1, specular=True, flip=True) -> dict[str, dict[str, int]]:
    """Independent count from the formulas the stages implement (3 vertices, 1 polygon)."""
    v = 3
    z = dict.fromkeys(("mul", "add", "cmp", "div", "sqrt", "lookup", "cvt"), 0)
    e = {s: dict(z) for s in STAGES}
    e["vertex_transform"].update(mul=12 * v, add=12 * v)  # 4 rows x (3 mul + 2 add + 1 add)
    e["backface_cull"].update(mul=9, add=5, cmp=1)  # 3x3 determinant of (x, y, w), sign
    e["normal_transform"].update(mul=9 * v, add=6 * v)
    e["normalise"].update(mul=6 * v, add=2 * v, sqrt=v, div=v)
    mul = lights * (3 + 3) + 3  # N.L, kd C d per light; base * (...)
    add = lights * (2 + 3)  # N.L, ambient + diffuse per light
    cmp = lights * 1 + 3  # N.L > 0 per light; clamp to 1
    if specular:
        mul += lights * (3 + 1 + 3)  # N.H, table index, ks C s
        add += lights * 2 + (lights - 1) * 3 + 3  # N.H, sum over lights, + spec
        cmp += lights
        e["light"].update(lookup=lights * v, cvt=lights * v)
    e["light"].update(mul=mul * v, add=add * v, cmp=cmp * v)
    e["clip"].update(cmp=6 * v)  # one compare per plane per corner
    e["perspective_divide"].update(div=v, mul=3 * v)
    e["screen_map"].update(mul=3 * v, add=(2 + flip) * v, cmp=(4 + 1 + 1) * v, cvt=v)
    for d in e.values():
        d["total"] = sum(d.values())
    return e


def test_ops_per_triangle_equal_independent_count_and_are_stable():
    a = ops_per_triangle()
    b = ops_per_triangle()
    assert a == b
    want = expected_per_triangle()
    for s in STAGES:
        assert a[s] == want[s], s
        assert all(isinstance(x, int) for x in a[s].values())
    assert a["total"]["total"] == sum(want[s]["total"] for s in STAGES)
    # Where the code matches the paper's text exactly (table 1): 72, 45, 30, 12.
    assert [
        a[s]["total"]
        for s in ("vertex_transform", "normal_transform", "normalise", "perspective_divide")
    ] == [72, 45, 30, 12]
    rows = paper_comparison(a)
    assert rows[-1][:2] == ("total", 270)


@pytest.mark.parametrize("lights,ks", [(2, 0.3), (1, 0.0), (3, 0.0)])
def test_light_counts_follow_the_code(lights, ks):
    base = ops_per_triangle.__globals__["default_triangle_scene"]()
    ls = tuple(Light(direction=(-0.3 + 0.1 * i, -0.4, -1.0)) for i in range(lights))
    sc = Scene(
        name="t",
        positions=base.positions,
        normals=base.normals,
        colours=base.colours,
        nverts=base.nverts,
        camera=base.camera,
        lights=ls,
        material=Material(kd=0.5, ks=ks),
    )
    got = ops_per_triangle(sc)
    assert got["light"] == expected_per_triangle(lights=lights, specular=ks > 0)["light"]


def test_scene_ops_scale_with_work():
    quad = [[-1.0, -1.0, -10.0], [1.0, -1.0, -10.0], [1.0, 1.0, -10.0], [-1.0, 1.0, -10.0]]
    t = run_geometry(make_scene([quad, quad[::-1], CUT_TRI + [CUT_TRI[-1]]]), 64, 64)
    # every corner is transformed; only front polygons' corners are lit
    assert t.ops["vertex_transform"]["mul"] == 12 * 12
    assert t.ops["normal_transform"]["mul"] == 9 * (4 + 4)
    assert t.ops["backface_cull"]["cmp"] == 3
    # the cut triangle paid for divisions in clip: 3 planes x 2 new corners
    assert t.ops["clip"]["div"] == 6
    assert t.ops["triangles"] == t.n_triangles == 2 + 2


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "kw",
    [
        dict(width=0),
        dict(width=16385),
        dict(height=-3),
        dict(height=2.5),
        dict(width=True),
        dict(z_bits=0),
        dict(z_bits=33),
        dict(z_bits="24"),
    ],
)
def test_bad_parameters_raise(kw):
    sc = make_scene([[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]])
    args = dict(width=64, height=64) | kw
    w, h = args.pop("width"), args.pop("height")
    with pytest.raises(RasterhwError):
        run_geometry(sc, w, h, **args)


def test_bad_scene_content_raises():
    tri = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]]
    with pytest.raises(RasterhwError, match="normal"):
        run_geometry(make_scene(tri, normals=np.zeros((3, 3))), 8, 8)
    with pytest.raises(RasterhwError, match="colours"):
        run_geometry(make_scene(tri, colours=np.full((3, 3), 1.5)), 8, 8)
    with pytest.raises(RasterhwError, match="light 0 direction"):
        run_geometry(make_scene(tri, lights=(Light(direction=(0.0, 0.0, 0.0)),)), 8, 8)
    with pytest.raises(RasterhwError, match="kd"):
        run_geometry(make_scene(tri, material=Material(kd=-1.0)), 8, 8)
    with pytest.raises(RasterhwError, match="one triangle"):
        ops_per_triangle(make_scene([tri, tri]))
    with pytest.raises(RasterhwError, match="front-facing"):
        ops_per_triangle(make_scene(tri[::-1]))
    assert math.isfinite(run_geometry(make_scene(tri), 8, 8).z.sum())


@pytest.mark.parametrize(("seed", "near"), [(5, 0.5), (6, 1.0), (7, 0.1)])
def test_clip_fast_path_equals_every_polygon_through_every_plane(seed, near):
    """clip() sends only polygons with a corner outside a plane through Sutherland-Hodgman; the
    corners, counts and compares equal the plane loop run on every polygon."""
    from rasterhw.golden_model import pipeline as pl
    from rasterhw.golden_model.opcount import OpCounter

    rng = np.random.default_rng(seed)
    # corners in clip space around the view volume: many inside, many crossing, some outside
    n = 3000
    k = 3   # triangles: convex whatever the corners
    corners = np.zeros((n, k, 7))
    corners[:, :, 3] = rng.uniform(0.5, 2.0, (n, 1))
    corners[:, :, :3] = rng.normal(0.0, 0.7, (n, k, 3)) * corners[:, :, 3:4]
    corners[:, :, 4:] = rng.random((n, k, 3))
    nverts = np.full(n, 3)
    fast, slow = OpCounter(), OpCounter()
    with fast.stage("clip"):
        a = pl.clip(corners, nverts, near, ops=fast)
    with slow.stage("clip"):
        b = pl._clip_planes(corners, nverts, near, slow)
    b[1][b[1] < 3] = 0
    assert np.array_equal(a[1], b[1]) and np.array_equal(a[2], b[2])
    assert np.array_equal(a[0], b[0])
    assert fast.as_dict() == slow.as_dict()
    assert 0 < int(np.count_nonzero(a[2])) < n   # both paths were exercised
