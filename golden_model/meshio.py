"""Load OBJ / PLY meshes into a :class:`Scene`, and resolve a scene spec (built-in or file).

OBJ files pass the project's own normaliser (:func:`_normalise_obj`: any white space, line ends,
comments, relative indices, polygons cut by :func:`triangulate_polygon`, every malformed face
refused with its line number) and are then read by trimesh (``force="mesh"``, ``process=False``:
vertices are neither merged nor reordered). PLY files are read by the project's own reader
(:mod:`rasterhw.golden_model.plyread`: ASCII and binary of both byte orders, faces of any size
mixed, as exporters write them). The camera is
placed to frame the mesh's bounding box; one parallel light; colours are the file's vertex or
face colours when it has them, grey otherwise.

Every bad input gives a :class:`RasterhwError` with a one-line message naming the file —
never a trimesh traceback.
"""

from __future__ import annotations

import logging
import math
import re
import warnings
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.plyread import PlyMesh, read_ply
from rasterhw.golden_model.scene import Camera, Light, Material, Scene

__all__ = ["MESH_EXTENSIONS", "decode_text", "load_mesh", "load_scene", "triangulate_polygon"]

MESH_EXTENSIONS = (".obj", ".ply")
_COORD_LIMIT = 1e15  # the Scene validator's limit
_GREY = (0.7, 0.7, 0.7)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    msg = text[0] if text else ""
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


#: byte-order marks, longest first (a UTF-32 LE mark starts with the UTF-16 LE one)
_BOMS = ((b"\x00\x00\xfe\xff", "utf-32-be"), (b"\xff\xfe\x00\x00", "utf-32-le"),
         (b"\xef\xbb\xbf", "utf-8"), (b"\xfe\xff", "utf-16-be"), (b"\xff\xfe", "utf-16-le"))


def decode_text(raw: bytes) -> tuple[str, str]:
    """Text of a mesh file whose encoding is not declared -> ``(text, encoding)``.

    A byte-order mark decides (UTF-8, UTF-16, UTF-32; the mark is dropped). Without one: bytes
    with no NUL that decode as UTF-8 are UTF-8 (a shortcut: the common case, and what the
    detector says of them too); anything else is detected by the ``charset-normalizer`` library
    (UTF-16/32 without a mark, Cyrillic or Japanese code pages, ...), and where it finds nothing
    (a few bytes, or bytes no encoding explains) it is Latin-1, which decodes any byte string.
    An OBJ's numbers and keywords are ASCII, and no detected encoding uses a line end as part of
    a character, so only comments and names can be affected by a wrong guess (a short Western
    European comment may come back in a neighbouring code page: the detector needs more text).
    """
    for bom, enc in _BOMS:
        if raw.startswith(bom):
            try:
                return raw[len(bom):].decode(enc), enc
            except UnicodeDecodeError:
                break  # not really a mark: fall through to the detector below
    if b"\x00" not in raw:
        try:
            return raw.decode("utf-8"), "utf-8"
        except UnicodeDecodeError:
            pass
    from charset_normalizer import from_bytes

    best = from_bytes(raw).best()
    if best is not None:
        return str(best), best.encoding.replace("_", "-")
    return raw.decode("latin-1"), "latin-1"


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        raise RasterhwError(f"cannot read {path}: {_one_line(exc)}") from None


def triangulate_polygon(points: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles ``(i, j, k)`` (indices into ``points``, an (n, 3) array of one polygon's
    corners in order) covering the polygon, each wound like the polygon.

    A convex polygon is fanned from its first corner (what OBJ and PLY readers commonly do, so
    convex files triangulate as before); a concave (simple) one is ear-clipped: the polygon is
    projected on the plane across its largest Newell-normal component and, corner by corner from
    the first, a corner is cut off as a triangle when it is convex and no other corner lies in
    that triangle. Fanning a concave polygon from a corner covers area outside it and misses area
    inside (an L-shaped hexagon drew as a pentagon: issue 33). A polygon with no ear left
    (self-intersecting, or all corners on a line) has its rest fanned."""
    n = len(points)
    if n == 3:
        return [(0, 1, 2)]
    p = np.asarray(points, dtype=np.float64)
    nrm = np.zeros(3)
    for i in range(n):   # Newell's normal: robust for non-planar and concave polygons
        a, b = p[i], p[(i + 1) % n]
        nrm += ((a[1] - b[1]) * (a[2] + b[2]), (a[2] - b[2]) * (a[0] + b[0]), (a[0] - b[0]) * (a[1] + b[1]))
    drop = int(np.argmax(np.abs(nrm)))
    if nrm[drop] == 0:
        return [(0, i, i + 1) for i in range(1, n - 1)]
    u, v = [(1, 2), (2, 0), (0, 1)][drop]
    xy = p[:, [u, v]] * (1.0 if nrm[drop] > 0 else -1.0, 1.0)   # counter-clockwise in the projection
    scale = float(np.abs(xy).max()) or 1.0
    eps = 1e-12 * scale * scale

    def cross(o, a, b):
        return (xy[a, 0] - xy[o, 0]) * (xy[b, 1] - xy[o, 1]) - (xy[a, 1] - xy[o, 1]) * (xy[b, 0] - xy[o, 0])

    if all(cross(i, (i + 1) % n, (i + 2) % n) >= -eps for i in range(n)):
        return [(0, i, i + 1) for i in range(1, n - 1)]   # convex: the fan
    idx = list(range(n))
    out = []
    while len(idx) > 3:
        m = len(idx)
        for k in range(m):
            a, b, c = idx[k - 1], idx[k], idx[(k + 1) % m]
            if cross(a, b, c) <= eps:
                continue   # reflex or flat corner: not an ear
            inside = False
            for q in idx:
                if q in (a, b, c):
                    continue
                if cross(a, b, q) >= -eps and cross(b, c, q) >= -eps and cross(c, a, q) >= -eps:
                    inside = True
                    break
            if not inside:
                out.append((a, b, c))
                del idx[k]
                break
        else:   # no ear: not a simple polygon; fan what is left
            out += [(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)]
            return out
    out.append((idx[0], idx[1], idx[2]))
    return out


_SHORT_VERTEX = re.compile(r"^v(?: +\S+){0,2} *$", re.M)
#: every white-space character OBJ allows between words (and Python's ``str.split`` splits on)
#: but the line end, as a space: tabs, vertical tabs, form feeds
_OBJ_BLANKS = str.maketrans({"\t": " ", "\v": " ", "\f": " "})
#: a face of exactly three corners, each ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn`` with absolute
#: (positive) indices: what trimesh reads exactly as written
_CORNER = r"[1-9][0-9]*(?:/(?:[1-9][0-9]*)?(?:/[1-9][0-9]*)?)?"
_PLAIN_FACE = re.compile(rf"^f +({_CORNER}) +({_CORNER}) +({_CORNER}) *$", re.M)


def _obj_is_plain(text: str) -> bool:
    """True if ``text`` (white space already spaces) has none of what only the full pass of
    :func:`_normalise_obj` reads right (CR line ends, indentation, continued lines, inline
    comments, vertices of fewer than 3 coordinates) and every face is a plain triangle
    (:data:`_PLAIN_FACE`) whose indices the file's vertices cover. Substring tests and regular
    expressions: a million-face file is not walked line by line in Python."""
    if "\r" in text or "\\" in text or text[:1] == " " or "\n " in text:
        return False
    at = text.find("#")
    while at >= 0:
        line_start = text.rfind("\n", 0, at) + 1
        if text[line_start:at].strip():
            return False   # something before the # on its line: an inline comment
        nl = text.find("\n", at)
        at = -1 if nl < 0 else text.find("#", nl)
    if _SHORT_VERTEX.search(text) is not None:
        return False
    faces = text.count("\nf ") + text.startswith("f ")
    if re.search(r"^f(?: |$)", text, re.M) is None and not faces:
        return True
    if re.search(r"^f$", text, re.M) is not None:
        return False
    n, top = 0, 0
    for m in _PLAIN_FACE.finditer(text):
        n += 1
        top = max(top, *(int(m.group(k).split("/", 1)[0]) for k in (1, 2, 3)))
    return n == faces and top <= text.count("\nv ") + text.startswith("v ")


def _face_index(part: str, corner: str, path, lineno: int) -> int:
    """One index of an OBJ face corner (``v``, ``vt`` or ``vn``), as written: a non-zero integer."""
    try:
        i = int(part)
    except ValueError:
        raise RasterhwError(f"{path}: line {lineno}: face vertex {corner[:40]!r} is not an integer index") from None
    if i == 0:
        raise RasterhwError(f"{path}: line {lineno}: face vertex index 0 (OBJ indices start at 1, "
                            "or count back from -1)")
    return i


def _normalise_obj(path: Path, text: str) -> str:
    """The OBJ ``text`` rewritten so that trimesh reads exactly what the file says (every OBJ
    passes here). White space between words may be any (tabs, vertical tabs, form feeds: made
    spaces); a file that is then plain (:func:`_obj_is_plain`: every face a triangle of absolute
    indices the file has) is what the full pass would write, and is returned as it is. Else: line ends
    (``\\r\\n``, ``\\r`` alone, ``\\n``) and backslash-continued lines joined, comments
    (whole-line and inline ``#``) and indentation removed, relative (negative) indices turned into
    absolute ones counted from the vertices read *so far* (the OBJ rule; trimesh counted from the
    end of the file), and polygons of more than 3 corners cut into triangles by
    :func:`triangulate_polygon`. Errors name the line: a vertex with fewer than 3 coordinates or
    a coordinate that is not a number, a face of fewer than 3 corners, index 0, an index that is
    not an integer or refers to a vertex the file does not have, a corner of more than three
    indices (``f 1/1/1/1 2 3``)."""
    text = text.translate(_OBJ_BLANKS)
    if _obj_is_plain(text):
        return text
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    out: list[str] = []
    faces: list[tuple[int, int, list[list[int | None]]]] = []   # (line number, out slot, corners)
    verts: list[tuple[float, float, float]] = []
    counts = {"v": 0, "vt": 0, "vn": 0}
    pending, start = "", 0
    for lineno, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0]
        if line.rstrip().endswith("\\") and "#" not in raw:
            pending, start = pending + line.rstrip()[:-1] + " ", start or lineno
            continue
        line, at = (pending + line).strip(), start or lineno
        pending, start = "", 0
        if not line:
            continue
        words = line.split()
        key = words[0]
        if key == "v":
            if len(words) < 4:
                raise RasterhwError(f"{path}: line {at}: vertex has {len(words) - 1} coordinates "
                                    "(a vertex needs x y z)")
            try:
                verts.append((float(words[1]), float(words[2]), float(words[3])))
            except ValueError:
                bad = next(w for w in words[1:4] if not _is_float(w))
                raise RasterhwError(f"{path}: line {at}: vertex coordinate {bad[:40]!r} is not a number") from None
            counts["v"] += 1
        elif key in ("vt", "vn"):
            counts[key] += 1
        elif key == "f":
            corners = words[1:]
            if len(corners) < 3:
                raise RasterhwError(f"{path}: line {at}: face has {len(corners)} vertices (a face needs at least 3)")
            res = []
            for c in corners:
                parts = c.split("/")
                if len(parts) > 3:
                    raise RasterhwError(f"{path}: line {at}: face vertex {c[:40]!r} is not v, v/vt, v//vn or v/vt/vn")
                idx: list[int | None] = []
                for kind, part in zip(("v", "vt", "vn"), parts, strict=False):
                    if part == "" and kind != "v":
                        idx.append(None)
                        continue
                    i = _face_index(part, c, path, at)
                    if i < 0:
                        i = counts[kind] + i + 1   # relative: -1 is the last one read so far
                        if i < 1:
                            raise RasterhwError(f"{path}: line {at}: relative index {part} goes back past the first "
                                                f"{'vertex' if kind == 'v' else kind}")
                    idx.append(i)
                res.append(idx)
            faces.append((at, len(out), res))
            out.append("")
            continue
        out.append(" ".join(words))
    for at, slot, res in faces:
        vi = [c[0] for c in res]
        if max(vi) > len(verts):
            raise RasterhwError(f"{path}: line {at}: face refers to vertex {max(vi)}; the file has {len(verts)}")
        tris = triangulate_polygon(np.array([verts[i - 1] for i in vi])) if len(res) > 3 else [(0, 1, 2)]
        out[slot] = "\n".join("f " + " ".join(_corner(res[k]) for k in t) for t in tris)
    return "\n".join(out) + "\n"


def _corner(idx: list[int | None]) -> str:
    return "/".join("" if i is None else str(i) for i in idx)


def _is_float(w: str) -> bool:
    try:
        float(w)
    except ValueError:
        return False
    return True


#: peak bytes per face while a mesh loads (trimesh's parse, our scene's positions, normals and
#: colours), measured: 630 B/face loading a 977,202-face OBJ; and per byte of the file (its text,
#: decoded and re-encoded)
_LOAD_BYTES_PER_FACE = 700
_LOAD_BYTES_PER_FILE_BYTE = 3


def _check_mesh_memory(path: Path, raw: bytes, ext: str) -> None:
    """One line before a mesh too big for this machine is parsed (a 10^7-triangle file ended in
    a MemoryError traceback): faces counted from the text (OBJ ``f`` lines) or the PLY header."""
    from rasterhw.golden_model.memcheck import HEADROOM, available_bytes, format_bytes

    if ext == ".ply":
        m = re.search(rb"^element\s+face\s+(\d+)", raw[: max(raw.find(b"end_header"), 0)], re.M)
        faces = int(m.group(1)) if m else 0
    else:
        faces = raw.count(b"\nf ") + raw.count(b"\rf ") + raw.startswith(b"f ")
    need = _LOAD_BYTES_PER_FACE * faces + _LOAD_BYTES_PER_FILE_BYTE * len(raw)
    avail = available_bytes()
    if need > HEADROOM * avail:
        raise RasterhwError(f"{path}: loading its {faces:,} faces needs about {format_bytes(need)} of memory, "
                            f"{format_bytes(avail)} is available; simplify the mesh")


def _frame_camera(lo: np.ndarray, hi: np.ndarray, fovy_deg: float = 45.0) -> Camera:
    """Look at the box centre from the front-right-above so the bounding sphere fits the view."""
    centre = (lo + hi) / 2
    radius = float(np.linalg.norm(hi - lo)) / 2
    direction = np.array([0.5, 0.4, 1.0])
    direction /= np.linalg.norm(direction)
    dist = radius / math.sin(math.radians(fovy_deg) / 2) * 1.05
    eye = centre + dist * direction
    return Camera(eye=tuple(float(c) for c in eye), target=tuple(float(c) for c in centre),
                  up=(0.0, 1.0, 0.0), fovy_deg=fovy_deg,
                  near=max(dist - 1.1 * radius, 1e-3 * dist), far=dist + 1.1 * radius)


def _colours(mesh, faces: np.ndarray) -> np.ndarray:
    """(F, 3, 3) corner colours in [0, 1]: the file's vertex or face colours, else grey."""
    visual = getattr(mesh, "visual", None)
    kind = getattr(visual, "kind", None)
    try:
        if kind == "vertex":
            vc = np.asarray(visual.vertex_colors, dtype=np.float64)[:, :3] / 255.0
            return vc[faces]
        if kind == "face":
            fc = np.asarray(visual.face_colors, dtype=np.float64)[:, :3] / 255.0
            return np.repeat(fc[:, None, :], 3, axis=1)
    except Exception:
        pass
    return np.broadcast_to(np.array(_GREY), (len(faces), 3, 3)).copy()


def load_mesh(path: str | Path, *, name: str | None = None, smooth: bool = True) -> Scene:
    """Read an OBJ or PLY file into a :class:`Scene` of triangles.

    Parameters
    ----------
    path : the .obj or .ply file.
    name : scene name; the file's stem by default.
    smooth : per-vertex normals (area-weighted average of the adjacent face normals; normals
        stored in the file are not used) for Gouraud shading; ``False`` gives each triangle
        its flat face normal.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise RasterhwError(
            f"{path}: unsupported mesh format {path.suffix or '(no extension)'!r}; use .obj or .ply"
        )
    if not path.is_file():
        raise RasterhwError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    if path.stat().st_size == 0:
        raise RasterhwError(f"{path}: file is empty")
    raw = _read_bytes(path)
    _check_mesh_memory(path, raw, ext)
    if ext == ".obj":
        # OBJ is text in no declared encoding: decode it here (UTF-8 with or without a BOM,
        # UTF-16, Latin-1) and hand trimesh clean UTF-8, so it never guesses (its guesser
        # needs an optional package) and a BOM never hides the first line.
        text, _enc = decode_text(raw)
        raw = _normalise_obj(path, text).encode("utf-8")
    else:   # PLY: the project's own reader (binary of either byte order, faces of any size mixed)
        return _scene_of(path, *_ply_triangles(read_ply(path, raw)), name=name, smooth=smooth)

    import io

    import trimesh

    # trimesh logs and warns about what it cannot parse; we report our own one-line error.
    log = logging.getLogger("trimesh")
    old_level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            where = str(path.resolve())
            try:   # material files beside the mesh; a name that is not UTF-8 (bytes kept as surrogates) has none
                where.encode("utf-8")
                resolver = trimesh.resolvers.FilePathResolver(where)
            except UnicodeEncodeError:
                resolver = None
            mesh = trimesh.load(io.BytesIO(raw), file_type=ext[1:], force="mesh", process=False,
                                resolver=resolver)
            faces = np.asarray(mesh.faces, dtype=np.int64)
            verts = np.asarray(mesh.vertices, dtype=np.float64)
    except RasterhwError:
        raise
    except MemoryError:
        raise RasterhwError(f"{path}: the {ext[1:].upper()} file describes more data than fits in memory") from None
    except Exception as exc:
        raise RasterhwError(f"{path}: not a readable {ext[1:].upper()} mesh ({_one_line(exc)})") from None
    finally:
        log.setLevel(old_level)

    return _scene_of(path, verts, faces, _colours(mesh, faces), name=name, smooth=smooth)


def _ply_triangles(ply: PlyMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, triangles, corner colours) of a PLY mesh: each polygon of more than 3 corners
    cut by :func:`triangulate_polygon` (n - 2 triangles, in the file's order; a convex one fanned
    from its first corner, as OBJ's), a face's colour on each of its triangles."""
    verts, corners, starts = ply.vertices, ply.corners, ply.starts
    sizes = np.diff(starts)
    if sizes.size and np.all(sizes == 3):
        faces, owner = corners.reshape(-1, 3), np.arange(len(sizes))
    else:
        faces, owner = _cut_polygons(verts, corners, starts)
    if ply.vertex_colours is not None:
        col = ply.vertex_colours[faces]
    elif ply.face_colours is not None:
        col = np.repeat(ply.face_colours[owner][:, None, :], 3, axis=1)
    else:
        col = np.broadcast_to(np.array(_GREY), (len(faces), 3, 3)).copy()
    return verts, faces, col


def _convex_mask(p: np.ndarray) -> np.ndarray:
    """For polygons ``p`` (m, n, 3) of n corners each: which ones :func:`triangulate_polygon`
    fans (convex in its projection, or with no normal), by the same arithmetic in the same order,
    for all of them at once."""
    m, n, _ = p.shape
    nrm = np.zeros((m, 3))
    for i in range(n):
        a, b = p[:, i], p[:, (i + 1) % n]
        nrm += np.stack([(a[:, 1] - b[:, 1]) * (a[:, 2] + b[:, 2]), (a[:, 2] - b[:, 2]) * (a[:, 0] + b[:, 0]),
                         (a[:, 0] - b[:, 0]) * (a[:, 1] + b[:, 1])], axis=1)
    drop = np.argmax(np.abs(nrm), axis=1)
    lead = nrm[np.arange(m), drop]
    uv = np.array([(1, 2), (2, 0), (0, 1)])[drop]
    rows, cols = np.arange(m)[:, None], np.arange(n)[None, :]
    xy = np.stack([p[rows, cols, uv[:, 0][:, None]], p[rows, cols, uv[:, 1][:, None]]], axis=2)
    xy[:, :, 0] *= np.where(lead > 0, 1.0, -1.0)[:, None]
    scale = np.abs(xy).max(axis=(1, 2))
    scale = np.where(scale == 0, 1.0, scale)
    eps = 1e-12 * scale * scale
    ok = np.ones(m, dtype=bool)
    for i in range(n):
        o, a, b = xy[:, i], xy[:, (i + 1) % n], xy[:, (i + 2) % n]
        c = (a[:, 0] - o[:, 0]) * (b[:, 1] - o[:, 1]) - (a[:, 1] - o[:, 1]) * (b[:, 0] - o[:, 0])
        ok &= c >= -eps
    return ok | (lead == 0)


def _cut_polygons(verts: np.ndarray, corners: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(triangles, the polygon each comes from) of polygons ``corners[starts[k]:starts[k+1]]``:
    :func:`triangulate_polygon` of each, in order; the polygons it fans (most: every triangle and
    every convex quad) are cut for a whole size at once, the rest one by one."""
    sizes = np.diff(starts)
    tri_of = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes - 2, out=tri_of[1:])
    faces = np.empty((int(tri_of[-1]), 3), dtype=np.int64)
    owner = np.repeat(np.arange(len(sizes)), sizes - 2)
    for n in np.unique(sizes).tolist():
        ks = np.flatnonzero(sizes == n)
        q = corners[starts[ks][:, None] + np.arange(n)]          # (m, n) vertex indices
        fan = np.ones(len(ks), dtype=bool) if n == 3 else _convex_mask(verts[q])
        for j in range(1, n - 1):                                # the fan (0, j, j + 1)
            faces[tri_of[ks[fan]] + j - 1] = q[fan][:, [0, j, j + 1]]
        for k, qk in zip(ks[~fan].tolist(), q[~fan], strict=True):
            faces[tri_of[k]:tri_of[k + 1]] = [(qk[a], qk[b], qk[c]) for a, b, c in triangulate_polygon(verts[qk])]
    return faces, owner


def _scene_name(path: Path) -> str:
    """The file's stem as text (a byte that is not UTF-8 shown as U+FFFD, never a surrogate that
    cannot be written out)."""
    import os

    return os.fsencode(path.stem).decode("utf-8", errors="replace")


def _scene_of(path: Path, verts: np.ndarray, faces: np.ndarray, col: np.ndarray, *, name: str | None,
              smooth: bool) -> Scene:
    """The checked :class:`Scene` of triangles ``faces`` over ``verts`` with corner colours ``col``."""
    if faces.ndim != 2 or faces.shape[0] == 0:
        raise RasterhwError(f"{path}: no faces (not a polygon mesh, or nothing trimesh could parse)")
    if faces.shape[1] != 3:
        raise RasterhwError(f"{path}: faces have {faces.shape[1]} corners after loading, expected triangles")
    if faces.min() < 0 or faces.max() >= len(verts):
        raise RasterhwError(f"{path}: a face refers to a vertex that does not exist")
    used = verts[np.unique(faces)]
    if not np.all(np.isfinite(used)):
        raise RasterhwError(f"{path}: a vertex coordinate is NaN or infinite")
    big = float(np.abs(used).max())
    if big > _COORD_LIMIT:
        raise RasterhwError(
            f"{path}: a vertex coordinate has magnitude {big:.3g} (more than {_COORD_LIMIT:g}); "
            "rescale the model"
        )
    lo, hi = used.min(axis=0), used.max(axis=0)
    if not np.any(hi > lo):
        raise RasterhwError(f"{path}: all vertices are at one point (nothing to frame)")

    pos = verts[faces]
    fn = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])  # length = 2 x area
    if smooth:
        # Area-weighted average of the faces around each vertex (vertices as trimesh keeps them:
        # an OBJ corner with its own normal index stays a separate vertex, so creases survive).
        vn = np.zeros_like(verts)
        np.add.at(vn, faces.ravel(), np.repeat(fn, 3, axis=0))
        nrm = vn[faces]
    else:
        nrm = np.repeat(fn[:, None, :], 3, axis=1)
    length = np.linalg.norm(nrm, axis=-1, keepdims=True)
    # Degenerate triangles (and vertices only they touch) have no normal: use +z, stay finite.
    nrm = np.where(length > 0, nrm / np.where(length > 0, length, 1.0), np.array([0.0, 0.0, 1.0]))
    return Scene(
        name=name if name is not None else _scene_name(path),
        positions=pos, normals=nrm, colours=col, nverts=np.full(len(faces), 3, dtype=np.int64),
        camera=_frame_camera(lo, hi), lights=(Light(direction=(-0.4, -1.0, -0.6)),),
        ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0),
    )


def load_scene(spec: str) -> Scene:
    """A built-in scene name (see :data:`rasterhw.golden_model.scenes.SCENES`) or an .obj/.ply path."""
    from rasterhw.golden_model.scenes import SCENES, build_scene

    if spec in SCENES:
        return build_scene(spec)
    p = Path(spec)
    if p.suffix.lower() in MESH_EXTENSIONS or p.exists():
        return load_mesh(p)
    raise RasterhwError(
        f"unknown scene {spec!r}: not a built-in scene ({', '.join(SCENES)}) "
        "and not an .obj or .ply file"
    )
