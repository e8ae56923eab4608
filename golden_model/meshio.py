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
import warnings
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Camera, Light, Material, Scene

__all__ = ["MESH_EXTENSIONS", "load_mesh", "load_scene"]

MESH_EXTENSIONS = (".obj", ".ply")
_COORD_LIMIT = 1e15  # the Scene validator's limit
_GREY = (0.7, 0.7, 0.7)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    msg = text[0] if text else ""
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def _check_obj_faces(path: Path) -> None:
    """trimesh drops OBJ faces with fewer than 3 vertices silently: find them in the raw text."""
    try:
        with path.open("r", encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, 1):
                if line.startswith("f") and line[1:2].isspace():
                    n = len(line.split("#", 1)[0].split()) - 1
                    if n < 3:
                        raise RasterhwError(
                            f"{path}: line {lineno}: face has {n} vertices (a face needs at least 3)"
                        )
    except OSError as exc:
        raise RasterhwError(f"cannot read {path}: {_one_line(exc)}") from None


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


def _colours(mesh, nfaces: int) -> np.ndarray:
    """(F, 3, 3) corner colours in [0, 1]: the file's vertex or face colours, else grey."""
    visual = getattr(mesh, "visual", None)
    kind = getattr(visual, "kind", None)
    try:
        if kind == "vertex":
            vc = np.asarray(visual.vertex_colors, dtype=np.float64)[:, :3] / 255.0
            return vc[np.asarray(mesh.faces)]
        if kind == "face":
            fc = np.asarray(visual.face_colors, dtype=np.float64)[:, :3] / 255.0
            return np.repeat(fc[:, None, :], 3, axis=1)
    except Exception:
        pass
    return np.broadcast_to(np.array(_GREY), (nfaces, 3, 3)).copy()


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
    if ext == ".obj":
        _check_obj_faces(path)

    import trimesh

    # trimesh logs and warns about what it cannot parse; we report our own one-line error.
    log = logging.getLogger("trimesh")
    old_level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mesh = trimesh.load(str(path), force="mesh", process=False)
            faces = np.asarray(mesh.faces, dtype=np.int64)
            verts = np.asarray(mesh.vertices, dtype=np.float64)
    except RasterhwError:
        raise
    except Exception as exc:
        raise RasterhwError(f"{path}: not a readable {ext[1:].upper()} mesh ({_one_line(exc)})") from None
    finally:
        log.setLevel(old_level)

    if ext == ".ply":
        _check_ply_faces(path, mesh)
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
    col = _colours(mesh, len(faces))

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
