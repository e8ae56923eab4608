"""Issue 33: OBJ relative indices (high 3), concave polygons, indented faces, inline comments,
CR-only line ends, 2-D vertices; and a differential test of the OBJ loader against a tiny
independent reader written here (hypothesis-generated files: absolute and relative indices,
triangles and convex n-gons, comments, line ends, indentation, encodings, garbage lines)."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.meshio import load_mesh, triangulate_polygon

PY = sys.executable
ISSUE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 2 0 0\nv 3 0 0\nv 2 1 0\nf -3 -2 -1\n"
PLAIN = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 2 0 0\nv 3 0 0\nv 2 1 0\nf 4 5 6\n"
#: an L-shaped hexagon starting at a corner that does not see the whole L (fanned from it, it
#: covers a triangle outside the L and misses one inside: the probe's "pentagon"), and the same
#: area cut into triangles by hand
L_HEX = "v 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nf 1 2 3 4 5 6\n"
L_TRIS = "v 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nf 5 6 2\nf 6 1 2\nf 5 2 4\nf 2 3 4\n"


def _load(tmp_path, text: str | bytes, name="m.obj"):
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return load_mesh(p)


def _render(tmp_path, text: str, name: str) -> bytes:
    from PIL import Image

    src, png = tmp_path / f"{name}.obj", tmp_path / f"{name}.png"
    src.write_text(text)
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "render", str(src), "--size", "48x48", "-o", str(png)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return np.asarray(Image.open(png))


def test_relative_indices_count_from_the_current_vertex(tmp_path):
    sc = _load(tmp_path, ISSUE)
    np.testing.assert_array_equal(sc.positions, _load(tmp_path, PLAIN, "p.obj").positions)
    assert sc.positions[0, :, 0].max() == 1.0   # the first triangle is the first one, not lost


def test_relative_index_before_the_first_vertex_is_one_line(tmp_path):
    with pytest.raises(RasterhwError, match="line 3: relative index -3 goes back past the first vertex"):
        _load(tmp_path, "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n")


@pytest.mark.parametrize("variant", [
    lambda t: t.replace("\nf", "\n   f").replace("\nv", "\n\tv"),          # indented lines
    lambda t: t.replace("\n", "  # a comment\n"),                          # inline comments
    lambda t: t.replace("\n", "\r"),                                      # CR-only line ends
    lambda t: t.replace("\n", "\r\n"),                                    # CRLF
    lambda t: t.replace("f 1 2 3", "f 1 \\\n 2 3"),                       # a continued line
], ids=["indented", "inline-comments", "cr-only", "crlf", "continued"])
def test_obj_variants_load_like_the_plain_file(tmp_path, variant):
    plain = _load(tmp_path, PLAIN, "p.obj").positions
    np.testing.assert_array_equal(_load(tmp_path, variant(PLAIN)).positions, plain)


def test_indented_face_with_index_zero_is_still_refused(tmp_path):
    with pytest.raises(RasterhwError, match="line 4: face vertex index 0"):
        _load(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n  f 1 2 0\n")


def test_two_d_vertex_is_one_line_naming_the_line(tmp_path):
    with pytest.raises(RasterhwError, match="line 2: vertex has 2 coordinates"):
        _load(tmp_path, "v 0 0 0\nv 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(RasterhwError, match="line 1: vertex coordinate 'x' is not a number"):
        _load(tmp_path, "v x 0 0 # c\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")


def test_concave_polygon_covers_its_own_area(tmp_path):
    sc = _load(tmp_path, L_HEX)
    assert sc.positions.shape == (4, 3, 3)
    p = sc.positions
    area = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]
    assert np.all(area > 0) and area.sum() == pytest.approx(3.0)   # same winding, the L's area
    cen = p.mean(axis=1)
    assert not np.any((cen[:, 0] > 1) & (cen[:, 1] > 1))   # nothing in the L's missing square


def test_render_of_relative_concave_obj_matches_the_plain_file(tmp_path):
    """The issue's "must show": same image as the equivalent plain OBJ."""
    np.testing.assert_array_equal(_render(tmp_path, ISSUE, "rel"), _render(tmp_path, PLAIN, "plain"))
    hexa = L_HEX.replace("f 1 2 3 4 5 6", "   f -6 -5 -4 -3 -2 -1   # the L\r").replace("\n", "\r")
    np.testing.assert_array_equal(_render(tmp_path, hexa, "hex"), _render(tmp_path, L_TRIS, "tris"))


# --------------------------------------------------------------- triangulate_polygon properties
@st.composite
def simple_polygons(draw):
    """Star-shaped polygons around the origin: corners at increasing angles and random radii
    (simple, mostly concave), in a random plane, either winding."""
    n = draw(st.integers(4, 12))
    # one corner per sector of 360/n degrees: every gap under 180, so the origin is inside
    angles = [360 * i / n + draw(st.integers(0, 99)) * 3.6 / n for i in range(n)]
    radii = draw(st.lists(st.integers(1, 10), min_size=n, max_size=n))
    pts = np.array([(r * np.cos(np.radians(a)), r * np.sin(np.radians(a)), 0.0) for a, r in zip(angles, radii, strict=True)])
    if draw(st.booleans()):
        pts = pts[::-1]
    axes = draw(st.permutations([0, 1, 2]))
    return pts[:, axes]


def _area2(p):   # twice the vector area
    return 0.5 * sum(np.cross(p[i], p[(i + 1) % len(p)]) for i in range(len(p)))


@settings(max_examples=150, deadline=None)
@given(simple_polygons())
def test_triangulation_covers_the_polygon_with_its_winding(pts):
    tris = triangulate_polygon(pts)
    assert len(tris) == len(pts) - 2
    poly = _area2(pts)
    parts = [0.5 * np.cross(pts[b] - pts[a], pts[c] - pts[a]) for a, b, c in tris]
    assert np.allclose(sum(parts), poly, atol=1e-6)                  # the polygon's area, no more
    big = np.argmax(np.abs(poly))
    assert all(t[big] * poly[big] >= -1e-9 for t in parts)           # every triangle wound like it


# --------------------------------------------------------------- differential: an independent reader
def reference_read(data: bytes) -> np.ndarray:
    """A tiny OBJ reader written from the format's description: UTF-8/UTF-16 by BOM, any line
    end, ``#`` comments, relative indices from the current count, convex polygons fanned."""
    for bom, enc in ((b"\xef\xbb\xbf", "utf-8"), (b"\xff\xfe", "utf-16-le"), (b"\xfe\xff", "utf-16-be")):
        if data.startswith(bom):
            text = data[len(bom):].decode(enc)
            break
    else:
        text = data.decode("utf-8")
    verts, tris = [], []
    for line in re.split(r"\r\n|\r|\n", text):
        w = line.split("#")[0].split()
        if not w:
            continue
        if w[0] == "v":
            if len(w) < 4:
                raise ValueError("short vertex")
            verts.append([float(x) for x in w[1:4]])
        elif w[0] == "f":
            idx = []
            for c in w[1:]:
                i = int(c.split("/")[0])
                if i == 0:
                    raise ValueError("index 0")
                idx.append(i - 1 if i > 0 else len(verts) + i)
            if len(idx) < 3 or min(idx) < 0:
                raise ValueError("bad face")
            tris += [(idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1)]
    if not tris or max(max(t) for t in tris) >= len(verts):
        raise ValueError("no faces or a missing vertex")
    return np.array(verts)[np.array(tris)]


@st.composite
def obj_files(draw):
    nv = draw(st.integers(3, 10))
    verts = draw(st.lists(st.tuples(*[st.integers(-50, 50)] * 3), min_size=nv, max_size=nv, unique=True))
    lines, count = [], 0

    def vline(v):
        return f"v {v[0]} {v[1]} {v[2]}"
    for v in verts[:3]:
        lines.append(vline(v))
        count += 1
    vi = 3
    for _ in range(draw(st.integers(1, 6))):
        if vi < nv and draw(st.booleans()):
            lines.append(vline(verts[vi]))
            vi, count = vi + 1, count + 1
        k = draw(st.sampled_from([3, 3, 4, 5]))
        if k > 3:   # a convex polygon: a regular one of its own in the plane z = its index
            base = count
            for j in range(k):
                a = 2 * np.pi * j / k
                lines.append(f"v {np.cos(a) * 7 + 60:.6f} {np.sin(a) * 7:.6f} {len(lines)}")
            count += k
            idx = list(range(base + 1, base + k + 1))
        else:
            idx = draw(st.lists(st.integers(1, count), min_size=3, max_size=3))
        rel = draw(st.booleans())
        corners = [str(i - count - 1) if rel else str(i) for i in idx]
        lines.append("f " + " ".join(corners))
    # sprinkle: comments, blank and garbage-but-ignorable lines, indentation
    extra = draw(st.lists(st.sampled_from(["# a comment", "", "o thing", "s off", "g grp"]), max_size=3))
    for e in extra:
        lines.insert(draw(st.integers(0, len(lines))), e)
    if draw(st.booleans()):
        lines = [("  " if draw(st.booleans()) else "") + ln for ln in lines]
    if draw(st.booleans()):
        lines = [ln + ("  # note é" if ln.strip() and draw(st.booleans()) else "") for ln in lines]
    if draw(st.booleans()):   # something both readers must refuse
        bad = draw(st.sampled_from(["v 1 2", "f 1 2 0", "f 1 2", "v a b c", f"f 1 2 {count + 40}"]))
        lines.insert(draw(st.integers(len(lines) // 2, len(lines))), bad)
    end = draw(st.sampled_from(["\n", "\r\n", "\r"]))
    text = end.join(lines) + end
    enc = draw(st.sampled_from(["utf-8", "utf-8-sig", "utf-16"]))
    return text.encode(enc)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(obj_files())
def test_loader_agrees_with_an_independent_reader(tmp_path, data):
    try:
        want = reference_read(data)
    except (ValueError, UnicodeDecodeError):
        want = None
    try:
        got = _load(tmp_path, data).positions
    except RasterhwError as e:
        assert want is None or np.ptp(want.reshape(-1, 3), axis=0).max() == 0, f"refused a good file: {e}"
        return
    assert want is not None, "accepted a file the reference refuses"
    np.testing.assert_array_equal(got, want)


# --------------------------------------------------------------- PLY
def _ply(verts, faces, *, counts=None, colours=None) -> str:
    vprops = "property float x\nproperty float y\nproperty float z\n"
    if colours is not None:
        vprops += "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(verts)}\n{vprops}element face {len(faces)}\n"
            "property list uchar int vertex_indices\nend_header\n")
    vl = [" ".join(map(str, v)) + ("" if colours is None else " " + " ".join(map(str, colours[i])))
          for i, v in enumerate(verts)]
    fl = [f"{(counts or {}).get(k, len(f))} " + " ".join(map(str, f)) for k, f in enumerate(faces)]
    return head + "\n".join(vl + fl) + "\n"


L_VERTS = [(2, 1, 0), (1, 1, 0), (1, 2, 0), (0, 2, 0), (0, 0, 0), (2, 0, 0)]


def test_concave_ply_polygon_is_cut_right_and_keeps_vertex_colours(tmp_path):
    cols = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 0), (0, 255, 255), (255, 0, 255)]
    sc = _load(tmp_path, _ply(L_VERTS, [list(range(6))], colours=cols), "l.ply")
    p = sc.positions
    area = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]
    assert np.all(area > 0) and area.sum() == pytest.approx(3.0)
    lookup = {tuple(map(float, v)): np.array(c) / 255 for v, c in zip(L_VERTS, cols, strict=True)}
    for t in range(len(p)):   # each corner keeps its own vertex's colour
        for k in range(3):
            np.testing.assert_allclose(sc.colours[t, k], lookup[tuple(p[t, k])])


def test_ply_face_whose_count_disagrees_with_its_indices_is_refused(tmp_path):
    with pytest.raises(RasterhwError, match="face 0 says 5 corners but lists 3"):
        _load(tmp_path, _ply([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [[0, 1, 2]], counts={0: 5}), "bad.ply")


def test_convex_ply_polygon_is_fanned_from_its_first_corner_like_obj(tmp_path):
    sq = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    sc = _load(tmp_path, _ply(sq, [[0, 1, 2, 3]]), "sq.ply")
    np.testing.assert_array_equal(sc.positions, np.array(sq, float)[[[0, 1, 2], [0, 2, 3]]])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(simple_polygons())
def test_ply_and_obj_of_one_polygon_load_the_same(tmp_path, pts):
    pts = np.round(pts * 100)   # integers: exact in the PLY's float32
    verts = [tuple(v) for v in pts]
    obj = "".join(f"v {x} {y} {z}\n" for x, y, z in verts) + "f " + " ".join(str(i + 1) for i in range(len(verts))) + "\n"
    np.testing.assert_array_equal(_load(tmp_path, _ply(verts, [list(range(len(verts)))]), "a.ply").positions,
                                  _load(tmp_path, obj, "a.obj").positions)


def test_mesh_too_big_for_memory_is_one_line_before_parsing(tmp_path, monkeypatch):
    monkeypatch.setenv("RASTERHW_MEMORY_LIMIT", "2M")
    faces = "".join(f"f {i % 3 + 1} {(i + 1) % 3 + 1} {(i + 2) % 3 + 1}\n" for i in range(5000))
    with pytest.raises(RasterhwError, match=r"loading its 5,000 faces needs about .* simplify the mesh"):
        _load(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + faces)
    ply = _ply([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [[0, 1, 2]] * 5000)
    with pytest.raises(RasterhwError, match="loading its 5,000 faces"):
        _load(tmp_path, ply, "m.ply")
    monkeypatch.setenv("RASTERHW_MEMORY_LIMIT", "1G")
    assert len(_load(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + faces).positions) == 5000
