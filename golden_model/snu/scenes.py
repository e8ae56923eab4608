"""SNU scenes (found by ``golden_model/scenes.py``; recipes in docs/scenes.md)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.scene import Light, Material, Scene
from rasterhw.golden_model.scenekit import lift, random_outlines, screen_camera
from rasterhw.golden_model.scenes import SceneInfo

__all__ = ["SCENES"]


def _build_snu(seed: int, *, n: int = 2000, width: int = 1280, height: int = 1024, area: float = 100.0,
               name: str = "snu-100px") -> Scene:
    """Gouraud triangles of exactly ``area`` px each, random vertex colours, random depths."""
    rng = np.random.default_rng(seed)
    cam, f = screen_camera(height)
    tri = random_outlines(rng, n, np.full(n, area))
    r = np.abs(tri).max(axis=(1, 2))
    c = np.stack([rng.uniform(r, width - r), rng.uniform(r, height - r)], axis=1)
    dist = rng.uniform(0.5 * f, 1.5 * f, n)
    pos = lift(tri + c[:, None, :], dist[:, None], width, height, f, cam.eye[2])
    nrm = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pos.shape).copy()
    col = rng.random((n, 3, 3))
    return Scene(name=name, seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(n, 3, dtype=np.int64), lights=(Light(direction=(0.0, 0.0, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


SCENES: dict[str, SceneInfo] = {
    "snu-100px": SceneInfo("snu-100px", "2000 Gouraud triangles of 100 px, random vertex colours (SNU target)",
                           1280, 1024, _build_snu, 4, 2000),
    "snu-100k": SceneInfo("snu-100k", "100,000 Gouraud triangles of 100 px, random vertex colours: the SNU headline "
                          "frame (one second's work)", 1280, 1024,
                          lambda seed: _build_snu(seed, n=100_000, name="snu-100k"), 100, 100_000),
}
