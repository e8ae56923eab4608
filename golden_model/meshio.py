"""Load OBJ / PLY meshes into a :class:`Scene`, and resolve a scene spec (built-in or file).

Meshes are read with trimesh (``force="mesh"``, ``process=False``: vertices are neither merged
nor reordered). Polygons with more than 3 corners are triangulated by trimesh. The camera is
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


def _ascii_ply_header(raw: bytes) -> bytes:
    """A PLY header is ASCII keywords, but comments may hold any bytes (trimesh decodes the
    header as UTF-8 and fails on a Latin-1 comment): non-ASCII header text becomes ``?``;
    the body (binary or ASCII numbers) is left as it is."""
    end = raw.find(b"end_header")
    if end < 0:
        return raw
    head = raw[:end]
    if head.isascii():
        return raw
    text, _enc = decode_text(head)
    return text.encode("ascii", errors="replace") + raw[end:]


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


_SHORT_VERTEX = re.compile(r"^v(?:[ \t]+\S+){0,2}[ \t]*$", re.M)


def _obj_is_plain(text: str) -> bool:
    """True if ``text`` has none of what only :func:`_normalise_obj` reads right (CR line ends,
    indentation, continued lines, inline comments, vertices of fewer than 3 coordinates); faces
    are looked at by :func:`_check_obj_faces`. Substring tests and one regular expression: a
    million-face file is not walked line by line in Python twice."""
    if "\r" in text or "\\" in text or text[:1] in (" ", "\t") or "\n " in text or "\n\t" in text:
        return False
    at = text.find("#")
    while at >= 0:
        line_start = text.rfind("\n", 0, at) + 1
        if text[line_start:at].strip():
            return False   # something before the # on its line: an inline comment
        nl = text.find("\n", at)
        at = -1 if nl < 0 else text.find("#", nl)
    return _SHORT_VERTEX.search(text) is None


def _check_obj_faces(path: Path, text: str) -> bool:
    """What trimesh gets wrong silently in an OBJ's faces, found in the raw text: a face with
    fewer than 3 vertices (dropped) and vertex index 0 (OBJ counts from 1; NumPy would read
    0 - 1 as the last vertex). An index that is not an integer is an error too. Returns True if a
    face is a polygon of more than 3 corners or has a relative index (:func:`_normalise_obj`
    rewrites those), False if every face is a plain triangle."""
    rewrite = False
    for lineno, line in enumerate(text.splitlines(), 1):
        if not (line.startswith("f") and line[1:2].isspace()):
            continue
        corners = line.split("#", 1)[0].split()[1:]
        if len(corners) > 3 or "-" in line:
            rewrite = True
        if len(corners) < 3:
            raise RasterhwError(f"{path}: line {lineno}: face has {len(corners)} vertices (a face needs at least 3)")
        for c in corners:
            _face_index(c.split("/", 1)[0], c, path, lineno)
    return rewrite


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
    """The OBJ ``text`` rewritten so that trimesh reads exactly what the file says: line ends
    (``\\r\\n``, ``\\r`` alone, ``\\n``) and backslash-continued lines joined, comments
    (whole-line and inline ``#``) and indentation removed, relative (negative) indices turned into
    absolute ones counted from the vertices read *so far* (the OBJ rule; trimesh counted from the
    end of the file), and polygons of more than 3 corners cut into triangles by
    :func:`triangulate_polygon`. Errors name the line: a vertex with fewer than 3 coordinates or
    a coordinate that is not a number, a face of fewer than 3 corners, index 0, an index that is
    not an integer or refers to a vertex the file does not have."""
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


def _check_ply_faces(path: Path, mesh) -> None:
    """trimesh drops short PLY faces too; its raw element data (kept in metadata) still has them."""
    try:
        face = mesh.metadata.get("_ply_raw", {}).get("face")
        if face is None:
            return
        data = face["data"]
        name = next(iter(face["properties"]))
        col = data[name]
        if isinstance(col, np.ndarray) and col.dtype == object:  # ASCII: ragged lists
            counts = np.fromiter((len(f) for f in col), dtype=np.int64, count=len(col))
        elif isinstance(col, np.ndarray) and col.dtype.names:  # binary: (count, list) records
            counts = np.asarray(col[col.dtype.names[0]], dtype=np.int64)
        else:
            counts = np.full(len(col), np.asarray(col).shape[-1] if np.ndim(col) > 1 else 3)
    except Exception:  # private trimesh layout changed: fall back to trusting trimesh
        return
    bad = np.flatnonzero(counts < 3)
    if bad.size:
        raise RasterhwError(
            f"{path}: face {int(bad[0])} has {int(counts[bad[0]])} vertices (a face needs at least 3)"
        )


def _check_ascii_ply(path: Path, raw: bytes) -> None:
    """An ASCII PLY's face lines say how many corners follow; trimesh reads ``5 0 1 2`` as a
    triangle. With the face element's one property a list (the common layout), every face line
    must hold exactly that many indices."""
    end = raw.find(b"end_header")
    if end < 0 or b"format ascii" not in raw[:end]:
        return
    elements: list[list] = []   # [name, count, [property kinds]]
    for line in raw[:end].decode("ascii", errors="replace").splitlines():
        w = line.split()
        if len(w) >= 3 and w[0] == "element":
            try:
                elements.append([w[1], int(w[2]), []])
            except ValueError:
                return
        elif w[:1] == ["property"] and elements:
            elements[-1][2].append(w[1])
    body = raw[end:].split(b"\n", 1)[1] if b"\n" in raw[end:] else b""
    lines = [ln for ln in body.decode("ascii", errors="replace").splitlines() if ln.strip()]
    row = 0
    for name, count, props in elements:
        if name == "face" and props == ["list"]:
            for k, ln in enumerate(lines[row:row + count]):
                w = ln.split()
                try:
                    n = int(float(w[0]))
                except ValueError:
                    raise RasterhwError(f"{path}: face {k}: corner count {w[0][:20]!r} is not a number") from None
                if len(w) - 1 != n:
                    raise RasterhwError(f"{path}: face {k} says {n} corners but lists {len(w) - 1}")
            return
        row += count


def _retriangulate_ply(mesh, verts: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """PLY polygons of more than 3 corners cut by :func:`triangulate_polygon` (trimesh fans
    them from the first corner, wrong for a concave one); ``faces`` unchanged if there are none
    or the raw polygons are not where this trimesh keeps them."""
    try:
        face = mesh.metadata.get("_ply_raw", {}).get("face")
        col = face["data"][next(iter(face["properties"]))]
        if isinstance(col, np.ndarray) and col.dtype.names:   # binary: (count, list) records
            polys = [list(r[col.dtype.names[1]][: r[col.dtype.names[0]]]) for r in col]
        else:
            polys = [list(np.asarray(f).ravel()) for f in col]
    except Exception:  # noqa: BLE001 - private trimesh layout changed: keep its triangles
        return faces
    if all(len(q) <= 3 for q in polys) or sum(len(q) - 2 for q in polys) != len(faces):
        return faces
    out = []
    for q in polys:
        q = np.asarray(q, dtype=np.int64)
        if q.min() < 0 or q.max() >= len(verts):
            return faces
        out += [(q[a], q[b], q[c]) for a, b, c in triangulate_polygon(verts[q])]
    return np.asarray(out, dtype=np.int64)   # n - 2 per polygon, in order: face colours still line up


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
        if not _obj_is_plain(text) or _check_obj_faces(path, text):
            text = _normalise_obj(path, text)
        raw = text.encode("utf-8")
    elif ext == ".ply":
        _check_ascii_ply(path, raw)
        raw = _ascii_ply_header(raw)

    import io

    import trimesh

    # trimesh logs and warns about what it cannot parse; we report our own one-line error.
    log = logging.getLogger("trimesh")
    old_level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            resolver = trimesh.resolvers.FilePathResolver(str(path.resolve()))
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

    if ext == ".ply":
        _check_ply_faces(path, mesh)
        faces = _retriangulate_ply(mesh, verts, faces)
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
    col = _colours(mesh, faces)

    return Scene(
        name=name if name is not None else path.stem,
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
