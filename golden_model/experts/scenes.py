"""EXPERTS scenes (found by ``golden_model/scenes.py``; recipes in docs/scenes.md).

* ``experts-1000`` / ``-2000``: Fr screen-parallel triangles, all on screen, total screen area
  Dc * 512 * 512 with Dc = 3, one depth per face (faces never interpenetrate).

* ``experts-tilt-1000`` / ``-2000``: the ``experts-{Fr}`` recipe (Fr triangles, all on screen,
  total screen area exactly Dc * 512 * 512 with Dc = 3) with every *vertex* at its own eye
  distance, ``d_face * (1 + U(-0.08, 0.08))`` with ``d_face ~ U(0.85, 1.15) F``: faces are tilted (dz/dx != 0), and overlapping
  faces interpenetrate, so segments cross within a line and the L-sort has work. Lifting a
  screen point along its eye ray keeps its screen position, so Fr and Dc are kept exactly.
* ``experts-solid-5/9/15/20`` and ``experts-solids``: the four solids of table 2.1, built as
  convex hulls and viewed so that the number of visible edges is the table's "線分の数":
  三角錐 (triangular pyramid, 2 faces seen: 5 edges), 四角柱 (square prism, 3 faces: 9),
  八角錐 (octagonal pyramid, 7 of its 8 sides seen: 15) and, for the illegible fourth
  ("カウ-ハーン(類2)"), our choice: a regular dodecahedron seen along a face normal (6 faces:
  20 edges). ``experts-solids`` puts all four in one frame.
* ``experts-uneven``: load balancing: 850 small triangles crowded into the top-left corner
  (x < 176, y < 200) over 150 large ones spread over the frame -- deliberately uneven in x
  (PXP ranges) and in y (SLP bands).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from rasterhw.golden_model.scene import Camera, Light, Material, Scene
from rasterhw.golden_model.scenekit import lift, project, random_outlines, screen_camera, unit
from rasterhw.golden_model.scenes import SceneInfo

__all__ = ["SCENES", "build_tilt", "build_solid", "build_solids", "build_pyramid", "build_uneven", "SOLIDS",
           "PYRAMID_FAMILY", "visible_edges"]


def _screen(height: int = 512):
    return screen_camera(height)


def _placed(rng: np.random.Generator, fr: int, width: int, height: int, dc: float) -> np.ndarray:
    """``fr`` triangle outlines (fr, 3, 2) in screen pixels, all on screen, total area
    ``dc * width * height`` (areas uniform in 0.5..1.5 of the mean, centres uniform)."""
    area = rng.uniform(0.5, 1.5, fr)
    area *= dc * width * height / area.sum()
    tri = random_outlines(rng, fr, area)
    r = np.abs(tri).max(axis=(1, 2))
    c = np.stack([rng.uniform(r, width - r), rng.uniform(r, height - r)], axis=1)
    return tri + c[:, None, :]


def _faces(name: str, seed: int, cam: Camera, pos: np.ndarray, nrm: np.ndarray, rng: np.random.Generator) -> Scene:
    """The scene of triangles ``pos`` / ``nrm``: one random colour per face, the EXPERTS light."""
    fr = len(pos)
    col = np.repeat(0.2 + 0.8 * rng.random((fr, 1, 3)), 3, axis=1)
    return Scene(name=name, seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(fr, 3, dtype=np.int64), lights=(Light(direction=(-0.3, -0.4, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


def _tilted(name: str, seed: int, fr: int, *, width=512, height=512, dc=3.0, tilt=0.08) -> Scene:
    rng = np.random.default_rng(seed)
    cam, f = _screen(height)
    sxy = _placed(rng, fr, width, height, dc)
    dist = rng.uniform(0.85 * f, 1.15 * f, fr)[:, None] * (1 + rng.uniform(-tilt, tilt, (fr, 3)))
    pos = lift(sxy, dist, width, height, f, cam.eye[2])
    # smooth-shading normals: the face's own normal, tilted per vertex by up to ~0.4 rad
    fn = unit(np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0]))
    nrm = unit(fn[:, None, :] + rng.uniform(-0.4, 0.4, (fr, 3, 3)))
    return _faces(name, seed, cam, pos, nrm, rng)


def build_tilt(fr: int):
    def build(seed: int) -> Scene:
        return _tilted(f"experts-tilt-{fr}", seed, fr)
    return build


# --------------------------------------------------------------------------- solids of table 2.1


def _hull_faces(v: np.ndarray) -> list[np.ndarray]:
    """Faces of the convex hull of points ``v`` (N, 3), each corner list counter-clockwise from outside."""
    n = len(v)
    cen = v.mean(axis=0)
    faces, seen = [], set()
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                nrm = np.cross(v[j] - v[i], v[k] - v[i])
                ln = np.linalg.norm(nrm)
                if ln < 1e-9:
                    continue
                nrm /= ln
                d = (v - v[i]) @ nrm
                if np.all(d <= 1e-9):
                    pass
                elif np.all(d >= -1e-9):
                    nrm, d = -nrm, -d
                else:
                    continue
                on = tuple(np.flatnonzero(np.abs(d) <= 1e-9))
                if on in seen:
                    continue
                seen.add(on)
                pts = v[list(on)]
                c = pts.mean(axis=0)
                u = pts[0] - c
                u /= np.linalg.norm(u)
                w = np.cross(nrm, u)
                ang = np.arctan2((pts - c) @ w, (pts - c) @ u)
                face = pts[np.argsort(ang)]
                if np.dot(np.cross(face[1] - face[0], face[2] - face[0]), c - cen) < 0:
                    face = face[::-1]
                faces.append(face)
    return faces


def _pyramid(n: int, h: float) -> np.ndarray:
    a = 2 * np.pi * np.arange(n) / n + np.pi / n
    return np.vstack([np.stack([np.cos(a), np.zeros(n), np.sin(a)], axis=1), [[0.0, h, 0.0]]])


def _prism(n: int, h: float) -> np.ndarray:
    a = 2 * np.pi * np.arange(n) / n + np.pi / n
    ring = np.stack([np.cos(a), np.zeros(n), np.sin(a)], axis=1)
    return np.vstack([ring, ring + [0.0, h, 0.0]])


def _dodecahedron() -> np.ndarray:
    p = (1 + 5 ** 0.5) / 2
    v = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    for a in (-1, 1):
        for b in (-1, 1):
            v += [(0, a / p, b * p), (a / p, b * p, 0), (a * p, 0, b / p)]
    return np.array(v, dtype=float)


def _view(direction) -> np.ndarray:
    d = np.asarray(direction, dtype=float)
    return d / np.linalg.norm(d)


#: name -> (vertices, view direction from the solid towards the eye, paper's line segments)
SOLIDS = {
    "5": ("三角錐 triangular pyramid", lambda: _pyramid(3, 1.4), _view((0.15, 0.55, 1.0)), 5),
    "9": ("四角柱 square prism", lambda: _prism(4, 1.6), _view((0.8, 0.7, 1.0)), 9),
    "15": ("八角錐 octagonal pyramid", lambda: _pyramid(8, 1.2), _view((0.2, 1.3, 1.0)), 15),
    "20": ("dodecahedron (our choice for the illegible fourth solid)", _dodecahedron, None, 20),
}


#: ours, not the paper's: n-gonal pyramids seen from above their apex (all n sides and the base
#: ring visible: 2n edges), the same size, so that only the number of edges varies
PYRAMID_FAMILY = {f"pyramid-{n}": (f"{n}-gonal pyramid from above (ours)", lambda n=n: _pyramid(n, 1.2),
                                   _view((0.0, 1.0, 0.3)), 2 * n) for n in (3, 4, 8, 10)}


def _solid_polys(key: str, rng: np.random.Generator, centre, scale: float):
    _, verts, view, _ = SOLIDS[key] if key in SOLIDS else PYRAMID_FAMILY[key]
    v = verts()
    v = v - (v.min(axis=0) + v.max(axis=0)) / 2
    v = v / np.abs(v).max()
    faces = _hull_faces(v)
    if view is None:  # dodecahedron: look along the normal of one face
        f0 = faces[0]
        view = _view(np.cross(f0[1] - f0[0], f0[2] - f0[0]))
    # rotate so that ``view`` becomes +z (towards the eye, which looks down -z)
    z = view
    x = np.cross((0.0, 1.0, 0.0), z)
    if np.linalg.norm(x) < 1e-6:
        x = np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    rot = np.stack([x, y, z])
    out = []
    for fc in faces:
        p = (fc @ rot.T) * scale + centre
        out.append(p)
    cols = 0.35 + 0.65 * rng.random((len(out), 3))
    return out, cols


def visible_edges(scene: Scene) -> int:
    """Edges of front-facing polygons (orthographic test along the camera axis is not used:
    the winding on screen decides, as in the pipeline)."""
    sxy, _ = project(scene, 512, 512)
    edges = set()
    for p in range(scene.n_polygons):
        k = int(scene.nverts[p])
        q = sxy[p, :k]
        x, y = q[:, 0], -q[:, 1]
        if 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) <= 0:
            continue
        w = scene.positions[p, :k]
        for i in range(k):
            a, b = tuple(np.round(w[i], 6)), tuple(np.round(w[(i + 1) % k], 6))
            edges.add((min(a, b), max(a, b)))
    return len(edges)


def _solids_scene(name: str, seed: int, keys, centres, scale: float) -> Scene:
    rng = np.random.default_rng(seed)
    polys, cols = [], []
    for key, c in zip(keys, centres, strict=True):
        p, col = _solid_polys(key, rng, np.asarray(c, dtype=float), scale)
        polys += p
        cols.append(col)
    cols = np.concatenate(cols)
    pos, nv = Scene.pad(polys)
    nrm = np.zeros_like(pos)
    for i, p in enumerate(polys):
        nn = np.cross(p[1] - p[0], p[2] - p[0])
        nrm[i] = nn / np.linalg.norm(nn)
    col = np.broadcast_to(cols[:, None, :], pos.shape).copy()
    dist = 12.0
    cam = Camera(eye=(0.0, 0.0, dist), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fovy_deg=30.0,
                 near=dist / 3, far=dist * 3)
    return Scene(name=name, seed=seed, camera=cam, positions=pos, normals=nrm, colours=col, nverts=nv,
                 lights=(Light(direction=(-0.4, -0.6, -1.0)),), ambient=(0.25, 0.25, 0.25),
                 material=Material(ka=1.0, kd=0.75, ks=0.0))


def build_solid(key: str):
    def build(seed: int) -> Scene:
        return _solids_scene(f"experts-solid-{key}", seed, [key], [(0.0, 0.0, 0.0)], 2.2)
    return build


def build_pyramid(n: int):
    """``experts-pyramid-{n}`` (ours): an n-gonal pyramid of the family :data:`PYRAMID_FAMILY`."""
    def build(seed: int) -> Scene:
        return _solids_scene(f"experts-pyramid-{n}", seed, [f"pyramid-{n}"], [(0.0, 0.0, 0.0)], 2.2)
    return build


def build_solids(seed: int) -> Scene:
    return _solids_scene("experts-solids", seed, list(SOLIDS), [(-1.6, 1.6, 0), (1.6, 1.6, 0),
                                                                (-1.6, -1.6, 0), (1.6, -1.6, 0)], 1.25)


# --------------------------------------------------------------------------- uneven load


def build_uneven(seed: int, *, width: int = 512, height: int = 512) -> Scene:
    rng = np.random.default_rng(seed)
    cam, f = _screen(height)
    ns, nb = 850, 150
    small = random_outlines(rng, ns, rng.uniform(20.0, 60.0, ns))
    rs = np.abs(small).max(axis=(1, 2))
    cs = np.stack([rng.uniform(rs, 176 - rs), rng.uniform(rs, 200 - rs)], axis=1)
    big_area = rng.uniform(0.5, 1.5, nb)
    big_area *= 1.0 * width * height / big_area.sum()
    big = random_outlines(rng, nb, big_area)
    rb = np.abs(big).max(axis=(1, 2))
    cb = np.stack([rng.uniform(rb, width - rb), rng.uniform(rb, height - rb)], axis=1)
    sxy = np.concatenate([small + cs[:, None], big + cb[:, None]])
    n = ns + nb
    dist = rng.uniform(0.85 * f, 1.15 * f, n)[:, None] * (1 + rng.uniform(-0.08, 0.08, (n, 3)))
    pos = lift(sxy, dist, width, height, f, cam.eye[2])
    fn = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    fn /= np.linalg.norm(fn, axis=1, keepdims=True)
    nrm = np.broadcast_to(fn[:, None, :], pos.shape).copy()
    col = np.repeat(0.2 + 0.8 * rng.random((n, 1, 3)), 3, axis=1)
    return Scene(name="experts-uneven", seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(n, 3, dtype=np.int64), lights=(Light(direction=(-0.3, -0.4, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


# --------------------------------------------------------------------------- flat faces (fig. 4.1)


def _build_experts(fr: int) -> Callable[[int], Scene]:
    def build(seed: int, *, width: int = 512, height: int = 512, dc: float = 3.0) -> Scene:
        """``fr`` screen-parallel triangles, all on screen, total area ``dc * width * height``."""
        rng = np.random.default_rng(seed)
        cam, f = _screen(height)
        sxy = _placed(rng, fr, width, height, dc)
        dist = rng.uniform(0.5 * f, 1.5 * f, fr)  # one depth per face: faces never interpenetrate
        pos = lift(sxy, dist[:, None], width, height, f, cam.eye[2])
        # Smooth-shading normals: tilted up to ~30 degrees from the face normal, per vertex.
        tilt = rng.uniform(-0.55, 0.55, (fr, 3, 2))
        nrm = unit(np.concatenate([tilt, np.ones((fr, 3, 1))], axis=-1))
        return _faces(f"experts-{fr}", seed, cam, pos, nrm, rng)

    return build


SCENES: dict[str, SceneInfo] = {
    **{
        f"experts-{fr}": SceneInfo(f"experts-{fr}", f"Fr = {fr} front-facing triangles at depth complexity 3 "
                                   "(EXPERTS fig. 4.1)", 512, 512, _build_experts(fr), fr, fr)
        for fr in (1000, 2000)
    },
    # tilted, interpenetrating faces (same Fr, Dc), table 2.1's solids, an uneven load
    **{
        f"experts-tilt-{fr}": SceneInfo(f"experts-tilt-{fr}", f"Fr = {fr} tilted, interpenetrating triangles at "
                                        "Dc = 3 (EXPERTS fig. 4.1)", 512, 512, build_tilt(fr), fr, fr)
        for fr in (1000, 2000)
    },
    **{
        f"experts-solid-{k}": SceneInfo(f"experts-solid-{k}", f"EXPERTS table 2.1 solid with {k} visible edges",
                                        512, 512, build_solid(str(k)), 21, n)
        for k, n in ((5, 4), (9, 6), (15, 9), (20, 12))
    },
    "experts-solids": SceneInfo("experts-solids", "the four solids of EXPERTS table 2.1 in one frame",
                                512, 512, build_solids, 21, 31),
    "experts-uneven": SceneInfo("experts-uneven", "850 small triangles crowded top-left over 150 large ones "
                                "(EXPERTS load balancing)", 512, 512, build_uneven, 8, 1000),
}
