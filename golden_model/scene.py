"""Scene description shared by every architecture.

A scene is a camera, parallel lights with an ambient term, a material and a list of
polygons. Polygons are stored *padded*: every polygon has ``K`` corner slots
(``K`` = the largest vertex count in the scene) and ``nverts[p]`` of them are used.
Per-corner attributes (position, normal, colour, optional (u, v)) let a cube carry
flat normals per face while a sphere shares smooth ones, with no index indirection,
and keep every stage of the pipeline a whole-array NumPy operation.

Conventions (also in ``docs/conventions.md``):

* world space is right-handed, y up; the camera looks along ``target - eye``;
* a light's ``direction`` is the direction the light *travels* (from the light
  towards the scene), so a surface facing the light has ``N . direction < 0`` —
  the vector Z-buffer paper's ``I = Ia + k (-N.L) / (|N||L|)``;
* colours are linear RGB in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["Camera", "Light", "Material", "Scene"]


@dataclass(frozen=True)
class Camera:
    """Perspective pin-hole camera.

    ``fovy_deg`` is the full vertical field of view; ``near``/``far`` bound the view
    volume used by clipping and by the Z mapping.
    """

    eye: tuple[float, float, float] = (0.0, 0.0, 5.0)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fovy_deg: float = 45.0
    near: float = 0.1
    far: float = 100.0


@dataclass(frozen=True)
class Light:
    """Parallel (directional) light: no position, no attenuation."""

    direction: tuple[float, float, float] = (-0.4, -1.0, -0.6)
    colour: tuple[float, float, float] = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Material:
    """Phong coefficients shared by every polygon of a scene.

    ``shininess`` is the specular exponent; the pipeline raises to it through a
    lookup table, as the SNU paper does.
    """

    ka: float = 1.0
    kd: float = 0.8
    ks: float = 0.0
    shininess: int = 16


@dataclass
class Scene:
    """Camera, lights and padded polygons.

    Attributes
    ----------
    positions : (P, K, 3) float64 — corner positions, world space.
    normals : (P, K, 3) float64 — corner normals (need not be unit length).
    colours : (P, K, 3) float64 — corner base colours in [0, 1].
    nverts : (P,) int64 — corners in use, 3 <= nverts <= K.
    uv : (P, K, 2) float64 or None — optional texture coordinates.
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray
    colours: np.ndarray
    nverts: np.ndarray
    camera: Camera = field(default_factory=Camera)
    lights: tuple[Light, ...] = (Light(),)
    ambient: tuple[float, float, float] = (0.2, 0.2, 0.2)
    material: Material = field(default_factory=Material)
    uv: np.ndarray | None = None
    seed: int | None = None

    def __post_init__(self) -> None:
        self.positions = np.ascontiguousarray(self.positions, dtype=np.float64)
        self.normals = np.ascontiguousarray(self.normals, dtype=np.float64)
        self.colours = np.ascontiguousarray(self.colours, dtype=np.float64)
        self.nverts = np.ascontiguousarray(self.nverts, dtype=np.int64)
        if self.uv is not None:
            self.uv = np.ascontiguousarray(self.uv, dtype=np.float64)
        self.validate()

    @property
    def n_polygons(self) -> int:
        return int(self.nverts.shape[0])

    @property
    def max_corners(self) -> int:
        return int(self.positions.shape[1])

    def validate(self) -> None:
        """Raise :class:`RasterhwError` on anything the pipeline cannot take."""
        p = self.positions
        if p.ndim != 3 or p.shape[2] != 3:
            raise RasterhwError(f"scene {self.name!r}: positions must be (P, K, 3), got {p.shape}")
        if p.shape[0] == 0:
            raise RasterhwError(f"scene {self.name!r}: no polygons")
        for what, arr, last in (("normals", self.normals, 3), ("colours", self.colours, 3)):
            if arr.shape != p.shape[:2] + (last,):
                raise RasterhwError(
                    f"scene {self.name!r}: {what} must be {p.shape[:2] + (last,)}, got {arr.shape}"
                )
        if self.uv is not None and self.uv.shape != p.shape[:2] + (2,):
            raise RasterhwError(f"scene {self.name!r}: uv must be {p.shape[:2] + (2,)}, got {self.uv.shape}")
        if self.nverts.shape != (p.shape[0],):
            raise RasterhwError(f"scene {self.name!r}: nverts must be ({p.shape[0]},), got {self.nverts.shape}")
        bad = np.flatnonzero(self.nverts < 3)
        if bad.size:
            raise RasterhwError(
                f"scene {self.name!r}: polygon {int(bad[0])} has {int(self.nverts[bad[0]])} vertices "
                "(a polygon needs at least 3)"
            )
        if int(self.nverts.max()) > p.shape[1]:
            raise RasterhwError(f"scene {self.name!r}: nverts exceeds the corner slots K={p.shape[1]}")
        limit = 1e15
        if int(self.nverts.min()) == p.shape[1]:
            # every corner slot is used (triangle meshes, k-gon scenes): whole-array reductions
            for what, arr in (("position", p), ("normal", self.normals), ("colour", self.colours)):
                if not np.isfinite(arr).all():
                    raise RasterhwError(f"scene {self.name!r}: a vertex {what} is NaN or infinite")
            mag = float(np.abs(p).max())
        else:
            used = np.arange(p.shape[1])[None, :] < self.nverts[:, None]
            # checked on whole arrays and masked afterwards (a boolean gather of every corner is slower)
            for what, arr in (("position", p), ("normal", self.normals), ("colour", self.colours)):
                if np.any(~np.isfinite(arr).all(axis=-1) & used):
                    raise RasterhwError(f"scene {self.name!r}: a vertex {what} is NaN or infinite")
            mag = float(np.where(used, np.abs(p).max(axis=-1), 0.0).max())
        if mag > limit:
            raise RasterhwError(
                f"scene {self.name!r}: a vertex coordinate has magnitude {mag:.3g} "
                f"(more than {limit:g}); rescale the model"
            )
        cam = self.camera
        vals = np.array([*cam.eye, *cam.target, *cam.up, cam.fovy_deg, cam.near, cam.far], dtype=float)
        if not np.all(np.isfinite(vals)):
            raise RasterhwError(f"scene {self.name!r}: camera has a NaN or infinite value")
        if not (0.0 < cam.near < cam.far):
            raise RasterhwError(f"scene {self.name!r}: camera needs 0 < near < far, got {cam.near}, {cam.far}")
        if not (0.0 < cam.fovy_deg < 180.0):
            raise RasterhwError(f"scene {self.name!r}: fovy_deg must be in (0, 180), got {cam.fovy_deg}")

    @staticmethod
    def pad(polys: list[np.ndarray], k: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Stack ragged per-polygon corner arrays into a padded (P, K, D) array + nverts.

        Padding slots repeat the polygon's last corner, so they are finite and harmless.
        """
        nverts = np.array([len(c) for c in polys], dtype=np.int64)
        k = int(nverts.max()) if k is None else k
        d = polys[0].shape[1]
        out = np.empty((len(polys), k, d), dtype=np.float64)
        for i, c in enumerate(polys):
            out[i, : len(c)] = c
            out[i, len(c) :] = c[-1]
        return out, nverts
