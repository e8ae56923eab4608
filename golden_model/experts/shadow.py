"""Shadows by shadow polygons in the scan line (Crow 1977) -- **our choice**.

The paper says only that the scan-line algorithm can shadow "shadowing を従来のアルゴリズムの少しの
変更で実現することができる" and that shadowing is part of the design; it gives no method. Crow's shadow
polygons fit a scan-line machine: they are extra segments in the ASL, invisible, that only count.

For the first light (parallel, travelling along ``L``) every polygon facing it casts a volume: the
polygon itself (near cap) and one quad per edge swept along ``L`` far past the scene; every face is
wound so that its normal points out of the volume. The faces go through the geometry pipeline twice,
as wound and reversed: whichever survives the back-face cull says whether the eye sees the face's
outside (+1, the line of sight enters the volume) or its inside (-1, it leaves). A visible point is
in shadow when the signed count of shadow faces in front of it is positive, leaving out the faces of
its own polygon's volume (a polygon does not shadow itself; the eye is outside every volume in our
scenes). Shadowed intensity is ``SHADOW_ATTEN`` times the lit one (our stand-in for "ambient only":
the ASB keeps one intensity per vertex, not its ambient part).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scene import Material, Scene
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = ["ShadowFaces", "shadow_faces", "SHADOW_ATTEN", "SHADOW_ATTEN_Q8"]

SHADOW_ATTEN = 0.4
SHADOW_ATTEN_Q8 = 102   # the bit model: level * 102 >> 8


@dataclass
class ShadowFaces:
    tris: ScreenTriangles     # screen triangles of the surviving shadow faces
    sign: np.ndarray          # (T,) +1 entering, -1 leaving
    owner: np.ndarray         # (T,) scene polygon whose volume the face bounds
    n_faces: int              # shadow faces built (before the cull)


def _newell(p: np.ndarray) -> np.ndarray:
    q = np.roll(p, -1, axis=0)
    return np.cross(p, q).sum(axis=0)


def shadow_faces(scene: Scene, width: int, height: int, *, z_bits: int = 16) -> ShadowFaces:
    """The shadow faces of ``scene``'s first light, through the geometry pipeline."""
    L = np.asarray(scene.lights[0].direction, dtype=float)
    L = L / np.linalg.norm(L)
    used = np.arange(scene.max_corners)[None, :] < scene.nverts[:, None]
    pts = scene.positions[used]
    far = 4.0 * float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) + 1.0
    faces, owner = [], []
    for p in range(scene.n_polygons):
        poly = scene.positions[p, :int(scene.nverts[p])]
        n = _newell(poly)
        if np.dot(n, -L) <= 1e-12 * np.linalg.norm(n):
            continue  # not lit: casts nothing
        faces.append(poly.copy())
        owner.append(p)
        c = poly.mean(axis=0)
        for i in range(len(poly)):
            a, b = poly[i], poly[(i + 1) % len(poly)]
            q = np.array([a, b, b + far * L, a + far * L])
            nq = np.cross(b - a, far * L)
            if np.dot(nq, (a + b) / 2 - c) < 0:
                q = q[::-1].copy()
            faces.append(q)
            owner.append(p)
    if not faces:
        empty = ScreenTriangles(width, height, np.zeros((0, 3, 2)), np.zeros((0, 3)), np.zeros((0, 3), np.int64),
                                np.zeros((0, 3, 3)), np.zeros(0, np.int64))
        return ShadowFaces(empty, np.zeros(0, np.int64), np.zeros(0, np.int64), 0)
    both = []
    for f in faces:
        both += [f, f[::-1].copy()]
    pos, nv = Scene.pad(both)
    nrm = np.zeros_like(pos)
    for i, f in enumerate(both):
        nrm[i] = _newell(f)
    col = np.full_like(pos, 0.5)
    sc = Scene(name=f"{scene.name}-shadow-faces", positions=pos, normals=nrm, colours=col, nverts=nv,
               camera=scene.camera, lights=scene.lights, ambient=(1.0, 1.0, 1.0),
               material=Material(ka=1.0, kd=0.0, ks=0.0))
    tris = run_geometry(sc, width, height, z_bits=z_bits)
    face = tris.poly_id // 2
    sign = np.where(tris.poly_id % 2 == 0, 1, -1).astype(np.int64)
    return ShadowFaces(tris, sign, np.asarray(owner, dtype=np.int64)[face], len(faces))
