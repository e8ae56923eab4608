"""Built-in scenes and mesh loading: counts, determinism, geometry, screen regime, bad input."""

from __future__ import annotations

import struct
import time

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.meshio import load_mesh, load_scene
from rasterhw.golden_model.scenekit import project as _project
from rasterhw.golden_model.scenes import SCENES, build_scene, list_scenes, screen_stats

EXPECTED = {
    "c50": 301, "c100": 601, "c150": 901, "c200": 1201, "c250": 1501, "c300": 1801,
    "sp27": 2701, "sp5": 2001, "sp8": 1354,
    "zbm-5x5": 1000, "snu-100px": 2000, "snu-100k": 100_000, "experts-1000": 1000, "experts-2000": 2000,
    "experts-tilt-1000": 1000, "experts-tilt-2000": 2000, "experts-solid-5": 4, "experts-solid-9": 6,
    "experts-solid-15": 9, "experts-solid-20": 12, "experts-solids": 31, "experts-uneven": 1000,
}


def _arrays(sc):
    return [sc.positions, sc.normals, sc.colours, sc.nverts]


def _newell(sc) -> np.ndarray:
    """Polygon normal from the corner order (counter-clockwise -> along the normal)."""
    k = sc.max_corners
    idx = np.arange(k)[None, :]
    nxt = (idx + 1) % sc.nverts[:, None]
    q = np.take_along_axis(sc.positions, nxt[..., None], axis=1)
    used = (idx < sc.nverts[:, None])[..., None]
    return np.where(used, np.cross(sc.positions, q), 0.0).sum(axis=1)


# ----------------------------------------------------------------------------- registry


def test_registry_matches_expected_counts():
    assert set(SCENES) == set(EXPECTED)
    rows = {r["name"]: r for r in list_scenes()}
    for name, n in EXPECTED.items():
        assert rows[name]["polygons"] == n
        assert set(rows[name]) == {"name", "description", "polygons", "default_width", "default_height"}
        assert rows[name]["description"] and "\n" not in rows[name]["description"]
    assert (rows["snu-100px"]["default_width"], rows["snu-100px"]["default_height"]) == (1280, 1024)
    assert (rows["c300"]["default_width"], rows["c300"]["default_height"]) == (512, 512)
    assert SCENES["c300"].size == (512, 512)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_builds_validates_and_counts(name):
    sc = build_scene(name)
    assert sc.n_polygons == EXPECTED[name]
    assert sc.name == name and sc.seed == SCENES[name].default_seed
    sc.validate()
    assert np.all(sc.colours >= 0) and np.all(sc.colours <= 1)
    # Winding and normals agree: counter-clockwise seen from where the normal points.
    assert np.all(np.einsum("pi,pi->p", _newell(sc), sc.normals.mean(axis=1)) > 0)
    # Every corner in front of the near plane and inside the far plane.
    _, zc = _project(sc, *SCENES[name].size)
    used = np.arange(sc.max_corners)[None, :] < sc.nverts[:, None]
    assert np.all(zc[used] > sc.camera.near) and np.all(zc[used] < sc.camera.far)


def test_unknown_scene_lists_valid_names():
    with pytest.raises(RasterhwError) as e:
        build_scene("c301")
    msg = str(e.value)
    assert "'c301'" in msg and "c300" in msg and "experts-2000" in msg and "\n" not in msg


@pytest.mark.parametrize("seed", [-1, 1.5, "3", True])
def test_bad_seed(seed):
    with pytest.raises(RasterhwError):
        build_scene("c50", seed=seed)


# ----------------------------------------------------------------------------- determinism


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_same_seed_same_bytes_other_seed_differs(name):
    a, b = build_scene(name), build_scene(name)
    for x, y in zip(_arrays(a), _arrays(b), strict=True):
        assert x.tobytes() == y.tobytes()
    assert a.camera == b.camera
    c = build_scene(name, seed=12345)
    assert c.seed == 12345
    assert any(x.tobytes() != y.tobytes() for x, y in zip(_arrays(a), _arrays(c), strict=True))
    d = build_scene(name, seed=12345)
    assert all(x.tobytes() == y.tobytes() for x, y in zip(_arrays(c), _arrays(d), strict=True))


def test_cube_series_are_prefixes():
    c300, c50 = build_scene("c300"), build_scene("c50")
    assert np.array_equal(c50.positions, c300.positions[:301])
    assert np.array_equal(c50.colours, c300.colours[:301])


def test_c300_builds_fast():
    build_scene("c300")
    t = time.perf_counter()
    for _ in range(5):
        build_scene("c300")
    assert (time.perf_counter() - t) / 5 < 0.05


# ----------------------------------------------------------------------------- structure


def test_cubes_are_flat_quads_one_colour_each():
    sc = build_scene("c100")
    assert np.all(sc.nverts == 4)
    n = sc.normals[1:].reshape(100, 6, 4, 3)
    assert np.allclose(n, n[:, :, :1])  # one normal per face
    assert np.allclose(np.linalg.norm(n[:, :, 0], axis=-1), 1)
    col = sc.colours[1:].reshape(100, 24, 3)
    assert np.allclose(col, col[:, :1])  # one colour per cube
    p = sc.positions[1:].reshape(100, 24, 3)
    # Every face is planar: corners lie in the plane of the face normal.
    pf = sc.positions[1:].reshape(100, 6, 4, 3)
    off = np.einsum("cfki,cfi->cfk", pf - pf[:, :, :1], n[:, :, 0])
    assert np.abs(off).max() < 1e-9
    # Cubes rest at or above the ground plane y = 0.
    assert p[..., 1].min() >= -1e-9
    # Opposite faces parallel, edges equal: a cube's 8 distinct corners are its bounding set.
    edge = np.linalg.norm(pf[:, :, 1] - pf[:, :, 0], axis=-1)
    assert np.allclose(edge, edge[:, :1])


def test_spheres_poles_and_smooth_normals():
    for name, slices, stacks, count, ground in (("sp27", 10, 10, 27, 1), ("sp5", 20, 20, 5, 1), ("sp8", 13, 13, 8, 2)):
        sc = build_scene(name)
        nv = sc.nverts[ground:].reshape(count, stacks, slices)
        assert np.all(nv[:, 0] == 3) and np.all(nv[:, -1] == 3) and np.all(nv[:, 1:-1] == 4)
        assert np.allclose(np.linalg.norm(sc.normals[ground:], axis=-1), 1)
        # Smooth: a normal is the radial direction of its corner (radius 1 spheres).
        c = sc.positions[ground:].reshape(count, -1, 3)
        n = sc.normals[ground:].reshape(count, -1, 3)
        centre = c.mean(axis=1, keepdims=True)
        assert np.allclose(c - centre, n, atol=1e-9)


def test_zbm_diamonds_are_two_5x5_edge_pairs():
    sc = build_scene("zbm-5x5")
    sxy, _ = _project(sc, 512, 512)
    top = sxy[:, 0]
    rel = sxy - top[:, None, :]
    assert np.allclose(rel, [[0, 0], [-5, 5], [0, 10], [5, 5]], atol=1e-6)
    assert np.allclose(top[:, 0] - np.floor(top[:, 0]), 0.25, atol=1e-6)
    assert np.allclose(top[:, 1], np.round(top[:, 1]), atol=1e-6)
    assert np.all(sxy >= 0) and np.all(sxy[..., 0] <= 512) and np.all(sxy[..., 1] <= 512)
    # Pixel centres per scan line: 1, 3, 5, 7, 9 then 9, 7, 5, 3, 1 (25 + 25 pixels), and no centre
    # closer than 0.2 px to an edge, so rounding cannot change the count.
    r = np.arange(10)
    half = np.where(r < 5, r + 0.5, 9.5 - r)
    xl = top[:, :1] - half[None, :]
    xr = top[:, :1] + half[None, :]
    count = np.floor(xr - 0.5) - np.ceil(xl - 0.5) + 1
    assert np.all(count == np.where(r < 5, 2 * r + 1, 19 - 2 * r))
    frac = (xl - 0.5) % 1.0
    assert np.all(np.minimum(frac, 1 - frac) > 0.2)
    # Scattered in depth: no two diamonds share a depth.
    assert len(np.unique(sc.positions[:, 0, 2])) == 1000


def test_snu_triangles_100px_on_screen():
    sc = build_scene("snu-100px")
    s = screen_stats(sc, 1280, 1024)
    assert s["drawn"] == 2000 and s["back_facing"] == 0
    assert s["area_per_drawn_px"] == pytest.approx(100.0, abs=1e-6)
    sxy, _ = _project(sc, 1280, 1024)
    u, v = sxy[:, 1] - sxy[:, 0], sxy[:, 2] - sxy[:, 0]
    a = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    assert np.allclose(a, 100.0, atol=1e-6)
    # Random colours per vertex, not per triangle.
    assert np.mean(np.abs(sc.colours[:, 0] - sc.colours[:, 1])) > 0.1


@pytest.mark.parametrize("name", ["experts-1000", "experts-2000", "experts-tilt-1000", "experts-tilt-2000"])
def test_experts_relevant_faces_and_depth_complexity(name):
    fr = int(name.rsplit("-", 1)[1])
    s = screen_stats(build_scene(name), 512, 512)
    assert s["drawn"] == fr and s["back_facing"] == 0 and s["off_screen"] == 0
    assert s["depth_complexity"] == pytest.approx(3.0, rel=1e-6)


@pytest.mark.parametrize("fr", [1000, 2000])
def test_experts_tilt_faces_are_tilted_and_interpenetrate(fr):
    from rasterhw.golden_model.experts import slp
    from rasterhw.golden_model.pipeline import run_geometry
    flat = slp.set_up(run_geometry(build_scene(f"experts-{fr}"), 512, 512), bit=False)
    tilt = slp.set_up(run_geometry(build_scene(f"experts-tilt-{fr}"), 512, 512), bit=False)
    assert np.abs(flat.dzdx).max() < 1e-9          # one depth per face: dz/dx = 0
    assert np.median(np.abs(tilt.dzdx)) > 1e-5      # tilted
    from rasterhw.golden_model.experts.model import render_frame
    # interpenetration: the visible face changes where neither segment starts or ends
    assert render_frame(run_geometry(build_scene(f"experts-{fr}"), 512, 512)).stats["crossings"] == 0
    assert render_frame(run_geometry(build_scene(f"experts-tilt-{fr}"), 512, 512)).stats["crossings"] > 500


@pytest.mark.parametrize("key,edges", [("5", 5), ("9", 9), ("15", 15), ("20", 20)])
def test_experts_solids_show_table_2_1_edge_counts(key, edges):
    from rasterhw.golden_model.experts.scenes import visible_edges
    sc = build_scene(f"experts-solid-{key}")
    assert visible_edges(sc) == edges
    s = screen_stats(sc, 512, 512)
    assert s["off_screen"] == 0 and s["drawn"] >= 2


def test_experts_uneven_is_uneven_in_x_and_y():
    sxy, _ = _project(build_scene("experts-uneven"), 512, 512)
    c = sxy.mean(axis=1)
    crowd = (c[:, 0] < 176) & (c[:, 1] < 200)
    assert crowd.sum() >= 850  # 850 crowded in 13 % of the frame


# ----------------------------------------------------------------------------- screen regime


def test_c300_regime():
    s = screen_stats(build_scene("c300"), 512, 512)
    assert s["behind_near"] == 0
    assert 0.4 < s["back_facing"] / s["polygons"] < 0.6  # about half back-facing
    assert 600 < s["drawn"] < 1100
    assert 60 < s["area_per_drawn_px"] < 300  # paper: ~128.5 px per drawn polygon
    assert s["empty_rows"] == 0  # cubes cover the whole frame


def test_sp8_small_on_screen():
    s = screen_stats(build_scene("sp8"), 512, 512)
    assert 0.2 < s["empty_row_fraction"] < 0.4  # paper: about 30 % of the scan lines empty
    assert s["depth_complexity"] < 0.2


# ----------------------------------------------------------------------------- meshes

OBJ = """# a unit square (quad) and a triangle
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 0.5 1
f 1 2 3 4
f 1 2 5
"""


def _ply_ascii(faces: list[list[int]]) -> str:
    head = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n"
            f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    verts = "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n1 1 0.5 255 255 255\n"
    return head + verts + "".join(f"{len(f)} {' '.join(map(str, f))}\n" for f in faces)


def _check_framed(sc):
    sc.validate()
    s = screen_stats(sc, 512, 512)
    assert s["behind_near"] == 0 and s["off_screen"] == 0
    sxy, zc = _project(sc, 512, 512)
    assert np.all(sxy >= 0) and np.all(sxy <= 512)
    assert np.all(zc > sc.camera.near) and np.all(zc < sc.camera.far)
    assert np.allclose(np.linalg.norm(sc.normals, axis=-1), 1)


def test_load_obj(tmp_path):
    p = tmp_path / "shape.obj"
    p.write_text(OBJ)
    sc = load_mesh(p)
    assert sc.name == "shape" and sc.n_polygons == 3 and np.all(sc.nverts == 3)  # quad -> 2 triangles
    assert np.allclose(sc.colours, 0.7)
    _check_framed(sc)
    # Smooth: corner 1 (shared by the quad and the triangle) has the same normal everywhere.
    flat = load_mesh(p, smooth=False, name="flat")
    assert flat.name == "flat"
    assert np.allclose(flat.normals, flat.normals[:, :1])
    assert not np.allclose(sc.normals, flat.normals)
    assert load_scene(str(p)).n_polygons == 3


def test_load_ply_with_vertex_colours(tmp_path):
    p = tmp_path / "tri.ply"
    p.write_text(_ply_ascii([[0, 1, 2], [1, 3, 2]]))
    sc = load_mesh(p)
    assert sc.n_polygons == 2
    assert np.allclose(sc.colours[0], [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    _check_framed(sc)


def test_load_binary_ply(tmp_path):
    p = tmp_path / "bin.ply"
    head = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
    body = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], "<f4").tobytes() + struct.pack("<B3i", 3, 0, 1, 2)
    p.write_bytes(head + body)
    sc = load_mesh(p)
    assert sc.n_polygons == 1
    _check_framed(sc)


def test_load_scene_builtin_equals_build():
    a, b = load_scene("sp8"), build_scene("sp8")
    assert a.positions.tobytes() == b.positions.tobytes()


BAD = {
    "missing": (None, "no such file"),
    "empty.obj": ("", "empty"),
    "junk.obj": ("hello\nthis is not a mesh\n", "no faces"),
    "lines.obj": ("v 0 0 0\nv 1 0 0\nl 1 2\n", "no faces"),
    "twovert.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "2 vertices"),
    "badindex.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "line 4: face refers to vertex 9; the file has 3"),
    "nan.obj": ("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "NaN or infinite"),
    "inf.obj": ("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
    "huge.obj": ("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n", "1e+30"),
    "point.obj": ("v 1 1 1\nf 1 1 1\n", "one point"),
    "junk.ply": (b"\x00\x01garbage\xff", "not a readable PLY"),
    "twovert.ply": (_ply_ascii([[0, 1, 2], [0, 1]]), "2 vertices"),
    "model.stl": ("solid x\nendsolid x\n", "unsupported"),
    "noext": ("v 0 0 0\n", "unsupported"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_mesh_input(tmp_path, capfd, name):
    content, expect = BAD[name]
    p = tmp_path / (name if name != "missing" else "missing.obj")
    if isinstance(content, bytes):
        p.write_bytes(content)
    elif content is not None:
        p.write_text(content)
    with pytest.raises(RasterhwError) as e:
        load_mesh(p)
    msg = str(e.value)
    assert expect in msg and "\n" not in msg and str(p) in msg
    assert "Traceback" not in capfd.readouterr().err


def test_load_scene_unknown():
    with pytest.raises(RasterhwError) as e:
        load_scene("no-such-scene")
    assert "c300" in str(e.value) and ".obj" in str(e.value)
    with pytest.raises(RasterhwError, match="no such file"):
        load_scene("/no/such/file.ply")


def test_sp5_spreads_over_more_lines_than_sp8():
    """The paper's narrow scene is sp8 (results note 1): sp5 must leave fewer empty lines."""
    sp5 = screen_stats(build_scene("sp5"), 512, 512)
    sp8 = screen_stats(build_scene("sp8"), 512, 512)
    assert sp5["empty_row_fraction"] < sp8["empty_row_fraction"]
    assert 0.2 <= sp8["empty_row_fraction"] <= 0.35
