"""SNU graphics system: a PHIGS-style structure store and its traversal (seed 004, section 4.1).

The paper's words (translated): the application links structures into a hierarchy stored as
*linked lists* in the CSS (Centralized Structure Store); geometry and attributes are stored
independently and *bound at traversal*; a ``post`` command starts the traversal, which binds
the linked lists, generates primitives and passes the graphics information on. For 3-vertex
polygons the traversal output per vertex is (x, y, z), (nx, ny, nz), (r, g, b): 9 real
values of 32 bits = 36 bytes per vertex, 108 bytes per polygon; at 100,000 polygons/s about
10 MB/s.

Model (decisions the paper leaves open are in ``docs/snu_geometry.md``):

* a :class:`CSS` maps structure ids to :class:`Structure` s, each a singly linked list of
  :class:`Element` s (``next`` pointers, appended at the tail);
* element kinds: ``execute`` (call another structure), ``local_transform`` (4x4 matrix
  composed with the current local transform: ``"replace"``, ``"pre"`` or ``"post"``),
  ``colour`` (interior colour attribute) and ``polygon3`` (corner positions, vertex normals,
  optional per-vertex colours);
* traversal state (PHIGS semantics): the *global* transform a structure inherits, its own
  *local* transform, and the current colour. ``execute`` pushes the state, starts the child
  with global = parent's composite (global @ local), local = identity, colour inherited,
  and pops it on return, so a child's attribute changes never leak to its parent;
* ``polygon3`` is fan-triangulated (the paper assumes 3-vertex polygons) and emitted in
  *world* coordinates: positions by the composite matrix, normals by its inverse transpose
  (not re-normalised: normalisation is a later pipeline stage, table 1). Colour is the
  element's vertex colour when it has one, otherwise the bound colour attribute.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene

__all__ = [
    "CSS",
    "RECORD_BYTES",
    "RECORD_DTYPE",
    "RECORD_FIELDS",
    "Element",
    "Structure",
    "TraversalOutput",
    "css_from_scene",
    "measure_traversal",
    "scene_triangles",
    "traversal_bandwidth",
]

RECORD_FIELDS = ("x", "y", "z", "nx", "ny", "nz", "r", "g", "b")
RECORD_DTYPE = np.dtype(np.float32)
#: bytes per emitted vertex record: 9 float32 = 36 (the paper's figure, computed here)
RECORD_BYTES = len(RECORD_FIELDS) * RECORD_DTYPE.itemsize

_KINDS = ("execute", "local_transform", "colour", "polygon3")
_MODES = ("replace", "pre", "post")


@dataclass
class Element:
    """One structure element; ``next`` links the structure's list."""

    kind: str
    data: object
    next: Element | None = None


@dataclass
class Structure:
    """A structure: a linked list of elements (``head`` .. ``tail``)."""

    sid: int
    head: Element | None = None
    tail: Element | None = None

    def append(self, element: Element) -> Element:
        if self.tail is None:
            self.head = self.tail = element
        else:
            self.tail.next = element
            self.tail = element
        return element

    def elements(self):
        e = self.head
        while e is not None:
            yield e
            e = e.next


@dataclass
class TraversalOutput:
    """What ``post`` hands to the geometry pipelines.

    Attributes
    ----------
    records : (3*T, 9) float32 -- x, y, z, nx, ny, nz, r, g, b per vertex, 3 per triangle.
    source : (T,) int64 -- the ``tag`` of the polygon3 element each triangle came from.
    stats : elements visited per kind, structures executed, deepest state stack.
    """

    records: np.ndarray
    source: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def n_triangles(self) -> int:
        return int(self.records.shape[0] // 3)

    @property
    def nbytes(self) -> int:
        return int(self.records.shape[0]) * RECORD_BYTES

    def triangles(self) -> np.ndarray:
        """Records reshaped to (T, 3, 9)."""
        return self.records.reshape(-1, 3, len(RECORD_FIELDS))


def _matrix(m) -> np.ndarray:
    m = np.asarray(m, dtype=np.float64)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise RasterhwError(f"a local transform must be a finite 4x4 matrix, got shape {m.shape}")
    if abs(np.linalg.det(m[:3, :3])) < 1e-300:
        raise RasterhwError("a local transform has a singular 3x3 part (normals cannot be transformed)")
    return m


class CSS:
    """Centralized Structure Store: structures as linked lists of elements."""

    def __init__(self) -> None:
        self.structures: dict[int, Structure] = {}

    def structure(self, sid: int) -> Structure:
        """The structure ``sid``, created empty on first use (PHIGS *open structure*)."""
        if isinstance(sid, bool) or not isinstance(sid, (int, np.integer)):
            raise RasterhwError(f"structure id must be an integer, not {sid!r}")
        return self.structures.setdefault(int(sid), Structure(int(sid)))

    # element constructors (PHIGS: execute structure, set local transformation 3,
    # set interior colour, polygon set 3 with data)
    def execute(self, sid: int, child: int) -> Element:
        if isinstance(child, bool) or not isinstance(child, (int, np.integer)):
            raise RasterhwError(f"execute needs a structure id, not {child!r}")
        return self.structure(sid).append(Element("execute", int(child)))

    def local_transform(self, sid: int, matrix, mode: str = "replace") -> Element:
        if mode not in _MODES:
            raise RasterhwError(f"local transform mode must be one of {_MODES}, not {mode!r}")
        return self.structure(sid).append(Element("local_transform", (_matrix(matrix), mode)))

    def colour(self, sid: int, rgb) -> Element:
        c = np.asarray(rgb, dtype=np.float64)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise RasterhwError(f"a colour must be 3 finite values, got {rgb!r}")
        return self.structure(sid).append(Element("colour", c))

    def polygon3(self, sid: int, points, normals, colours=None, *, tag: int = -1) -> Element:
        p = np.asarray(points, dtype=np.float64)
        nrm = np.asarray(normals, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 3:
            raise RasterhwError(f"polygon3 needs (n>=3, 3) points, got shape {p.shape}")
        if nrm.shape != p.shape:
            raise RasterhwError(f"polygon3 normals must be {p.shape}, got {nrm.shape}")
        c = None
        if colours is not None:
            c = np.asarray(colours, dtype=np.float64)
            if c.shape != p.shape:
                raise RasterhwError(f"polygon3 colours must be {p.shape}, got {c.shape}")
        for what, a in (("point", p), ("normal", nrm), ("colour", c)):
            if a is not None and not np.all(np.isfinite(a)):
                raise RasterhwError(f"polygon3 has a NaN or infinite {what}")
        return self.structure(sid).append(Element("polygon3", (p, nrm, c, int(tag))))

    # traversal
    def post(self, root: int, *, max_depth: int = 64) -> TraversalOutput:
        """Traverse from ``root``, binding attributes, and emit per-vertex records.

        Raises :class:`RasterhwError` for an unknown structure, an unknown element kind, or a
        structure network deeper than ``max_depth`` (which is how a cycle shows up).
        """
        if int(root) not in self.structures:
            raise RasterhwError(f"post: no structure {root!r} in the CSS")
        recs: list[np.ndarray] = []
        tags: list[int] = []
        stats = {k: 0 for k in _KINDS} | {"structures": 0, "max_stack": 0}
        eye = np.eye(4)
        # Explicit traversal state stack: (element to resume at, global, local, colour).
        stack: list[tuple] = []
        glob, local, colour = eye, eye.copy(), np.ones(3)
        element = self.structures[int(root)].head
        stats["structures"] = 1
        while True:
            if element is None:
                if not stack:
                    break
                element, glob, local, colour = stack.pop()
                continue
            kind = element.kind
            if kind not in _KINDS:
                raise RasterhwError(f"post: unknown element kind {kind!r}")
            stats[kind] += 1
            if kind == "execute":
                child = element.data
                if child not in self.structures:
                    raise RasterhwError(f"post: execute of missing structure {child!r}")
                if len(stack) >= max_depth:
                    raise RasterhwError(f"post: structure network deeper than {max_depth} (a cycle?)")
                stack.append((element.next, glob, local, colour))
                stats["max_stack"] = max(stats["max_stack"], len(stack))
                stats["structures"] += 1
                glob, local = glob @ local, eye.copy()
                element = self.structures[child].head
                continue
            if kind == "local_transform":
                m, mode = element.data
                local = m if mode == "replace" else (m @ local if mode == "pre" else local @ m)
            elif kind == "colour":
                colour = element.data
            else:
                p, nrm, c, tag = element.data
                comp = glob @ local
                pw = p @ comp[:3, :3].T + comp[:3, 3]
                nw = nrm @ np.linalg.inv(comp[:3, :3])  # (M^-T n) as row vectors
                cw = np.broadcast_to(colour, p.shape) if c is None else c
                v = np.concatenate([pw, nw, cw], axis=1)
                fan = np.stack([np.zeros(len(p) - 2, dtype=np.int64),
                                np.arange(1, len(p) - 1), np.arange(2, len(p))], axis=1)
                recs.append(v[fan.ravel()])
                tags.extend([tag] * (len(p) - 2))
            element = element.next
        records = (np.concatenate(recs) if recs else np.zeros((0, 9))).astype(RECORD_DTYPE)
        return TraversalOutput(records=records, source=np.asarray(tags, dtype=np.int64), stats=stats)


def traversal_bandwidth(polys_per_s: float = 100_000) -> float:
    """Bytes/s from traversal to the pipelines: ``polys_per_s * 3 * RECORD_BYTES``.

    The paper: 108 bytes per polygon, "about 10 MB/s" at 100,000 polygons/s; this gives
    10.8e6 for the default.
    """
    if not np.isfinite(polys_per_s) or polys_per_s < 0:
        raise RasterhwError(f"polys_per_s must be a finite number >= 0, not {polys_per_s!r}")
    return float(polys_per_s) * 3 * RECORD_BYTES


#: The dual-port memories between the stages (3.1): "256 KByte RAM, 16 bits at a time".
DPM_BYTES = 256 * 1024
DPM_WIDTH_BYTES = 2


def measure_traversal(scene: Scene, *, polys_per_s: float = 100_000, polys_per_object: int = 6,
                      clock_hz: float = 40e6, bus_clocks_per_transfer: int = 2) -> dict:
    """Build the scene's structure store, ``post`` it, and measure what the traversal emits.

    Returns ``triangles``, ``bytes`` (the records really emitted), ``bytes_per_triangle``,
    ``bandwidth`` (bytes/s at ``polys_per_s``), ``post_s`` (host seconds of the traversal model,
    not an i860 figure) and the dual-port memory beside it: ``dpm_rate`` (one 16-bit transfer
    per i860 bus cycle of ``bus_clocks_per_transfer`` clocks -- our assumption, the paper gives
    no memory timing), ``dpm_triangles`` (records that fit in 256 KB) and ``elements`` visited.
    """
    import time

    css = css_from_scene(scene, polys_per_object=polys_per_object)
    t0 = time.perf_counter()
    out = css.post(0)
    post_s = time.perf_counter() - t0
    t = out.n_triangles
    if t == 0:
        raise RasterhwError(f"scene {scene.name!r}: the traversal emitted no triangles")
    per = out.nbytes / t
    return {"triangles": t, "bytes": out.nbytes, "bytes_per_triangle": per, "bandwidth": per * polys_per_s,
            "post_s": post_s, "elements": sum(out.stats[k] for k in _KINDS),
            "structures": out.stats["structures"],
            "dpm_rate": DPM_WIDTH_BYTES * clock_hz / bus_clocks_per_transfer,
            "dpm_triangles": DPM_BYTES // int(per)}


def _translate(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = t
    return m


def css_from_scene(scene: Scene, *, polys_per_object: int = 6, root: int = 0) -> CSS:
    """Turn a scene's polygons into a small hierarchy whose traversal gives the same triangles.

    Polygons are cut, in order, into objects of ``polys_per_object``; each object becomes one
    structure holding its polygons in *local* coordinates (centred on the object's mean corner
    position) and is executed from the root under a translation back to where it was. A
    polygon whose corners share one colour is stored without vertex colours, after a
    ``colour`` attribute element (emitted only when the colour changes), so the colour comes
    from the attribute bound at traversal; other polygons carry vertex colours. Every
    polygon3 is tagged with its scene polygon index.
    """
    if not isinstance(scene, Scene):
        raise RasterhwError(f"css_from_scene needs a Scene, not {type(scene).__name__}")
    if isinstance(polys_per_object, bool) or not isinstance(polys_per_object, int) or polys_per_object < 1:
        raise RasterhwError(f"polys_per_object must be a positive integer, not {polys_per_object!r}")
    css = CSS()
    css.structure(root)
    sid = root + 1
    for first in range(0, scene.n_polygons, polys_per_object):
        idx = range(first, min(first + polys_per_object, scene.n_polygons))
        corners = np.concatenate([scene.positions[p, : scene.nverts[p]] for p in idx])
        centre = corners.mean(axis=0)
        css.local_transform(root, _translate(centre), "replace")
        css.execute(root, sid)
        bound = None
        for p in idx:
            n = int(scene.nverts[p])
            pos = scene.positions[p, :n] - centre
            col = scene.colours[p, :n]
            if np.all(col == col[0]):
                if bound is None or not np.array_equal(bound, col[0]):
                    css.colour(sid, col[0])
                    bound = col[0]
                css.polygon3(sid, pos, scene.normals[p, :n], tag=p)
            else:
                css.polygon3(sid, pos, scene.normals[p, :n], col, tag=p)
        sid += 1
    return css


def scene_triangles(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The scene's polygons fan-triangulated directly: ((T, 3, 9) float64 records, (T,) polygon).

    The expectation :func:`css_from_scene` + ``post`` must reproduce.
    """
    tris, src = [], []
    for p in range(scene.n_polygons):
        n = int(scene.nverts[p])
        v = np.concatenate([scene.positions[p, :n], scene.normals[p, :n], scene.colours[p, :n]], axis=1)
        for k in range(1, n - 1):
            tris.append(v[[0, k, k + 1]])
            src.append(p)
    return np.asarray(tris), np.asarray(src, dtype=np.int64)
