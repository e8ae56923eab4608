"""The project's own PLY reader: ASCII and binary (both byte orders), faces of any size mixed.

Exporters write what the format allows: Blender's binary PLY mixes quads and triangles in one
``face`` element, some tools put a property before the face's index list, some write big-endian.
trimesh read a binary PLY with faces of mixed sizes as "PLY is unexpected length!" and picked the
first face property as the index list; this reader follows the header: every element in order,
every property by its declared type (a list as its count, then that many items), so each face
is the polygon the file says, of whatever size. A face of fewer than 3 corners, a count that
disagrees with the line, an index outside the vertices, a body shorter than the header says:
one :class:`RasterhwError` line naming the face.

:func:`read_ply` gives the vertices, each face's corner indices (one flat array and the offsets
where each face starts), and the file's vertex or face colours (``red``/``green``/``blue``) when
it has them; :mod:`rasterhw.golden_model.meshio` cuts the polygons into triangles.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["PlyMesh", "read_ply"]

#: PLY type names (both spellings) -> NumPy type codes
_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
#: NumPy type codes -> struct codes
_STRUCT = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f", "f8": "d"}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_INDEX_NAMES = ("vertex_indices", "vertex_index")


@dataclass
class PlyMesh:
    """What a PLY file holds for rendering."""

    vertices: np.ndarray            # (V, 3) float64
    corners: np.ndarray             # every face's vertex indices, one after the other (int64)
    starts: np.ndarray              # (F + 1,) where each face's corners start in ``corners``
    vertex_colours: np.ndarray | None = None   # (V, 3) in [0, 1]
    face_colours: np.ndarray | None = None     # (F, 3) in [0, 1]


@dataclass
class _Prop:
    name: str
    code: str                       # NumPy code of a scalar, or of a list's items
    count: str | None = None        # NumPy code of a list's count; None for a scalar


@dataclass
class _Element:
    name: str
    n: int
    props: list[_Prop]


def _header(path, raw: bytes) -> tuple[str | None, list[_Element], int]:
    """(byte order or None for ASCII, elements, offset of the body)."""
    m = re.search(rb"end_header[ \t]*(\r\n|\n|\r)", raw[:1 << 20])
    if not raw.startswith(b"ply") or m is None:
        raise RasterhwError(f"{path}: not a readable PLY mesh (no 'ply' ... 'end_header' header)")
    order, elements = "missing", []
    for lineno, line in enumerate(raw[:m.start()].decode("ascii", "replace").splitlines()[1:], 2):
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        try:
            if w[0] == "format":
                if w[1] not in _FORMATS:
                    raise RasterhwError(f"{path}: PLY format {w[1]!r} (ascii, binary_little_endian or binary_big_endian)")
                order = _FORMATS[w[1]]
            elif w[0] == "element":
                n = int(w[2])
                if n < 0:
                    raise ValueError
                elements.append(_Element(w[1], n, []))
            elif w[0] == "property" and w[1] == "list":
                elements[-1].props.append(_Prop(w[4], _TYPES[w[3]], _TYPES[w[2]]))
            elif w[0] == "property":
                elements[-1].props.append(_Prop(w[2], _TYPES[w[1]]))
            else:
                raise ValueError
        except (IndexError, KeyError, ValueError):
            raise RasterhwError(f"{path}: PLY header line {lineno} {line.strip()[:60]!r} is not a PLY header line") from None
    if order == "missing":
        raise RasterhwError(f"{path}: the PLY header has no format line")
    return order, elements, m.end()


def _colours(el: _Element, table: dict[str, np.ndarray]) -> np.ndarray | None:
    names = {p.name: p for p in el.props if p.count is None}
    if not all(c in names for c in ("red", "green", "blue")):
        return None
    cols = []
    for c in ("red", "green", "blue"):
        v = np.asarray(table[c], dtype=np.float64)
        kind = np.dtype(names[c].code).kind
        cols.append(np.clip(v, 0, 1) if kind == "f" else np.clip(v / 255.0, 0, 1))
    return np.stack(cols, axis=1)


def _face_prop(path, el: _Element) -> _Prop:
    lists = [p for p in el.props if p.count is not None]
    named = [p for p in lists if p.name in _INDEX_NAMES]
    if not (named or lists):
        raise RasterhwError(f"{path}: the PLY face element has no list of vertex indices")
    return (named or lists)[0]


# ------------------------------------------------------------------ binary
def _binary_element(path, el: _Element, raw: bytes, at: int, order: str,
                    want_lists: bool) -> tuple[dict[str, np.ndarray], list | None, int]:
    """Read element ``el`` at byte ``at``: (scalar columns, the index list's (corners, starts) or None, end)."""
    if all(p.count is None for p in el.props):   # fixed-size records: one read
        dt = np.dtype([(f"p{k}", order + p.code) for k, p in enumerate(el.props)])
        end = at + dt.itemsize * el.n
        if end > len(raw):
            raise RasterhwError(f"{path}: the PLY body ends inside element {el.name!r} ({el.n} {el.name}s declared)")
        rec = np.frombuffer(raw, dt, count=el.n, offset=at)
        return {p.name: rec[f"p{k}"] for k, p in enumerate(el.props)}, None, end
    face = _face_prop(path, el) if want_lists else None
    uniform = _uniform(el, raw, at, order)
    if uniform is not None:   # every list the same length (all triangles): one read too
        dt, counts = uniform
        end = at + dt.itemsize * el.n
        if end <= len(raw):
            rec = np.frombuffer(raw, dt, count=el.n, offset=at)
            if all(np.all(rec[f"n{k}"] == counts[k]) for k in counts):
                cols = {p.name: rec[f"p{k}"] for k, p in enumerate(el.props) if p.count is None}
                lists = None
                if face is not None:
                    k = el.props.index(face)
                    idx = np.asarray(rec[f"p{k}"], dtype=np.int64).reshape(el.n, counts[k])
                    lists = [idx.ravel(), np.arange(el.n + 1, dtype=np.int64) * counts[k]]
                return cols, lists, end
    # lists of varying length (quads and triangles mixed): record by record (struct: ~1 us a field)
    scal = {p.name: [] for p in el.props if p.count is None}
    fmt = {id(p): (struct.Struct(order + _STRUCT[p.count or p.code]), np.dtype(p.code).itemsize, _STRUCT[p.code])
           for p in el.props}
    corners, starts = [], [0]
    try:
        for _i in range(el.n):
            for p in el.props:
                one, size, code = fmt[id(p)]
                (v,) = one.unpack_from(raw, at)
                at += one.size
                if p.count is None:
                    scal[p.name].append(v)
                    continue
                if p is face:
                    corners.extend(struct.unpack_from(f"{order}{v}{code}", raw, at))
                    starts.append(starts[-1] + v)
                elif at + v * size > len(raw):
                    raise struct.error("short")
                at += v * size
    except struct.error:
        raise RasterhwError(f"{path}: the PLY body ends inside {el.name} {_i} ({el.n} {el.name}s declared)") from None
    lists = None
    if face is not None:
        lists = [np.asarray(corners, dtype=np.int64), np.asarray(starts, np.int64)]
    return {k: np.asarray(v) for k, v in scal.items()}, lists, at


def _uniform(el: _Element, raw: bytes, at: int, order: str):
    """A record type reading ``el`` if every list has the length of its first record's list."""
    counts, fields, pos = {}, [], at
    for k, p in enumerate(el.props):
        if p.count is None:
            fields.append((f"p{k}", order + p.code))
            pos += np.dtype(p.code).itemsize
            continue
        csize = np.dtype(p.count).itemsize
        if pos + csize > len(raw):
            return None
        n = int(np.frombuffer(raw, order + p.count, 1, pos)[0])
        if n <= 0:
            return None
        counts[k] = n
        fields += [(f"n{k}", order + p.count), (f"p{k}", order + p.code, (n,))]
        pos += csize + n * np.dtype(p.code).itemsize
    return np.dtype(fields), counts


# ------------------------------------------------------------------ ASCII
def _ascii_element(path, el: _Element, lines: list[bytes], row: int,
                   want_lists: bool) -> tuple[dict[str, np.ndarray], list | None, int]:
    rows = lines[row:row + el.n]
    if len(rows) < el.n:
        raise RasterhwError(f"{path}: the PLY body has {len(rows)} of the {el.n} {el.name} lines its header declares")
    if all(p.count is None for p in el.props):
        try:
            vals = np.array(b" ".join(rows).split(), dtype=np.float64)
        except ValueError:
            raise RasterhwError(f"{path}: a {el.name} line holds something that is not a number") from None
        if vals.size != el.n * len(el.props):
            raise RasterhwError(f"{path}: {el.name} lines do not hold {len(el.props)} numbers each")
        vals = vals.reshape(el.n, len(el.props)) if el.n else vals.reshape(0, len(el.props))
        return {p.name: vals[:, k] for k, p in enumerate(el.props)}, None, row + el.n
    face = _face_prop(path, el) if want_lists else None
    scal = {p.name: np.empty(el.n) for p in el.props if p.count is None}
    corners, starts = [], [0]
    last_is_list = el.props[-1].count is not None
    for i, ln in enumerate(rows):
        w = ln.split()
        at = 0
        for p in el.props:
            try:
                if p.count is None:
                    scal[p.name][i] = float(w[at])
                    at += 1
                    continue
                n = int(float(w[at]))
            except (IndexError, ValueError):
                raise RasterhwError(f"{path}: {el.name} {i}: {ln.decode('ascii', 'replace').strip()[:40]!r} "
                                    "does not hold what the header says") from None
            items = w[at + 1:at + 1 + n]
            if len(items) != n or (p is el.props[-1] and len(w) != at + 1 + n):
                if last_is_list:
                    raise RasterhwError(f"{path}: {el.name} {i} says {n} corners but lists {len(w) - at - 1}")
                raise RasterhwError(f"{path}: {el.name} {i} says {n} items but the line does not hold them")
            if p is face:
                try:
                    corners.append(np.array([int(x) for x in items], dtype=np.int64))
                except ValueError:
                    raise RasterhwError(f"{path}: face {i}: an index is not an integer") from None
                starts.append(starts[-1] + n)
            at += 1 + n
    lists = None
    if face is not None:
        lists = [np.concatenate(corners) if corners else np.zeros(0, np.int64), np.asarray(starts, np.int64)]
    return scal, lists, row + el.n


def read_ply(path: str | Path, raw: bytes) -> PlyMesh:
    """The mesh in ``raw`` (the bytes of PLY file ``path``): see the module docstring."""
    order, elements, body = _header(path, raw)
    vertex = next((e for e in elements if e.name == "vertex"), None)
    face = next((e for e in elements if e.name == "face"), None)
    if vertex is None or not all(any(p.name == c and p.count is None for p in vertex.props) for c in "xyz"):
        raise RasterhwError(f"{path}: the PLY file has no vertex element with x, y and z")
    if face is None:
        raise RasterhwError(f"{path}: no faces (the PLY file has no face element: a point cloud?)")
    tables: dict[str, tuple] = {}
    if order is None:
        lines = [ln for ln in re.split(rb"\r\n|\n|\r", raw[body:]) if ln.strip()]
        row = 0
        for el in elements:
            cols, lists, row = _ascii_element(path, el, lines, row, el is face)
            tables[el.name] = (cols, lists)
    else:
        at = body
        for el in elements:
            cols, lists, at = _binary_element(path, el, raw, at, order, el is face)
            tables[el.name] = (cols, lists)
    vcols, _ = tables["vertex"]
    verts = np.stack([np.asarray(vcols[c], dtype=np.float64) for c in "xyz"], axis=1)
    fcols, (corners, starts) = tables["face"]
    sizes = np.diff(starts)
    short = np.flatnonzero(sizes < 3)
    if short.size:
        k = int(short[0])
        raise RasterhwError(f"{path}: face {k} has {int(sizes[k])} vertices (a face needs at least 3)")
    if corners.size and (corners.min() < 0 or corners.max() >= len(verts)):
        k = int(np.searchsorted(starts, int(np.flatnonzero((corners < 0) | (corners >= len(verts)))[0]), "right") - 1)
        raise RasterhwError(f"{path}: face {k} refers to a vertex the file does not have ({len(verts)} vertices)")
    return PlyMesh(verts, corners, starts, _colours(vertex, vcols), _colours(face, fcols))
