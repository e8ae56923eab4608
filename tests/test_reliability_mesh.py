"""Issue 33: OBJ relative indices (high 3), concave polygons, indented faces, inline comments,
CR-only line ends, 2-D vertices; and a differential test of the OBJ loader against a tiny
independent reader written here (hypothesis-generated files: absolute and relative indices,
triangles and convex n-gons, comments, line ends, indentation, encodings, garbage lines; issue 47:
tabs and other white space, malformed corners, and binary PLY of mixed face sizes in both byte
orders against an independent PLY reader)."""

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
                if c.count("/") > 2:
                    raise ValueError("a corner of more than v/vt/vn")
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
    if draw(st.booleans()):   # tabs (and other white space OBJ allows) between the words (issue 47)
        sep = draw(st.sampled_from(["\t", " \t", "\t\t", "\x0b", "\x0c"]))
        lines = [ln.replace(" ", sep) if draw(st.booleans()) else ln for ln in lines]
    if draw(st.booleans()):
        lines = [ln + ("  # note é" if ln.strip() and draw(st.booleans()) else "") for ln in lines]
    if draw(st.booleans()):   # something both readers must refuse
        bad = draw(st.sampled_from(["v 1 2", "f 1 2 0", "f 1 2", "v a b c", f"f 1 2 {count + 40}",
                                    "f 1/1/1/1 2 3", "f 1 2//1/1 3"]))   # corners of 4 indices
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


# --------------------------------------------------------------- issue 47: meshes as exporters write them
def _binary_ply(verts, faces, order: str, *, before=False, colours=None) -> bytes:
    """A binary PLY (``order``: ``<`` or ``>``) of float32 vertices and faces of any sizes;
    ``before``: a uchar property before the face's index list (as some exporters write)."""
    import struct

    name = {"<": "binary_little_endian", ">": "binary_big_endian"}[order]
    vprops = "property float x\nproperty float y\nproperty float z\n"
    if colours is not None:
        vprops += "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    head = (f"ply\nformat {name} 1.0\ncomment made by a test\nelement vertex {len(verts)}\n{vprops}"
            f"element face {len(faces)}\n" + ("property uchar flags\n" if before else "")
            + "property list uchar int vertex_indices\nend_header\n")
    body = b"".join(struct.pack(f"{order}3f", *v) + (b"" if colours is None else bytes(colours[i]))
                    for i, v in enumerate(verts))
    body += b"".join((b"\x07" if before else b"") + struct.pack(f"{order}B{len(f)}i", len(f), *f) for f in faces)
    return head.encode() + body


def _obj_twin(verts, faces) -> str:
    """The plain-triangle OBJ of the same polygons (each convex one fanned from its first corner)."""
    tris = [(f[0], f[j], f[j + 1]) for f in faces for j in range(1, len(f) - 1)]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in verts) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris)


#: a little box of quads and triangles mixed (as Blender exports): convex faces, outward
BOX_V = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2), (1, 3, 1)]
BOX_F = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6], [1, 6, 5], [3, 0, 4, 7], [2, 3, 8], [3, 7, 8],
         [7, 6, 8], [6, 2, 8]]


def _render_file(tmp_path, name: str, data: bytes, arch: str) -> np.ndarray:
    from PIL import Image

    src, png = tmp_path / name, tmp_path / f"{name}-{arch}.png"
    src.write_bytes(data)
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "render", str(src), "--arch", arch, "--size", "48x48",
                        "-o", str(png)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return np.asarray(Image.open(png))


@pytest.mark.parametrize("arch", ["reference", "zbm"])
def test_tabbed_obj_and_mixed_binary_ply_render_like_their_plain_twins(tmp_path, arch):
    """The issue's must-show: an OBJ separated by tabs (refused before: "no faces") and binary PLY
    of quads and triangles mixed in both byte orders (before: "PLY is unexpected length!") give
    the pixels of their plain-triangle twin, on the reference and on ZB/M."""
    twin = _render_file(tmp_path, "twin.obj", _obj_twin(BOX_V, BOX_F).encode(), arch)
    assert (twin != twin[0, 0]).any()   # something was drawn
    tabbed = _obj_twin(BOX_V, BOX_F).replace(" ", "\t")
    np.testing.assert_array_equal(_render_file(tmp_path, "tabs.obj", tabbed.encode(), arch), twin)
    for order in "<>":
        got = _render_file(tmp_path, f"mixed{order == '>'}.ply", _binary_ply(BOX_V, BOX_F, order), arch)
        np.testing.assert_array_equal(got, twin)


def test_malformed_corner_is_refused_naming_its_line(tmp_path):
    """``f 1/1/1/1 2 3`` was read as a degenerate triangle (exit 0, nothing drawn)."""
    from test_reliability import one_line_error

    src = tmp_path / "bad.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n")
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "render", str(src), "--size", "16x16", "-o",
                        str(tmp_path / "b.png")], capture_output=True, text=True, timeout=300)
    one_line_error(r, contains="line 4: face vertex '1/1/1/1' is not v, v/vt, v//vn or v/vt/vn")
    assert not (tmp_path / "b.png").exists()


@pytest.mark.parametrize("fmt", ["ascii", "<", ">"])
def test_two_corner_ply_face_after_another_property_is_refused_not_dropped(tmp_path, fmt):
    faces = [[0, 1, 2], [0, 1]]
    if fmt == "ascii":
        data = (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                b"element face 2\nproperty uchar flags\nproperty list uchar int vertex_indices\nend_header\n"
                b"0 0 0\n1 0 0\n0 1 0\n7 3 0 1 2\n7 2 0 1\n")
    else:
        data = _binary_ply([(0, 0, 0), (1, 0, 0), (0, 1, 0)], faces, fmt, before=True)
    with pytest.raises(RasterhwError, match="face 1 has 2 vertices"):
        _load(tmp_path, data, "two.ply")


def test_a_file_name_that_is_not_utf8_loads(tmp_path):
    import os

    name = os.fsdecode(b"m\xff\xfe.obj")
    sc = _load(tmp_path, PLAIN, name)
    assert len(sc.positions) == 2 and sc.name == "m\ufffd\ufffd"
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "render", os.fsencode(str(tmp_path / name)), "--size",
                        "16x16", "-o", str(tmp_path / "u.png"), "--json"], capture_output=True, timeout=300)
    assert r.returncode == 0 and b"Traceback" not in r.stderr, r.stderr


def reference_ply(data: bytes) -> np.ndarray:
    """An independent binary-PLY reader for the files :func:`ply_files` writes (float32 x y z, one
    uchar-counted int list, optionally a uchar before it), polygons fanned from the first corner."""
    import struct

    head, body = data.split(b"end_header\n", 1)
    order = "<" if b"binary_little_endian" in head else ">"
    nv = int(re.search(rb"element vertex (\d+)", head).group(1))
    nf = int(re.search(rb"element face (\d+)", head).group(1))
    before = b"property uchar flags" in head
    verts = [struct.unpack_from(f"{order}3f", body, 12 * i) for i in range(nv)]
    at, tris = 12 * nv, []
    for _ in range(nf):
        at += before
        (n,) = struct.unpack_from("B", body, at)
        idx = struct.unpack_from(f"{order}{n}i", body, at + 1)
        at += 1 + 4 * n
        if n < 3:
            raise ValueError("short face")
        tris += [(idx[0], idx[k], idx[k + 1]) for k in range(1, n - 1)]
    return np.array(verts, dtype=np.float64)[np.array(tris)]


@st.composite
def ply_files(draw):
    """Binary PLY, either byte order, triangles and convex n-gons (regular, in planes of their own)
    mixed in any order, sometimes a property before the index list."""
    verts, faces = [], []
    for _ in range(draw(st.integers(1, 8))):
        k = draw(st.sampled_from([3, 3, 4, 4, 5, 6]))
        z, r = draw(st.integers(-20, 20)), draw(st.integers(1, 9))
        base = len(verts)
        verts += [(round(np.cos(2 * np.pi * j / k) * r, 3), round(np.sin(2 * np.pi * j / k) * r, 3), z)
                  for j in range(k)]
        faces.append(list(range(base, base + k)))
    order = draw(st.sampled_from("<>"))
    return _binary_ply(verts, faces, order, before=draw(st.booleans()))


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(ply_files())
def test_ply_loader_agrees_with_an_independent_reader(tmp_path, data):
    np.testing.assert_array_equal(_load(tmp_path, data, "h.ply").positions, reference_ply(data))
