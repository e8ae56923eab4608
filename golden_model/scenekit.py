"""Building blocks of the built-in scenes, shared by ``golden_model/scenes.py`` and the machines'
``golden_model/NAME/scenes.py``: the screen camera, lifting screen points into the world, random
triangle outlines of a given area, and projecting a scene's corners back to the screen.

The convention (see ``golden_model/scenes.py``): a point meant for pixel position ``(sx, sy)``
at eye distance ``d`` goes to ``X = (sx - w/2) d / F``, ``Y = (h/2 - sy) d / F``, ``Z = D - d``
with the eye at ``(0, 0, D)`` looking down ``-z`` and ``F = (h/2) / tan(fovy/2)``.
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.scene import Camera, Scene

__all__ = ["focal_px", "lift", "project", "random_outlines", "screen_camera", "unit"]


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def focal_px(height: int, fovy_deg: float) -> float:
    return (height / 2) / math.tan(math.radians(fovy_deg) / 2)


def lift(sxy: np.ndarray, dist: np.ndarray, width: int, height: int, f: float, eye_z: float) -> np.ndarray:
    """Screen points (…, 2) in pixels at eye distance ``dist`` (… broadcast) -> world (…, 3)."""
    x = (sxy[..., 0] - width / 2) * dist / f
    y = (height / 2 - sxy[..., 1]) * dist / f
    z = np.broadcast_to(eye_z - dist, x.shape)
    return np.stack([x, y, z], axis=-1)


def screen_camera(height: int, fovy_deg: float = 45.0) -> tuple[Camera, float]:
    f = focal_px(height, fovy_deg)
    cam = Camera(eye=(0.0, 0.0, f), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                 fovy_deg=fovy_deg, near=0.25 * f, far=2.0 * f)
    return cam, f


def random_outlines(rng: np.random.Generator, n: int, area_px: np.ndarray) -> np.ndarray:
    """``n`` roughly equilateral triangle outlines centred on 0 with exact ``area_px`` (n,).

    Returned (n, 3, 2) in *screen* pixels (y down), counter-clockwise as seen on the monitor
    with y up, i.e. counter-clockwise seen from the camera.
    """
    ang = rng.uniform(0, 2 * np.pi, (n, 1)) + (2 * np.pi / 3) * np.arange(3)[None, :]
    ang = ang + rng.uniform(-0.35, 0.35, (n, 3))
    rad = rng.uniform(0.7, 1.3, (n, 3))
    ox, oy = rad * np.cos(ang), rad * np.sin(ang)  # y up
    a = 0.5 * ((ox[:, 1] - ox[:, 0]) * (oy[:, 2] - oy[:, 0]) - (ox[:, 2] - ox[:, 0]) * (oy[:, 1] - oy[:, 0]))
    k = np.sqrt(area_px / a)[:, None]
    return np.stack([ox * k, -oy * k], axis=-1)  # screen y down


def project(scene: Scene, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Corners -> (P, K, 2) screen pixels (y down) and (P, K) eye depth along the view axis."""
    cam = scene.camera
    eye = np.asarray(cam.eye, dtype=float)
    fwd = unit(np.asarray(cam.target, dtype=float) - eye)
    side = unit(np.cross(fwd, np.asarray(cam.up, dtype=float)))
    up = np.cross(side, fwd)
    rel = scene.positions - eye
    xc, yc, zc = rel @ side, rel @ up, rel @ fwd
    f = focal_px(height, cam.fovy_deg)
    with np.errstate(divide="ignore", invalid="ignore"):
        sxy = np.stack([width / 2 + f * xc / zc, height / 2 - f * yc / zc], axis=-1)
    return sxy, zc
