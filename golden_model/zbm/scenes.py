"""ZB/M scenes (found by ``golden_model/scenes.py``; recipes in docs/scenes.md)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.scene import Light, Material, Scene
from rasterhw.golden_model.scenekit import lift, screen_camera
from rasterhw.golden_model.scenes import SceneInfo

__all__ = ["SCENES"]


def _build_zbm(seed: int, *, n: int = 1000, width: int = 512, height: int = 512) -> Scene:
    """Screen-facing diamonds 10 px wide and 10 px tall: two edge pairs of 5 rows x 25 px each."""
    rng = np.random.default_rng(seed)
    cam, f = screen_camera(height)
    cx = rng.integers(5, width - 5, n) + 0.25  # 0.25 px off the pixel centres' x
    ty = rng.integers(0, height - 10 + 1, n).astype(float)
    # Counter-clockwise seen from the camera: top -> left -> bottom -> right.
    sxy = np.stack([np.stack([cx, ty], 1), np.stack([cx - 5, ty + 5], 1),
                    np.stack([cx, ty + 10], 1), np.stack([cx + 5, ty + 5], 1)], axis=1)
    dist = rng.uniform(0.5 * f, 1.5 * f, n)
    pos = lift(sxy, dist[:, None], width, height, f, cam.eye[2])
    nrm = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pos.shape).copy()
    col = rng.uniform(0.1, 1.0, (n, 4, 3))
    return Scene(name="zbm-5x5", seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(n, 4, dtype=np.int64), lights=(Light(direction=(0.0, 0.0, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


SCENES: dict[str, SceneInfo] = {
    "zbm-5x5": SceneInfo("zbm-5x5", "1000 screen-facing diamonds, each two 5x5-pixel edge pairs (ZB/M table 1)",
                         512, 512, _build_zbm, 3, 1000),
}
