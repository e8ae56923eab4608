"""Built-in, seeded scenes named after the papers' test data.

Every builder is a whole-array NumPy function of one integer seed; the same seed gives
byte-identical arrays. The recipes, and what we decided where the papers are silent, are in
``docs/scenes.md``; ``python -m rasterhw.golden_model.scenes`` prints the screen statistics
quoted there.

Winding: every polygon is counter-clockwise seen from the side its normal points to (from
outside a closed solid), so back-face culling by screen-space winding and by ``N . view``
agree.

Pixel-exact scenes (``zbm-5x5``, ``snu-100px``, ``experts-*``) are built in screen
coordinates and lifted into the world through the camera: a point meant for pixel position
``(sx, sy)`` at eye distance ``d`` goes to ``X = (sx - w/2) d / F``, ``Y = (h/2 - sy) d / F``,
``Z = D - d`` with the eye at ``(0, 0, D)`` looking down ``-z`` and
``F = (h/2) / tan(fovy/2)`` the focal length in pixels. A standard perspective projection
(vertical ``fovy``, aspect ``w/h``, centre of the frame at ``(w/2, h/2)``, y down) maps it back
to ``(sx, sy)`` up to rounding in the last bits; vertices are kept 0.25 px away from pixel
centres in x (and on integer rows in y) so that rounding never decides coverage.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Camera, Light, Material, Scene

__all__ = ["SCENES", "SceneInfo", "build_scene", "list_scenes", "screen_stats"]


@dataclass(frozen=True)
class SceneInfo:
    """One built-in scene: what it is, its default frame and seed, and how to build it."""

    name: str
    description: str
    default_width: int
    default_height: int
    builder: Callable[[int], Scene]
    default_seed: int
    polygons: int

    @property
    def size(self) -> tuple[int, int]:
        return (self.default_width, self.default_height)


# --------------------------------------------------------------------------- helpers


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _orbit_camera(target, *, azimuth_deg: float, elevation_deg: float, distance: float,
                  fovy_deg: float = 45.0, near: float, far: float) -> Camera:
    """Camera on a sphere around ``target``; azimuth 0 looks from +z, 90 from +x."""
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    t = np.asarray(target, dtype=float)
    d = np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])
    eye = t + distance * d
    return Camera(eye=tuple(float(c) for c in eye), target=tuple(float(c) for c in t),
                  up=(0.0, 1.0, 0.0), fovy_deg=fovy_deg, near=near, far=far)


def _ground(half: float, colour, *, pieces: int = 1, y: float = 0.0):
    """Square ground plate in the plane ``y``, normal +y, split into ``pieces`` strips along x.

    Returns (P, 4, 3) positions, normals, colours.
    """
    x = np.linspace(-half, half, pieces + 1)
    x0, x1 = x[:-1], x[1:]
    # Counter-clockwise seen from above (+y): (x0, +z) -> (x1, +z) -> (x1, -z) -> (x0, -z).
    pos = np.empty((pieces, 4, 3))
    pos[:, 0] = np.stack([x0, np.full(pieces, y), np.full(pieces, half)], axis=1)
    pos[:, 1] = np.stack([x1, np.full(pieces, y), np.full(pieces, half)], axis=1)
    pos[:, 2] = np.stack([x1, np.full(pieces, y), np.full(pieces, -half)], axis=1)
    pos[:, 3] = np.stack([x0, np.full(pieces, y), np.full(pieces, -half)], axis=1)
    nrm = np.broadcast_to(np.array([0.0, 1.0, 0.0]), pos.shape).copy()
    col = np.broadcast_to(np.asarray(colour, dtype=float), pos.shape).copy()
    return pos, nrm, col


# Unit cube [-1, 1]^3: corner index bits (x, y, z); faces counter-clockwise from outside.
_CUBE_CORNERS = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)], dtype=float) * 2 - 1
_CUBE_FACES = np.array([
    [4, 6, 7, 5],  # +x
    [0, 1, 3, 2],  # -x
    [2, 3, 7, 6],  # +y
    [0, 4, 5, 1],  # -y
    [1, 5, 7, 3],  # +z
    [0, 2, 6, 4],  # -z
])
_CUBE_NORMALS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)


def _cubes(centre: np.ndarray, half: np.ndarray, yaw: np.ndarray):
    """N cubes (half edge ``half``, turned by ``yaw`` about +y) -> (6N, 4, 3) quads + flat normals."""
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.zeros((len(yaw), 3, 3))
    rot[:, 0, 0], rot[:, 0, 2] = c, s
    rot[:, 1, 1] = 1.0
    rot[:, 2, 0], rot[:, 2, 2] = -s, c
    corners = np.einsum("nij,kj->nki", rot, _CUBE_CORNERS) * half[:, None, None] + centre[:, None, :]
    pos = corners[:, _CUBE_FACES]  # (N, 6, 4, 3)
    nrm = np.einsum("nij,fj->nfi", rot, _CUBE_NORMALS)  # (N, 6, 3)
    nrm = np.broadcast_to(nrm[:, :, None, :], pos.shape)
    return pos.reshape(-1, 4, 3), nrm.reshape(-1, 4, 3)


def _uv_sphere(centre: np.ndarray, radius: float, slices: int, stacks: int):
    """UV spheres at ``centre`` (S, 3): ``slices * stacks`` polygons each.

    The two polar stacks are fans of ``slices`` triangles (3 corners, 4th slot padded with the
    last corner), the others quads; normals are the exact radial unit vectors (smooth).
    Returns (S * slices * stacks, 4, 3) positions and normals and the (…,) nverts.
    """
    theta = np.pi * np.arange(stacks + 1) / stacks
    phi = 2 * np.pi * (np.arange(slices + 1) % slices) / slices  # seam reuses phi = 0 exactly
    st, ct = np.sin(theta), np.cos(theta)
    st[0] = st[-1] = 0.0
    ct[0], ct[-1] = 1.0, -1.0
    # Grid of unit directions g[j, i]; phi turns clockwise seen from +y so that the corner order
    # below is counter-clockwise seen from outside.
    g = np.stack([st[:, None] * np.cos(phi)[None, :], np.broadcast_to(ct[:, None], (stacks + 1, slices + 1)),
                  -st[:, None] * np.sin(phi)[None, :]], axis=-1)
    j, i = np.meshgrid(np.arange(stacks), np.arange(slices), indexing="ij")
    quad = np.stack([g[j, i], g[j + 1, i], g[j + 1, i + 1], g[j, i + 1]], axis=2)  # (stacks, slices, 4, 3)
    # Polar fans: drop the repeated pole corner, pad by repeating the last one.
    quad[0] = np.stack([quad[0, :, 0], quad[0, :, 1], quad[0, :, 2], quad[0, :, 2]], axis=1)
    quad[-1] = np.stack([quad[-1, :, 0], quad[-1, :, 1], quad[-1, :, 3], quad[-1, :, 3]], axis=1)
    nv = np.full((stacks, slices), 4, dtype=np.int64)
    nv[0] = nv[-1] = 3
    unit = quad.reshape(-1, 4, 3)
    ns = len(centre)
    pos = unit[None] * radius + centre[:, None, None, :]
    nrm = np.broadcast_to(unit[None], pos.shape)
    return pos.reshape(-1, 4, 3), nrm.reshape(-1, 4, 3), np.tile(nv.ravel(), ns)


def _focal_px(height: int, fovy_deg: float) -> float:
    return (height / 2) / math.tan(math.radians(fovy_deg) / 2)


def _lift(sxy: np.ndarray, dist: np.ndarray, width: int, height: int, f: float, eye_z: float) -> np.ndarray:
    """Screen points (…, 2) in pixels at eye distance ``dist`` (… broadcast) -> world (…, 3)."""
    x = (sxy[..., 0] - width / 2) * dist / f
    y = (height / 2 - sxy[..., 1]) * dist / f
    z = np.broadcast_to(eye_z - dist, x.shape)
    return np.stack([x, y, z], axis=-1)


def _screen_camera(height: int, fovy_deg: float = 45.0) -> tuple[Camera, float]:
    f = _focal_px(height, fovy_deg)
    cam = Camera(eye=(0.0, 0.0, f), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                 fovy_deg=fovy_deg, near=0.25 * f, far=2.0 * f)
    return cam, f


def _random_triangles(rng: np.random.Generator, n: int, area_px: np.ndarray) -> np.ndarray:
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


# --------------------------------------------------------------------------- scenes

# c-series recipe (docs/scenes.md): the camera looks level along -z from height _C_EYE_Y above
# the ground plane y = 0; cube centres are uniform in the view pyramid's screen square and
# uniform in eye distance, so cubes cover the whole frame; the ground plate lies under the
# pyramid and shows only as a thin band at the bottom of the frame (the paper's per-N pixel
# totals put its ground at a few thousand pixels).
_C_DIST = (100.0, 300.0)  # eye distance of a cube centre, uniform, world units
_C_EDGE = (2.0, 7.0)      # cube edge length, uniform, world units
_C_FOVY = 45.0
_C_TAN = math.tan(math.radians(_C_FOVY) / 2)
_C_EYE_Y = 0.97 * _C_TAN * _C_DIST[1]


def _build_cubes(n: int) -> Callable[[int], Scene]:
    def build(seed: int) -> Scene:
        rng = np.random.default_rng(seed)
        # One (n, 8) draw: row k is cube k's parameters, so cN is a prefix of c300 for a seed.
        u = rng.random((n, 8))
        edge = _C_EDGE[0] + (_C_EDGE[1] - _C_EDGE[0]) * u[:, 0]
        half = edge / 2
        d = _C_DIST[0] + (_C_DIST[1] - _C_DIST[0]) * u[:, 1]
        x = (2 * u[:, 2] - 1) * _C_TAN * d
        y = np.maximum(_C_EYE_Y + (2 * u[:, 3] - 1) * _C_TAN * d, half)  # never below the ground
        yaw = u[:, 4] * (np.pi / 2)
        centre = np.stack([x, y, -d], axis=1)
        cpos, cnrm = _cubes(centre, half, yaw)
        ccol = np.repeat(0.25 + 0.75 * u[:, 5:8], 6 * 4, axis=0).reshape(-1, 4, 3)
        gx = _C_TAN * _C_DIST[1] + _C_EDGE[1]
        gpos = np.array([[[-gx, 0.0, -0.5 * _C_DIST[0]], [gx, 0.0, -0.5 * _C_DIST[0]],
                          [gx, 0.0, -_C_DIST[1] - _C_EDGE[1]], [-gx, 0.0, -_C_DIST[1] - _C_EDGE[1]]]])
        gnrm = np.broadcast_to(np.array([0.0, 1.0, 0.0]), gpos.shape)
        gcol = np.broadcast_to(np.array([0.45, 0.55, 0.35]), gpos.shape)
        cam = Camera(eye=(0.0, _C_EYE_Y, 0.0), target=(0.0, _C_EYE_Y, -1.0), up=(0.0, 1.0, 0.0),
                     fovy_deg=_C_FOVY, near=1.0, far=1000.0)
        return Scene(
            name=f"c{n}", seed=seed, camera=cam,
            positions=np.concatenate([gpos, cpos]), normals=np.concatenate([gnrm, cnrm]),
            colours=np.concatenate([gcol, ccol]), nverts=np.full(1 + 6 * n, 4, dtype=np.int64),
            lights=(Light(direction=(-0.4, -1.0, -0.6)),), ambient=(0.2, 0.2, 0.2),
            material=Material(ka=1.0, kd=0.8, ks=0.0),
        )

    return build


def _build_spheres(name: str, centres: np.ndarray, slices: int, stacks: int, *, ground_half: float,
                   ground_pieces: int, azimuth: float, elevation: float, distance: float):
    centres = np.asarray(centres, dtype=float)

    def build(seed: int) -> Scene:
        rng = np.random.default_rng(seed)
        spos, snrm, snv = _uv_sphere(centres, 1.0, slices, stacks)
        per = slices * stacks
        scol = np.repeat(0.3 + 0.7 * rng.random((len(centres), 3)), per * 4, axis=0).reshape(-1, 4, 3)
        gpos, gnrm, gcol = _ground(ground_half, (0.55, 0.55, 0.5), pieces=ground_pieces)
        target = (0.0, float(centres[:, 1].max() + 1) / 2, 0.0)
        cam = _orbit_camera(target, azimuth_deg=azimuth, elevation_deg=elevation, distance=distance,
                            near=0.1 * distance, far=3.0 * distance)
        return Scene(
            name=name, seed=seed, camera=cam,
            positions=np.concatenate([gpos, spos]), normals=np.concatenate([gnrm, snrm]),
            colours=np.concatenate([gcol, scol]),
            nverts=np.concatenate([np.full(ground_pieces, 4, dtype=np.int64), snv]),
            lights=(Light(direction=(-0.4, -1.0, -0.6)),), ambient=(0.2, 0.2, 0.2),
            material=Material(ka=1.0, kd=0.8, ks=0.0),
        )

    return build


def _grid(nx: int, ny: int, nz: int, spacing: float = 2.0) -> np.ndarray:
    ax = lambda n: (np.arange(n) - (n - 1) / 2) * spacing  # noqa: E731
    x, y, z = np.meshgrid(ax(nx), np.arange(ny) * spacing + 1.0, ax(nz), indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


# sp5: a quincunx of spacing 7.5 seen along its diagonal from high up, so the five spheres are
# spread down the screen (fewer empty lines than the narrow sp8; docs/scenes.md).
_SP5_CENTRES = np.array([[-7.5, 1.0, -7.5], [7.5, 1.0, -7.5], [0.0, 1.0, 0.0], [-7.5, 1.0, 7.5], [7.5, 1.0, 7.5]])


def _build_zbm(seed: int, *, n: int = 1000, width: int = 512, height: int = 512) -> Scene:
    """Screen-facing diamonds 10 px wide and 10 px tall: two edge pairs of 5 rows x 25 px each."""
    rng = np.random.default_rng(seed)
    cam, f = _screen_camera(height)
    cx = rng.integers(5, width - 5, n) + 0.25  # 0.25 px off the pixel centres' x
    ty = rng.integers(0, height - 10 + 1, n).astype(float)
    # Counter-clockwise seen from the camera: top -> left -> bottom -> right.
    sxy = np.stack([np.stack([cx, ty], 1), np.stack([cx - 5, ty + 5], 1),
                    np.stack([cx, ty + 10], 1), np.stack([cx + 5, ty + 5], 1)], axis=1)
    dist = rng.uniform(0.5 * f, 1.5 * f, n)
    pos = _lift(sxy, dist[:, None], width, height, f, cam.eye[2])
    nrm = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pos.shape).copy()
    col = rng.uniform(0.1, 1.0, (n, 4, 3))
    return Scene(name="zbm-5x5", seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(n, 4, dtype=np.int64), lights=(Light(direction=(0.0, 0.0, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


def _build_snu(seed: int, *, n: int = 2000, width: int = 1280, height: int = 1024, area: float = 100.0,
               name: str = "snu-100px") -> Scene:
    """Gouraud triangles of exactly ``area`` px each, random vertex colours, random depths."""
    rng = np.random.default_rng(seed)
    cam, f = _screen_camera(height)
    tri = _random_triangles(rng, n, np.full(n, area))
    r = np.abs(tri).max(axis=(1, 2))
    c = np.stack([rng.uniform(r, width - r), rng.uniform(r, height - r)], axis=1)
    dist = rng.uniform(0.5 * f, 1.5 * f, n)
    pos = _lift(tri + c[:, None, :], dist[:, None], width, height, f, cam.eye[2])
    nrm = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pos.shape).copy()
    col = rng.random((n, 3, 3))
    return Scene(name=name, seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                 nverts=np.full(n, 3, dtype=np.int64), lights=(Light(direction=(0.0, 0.0, -1.0)),),
                 ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))


def _build_experts(fr: int) -> Callable[[int], Scene]:
    def build(seed: int, *, width: int = 512, height: int = 512, dc: float = 3.0) -> Scene:
        """``fr`` screen-parallel triangles, all on screen, total area ``dc * width * height``."""
        rng = np.random.default_rng(seed)
        cam, f = _screen_camera(height)
        area = rng.uniform(0.5, 1.5, fr)
        area *= dc * width * height / area.sum()
        tri = _random_triangles(rng, fr, area)
        r = np.abs(tri).max(axis=(1, 2))
        c = np.stack([rng.uniform(r, width - r), rng.uniform(r, height - r)], axis=1)
        dist = rng.uniform(0.5 * f, 1.5 * f, fr)  # one depth per face: faces never interpenetrate
        pos = _lift(tri + c[:, None, :], dist[:, None], width, height, f, cam.eye[2])
        # Smooth-shading normals: tilted up to ~30 degrees from the face normal, per vertex.
        tilt = rng.uniform(-0.55, 0.55, (fr, 3, 2))
        nrm = _unit(np.concatenate([tilt, np.ones((fr, 3, 1))], axis=-1))
        col = np.repeat(0.2 + 0.8 * rng.random((fr, 1, 3)), 3, axis=1)
        return Scene(name=f"experts-{fr}", seed=seed, camera=cam, positions=pos, normals=nrm, colours=col,
                     nverts=np.full(fr, 3, dtype=np.int64), lights=(Light(direction=(-0.3, -0.4, -1.0)),),
                     ambient=(0.2, 0.2, 0.2), material=Material(ka=1.0, kd=0.8, ks=0.0))

    return build


def _experts_builder(fn: str, *args) -> Callable[[int], Scene]:
    """An EXPERTS builder from golden_model/experts/scenes.py, imported when first used."""
    def build(seed: int) -> Scene:
        from rasterhw.golden_model.experts import scenes as ex
        f = getattr(ex, fn)
        return (f(*args) if args else f)(seed)
    return build


def _info(name, desc, size, builder, seed, polygons) -> SceneInfo:
    return SceneInfo(name, desc, size[0], size[1], builder, seed, polygons)


_CUBE_SEED = 1987
SCENES: dict[str, SceneInfo] = {
    **{
        f"c{n}": _info(f"c{n}", f"{n} random cubes on a ground plate (vector Z-buffer paper, table 1)",
                       (512, 512), _build_cubes(n), _CUBE_SEED, 6 * n + 1)
        for n in (50, 100, 150, 200, 250, 300)
    },
    "sp27": _info("sp27", "3x3x3 stacked spheres of 10x10 polygons on a ground plate (vector Z-buffer paper)",
                  (512, 512), _build_spheres("sp27", _grid(3, 3, 3), 10, 10, ground_half=5.0, ground_pieces=1,
                                             azimuth=30.0, elevation=25.0, distance=15.0), 27, 2701),
    "sp5": _info("sp5", "5 spheres of 20x20 polygons spread down the screen on a ground plate (vector Z-buffer paper)",
                 (512, 512), _build_spheres("sp5", _SP5_CENTRES, 20, 20, ground_half=8.5, ground_pieces=1,
                                            azimuth=45.0, elevation=75.0, distance=35.0), 5, 2001),
    "sp8": _info("sp8", "a column of 8 spheres of 13x13 polygons, small on screen (vector Z-buffer paper)",
                 (512, 512), _build_spheres("sp8", _grid(1, 8, 1), 13, 13, ground_half=2.0, ground_pieces=2,
                                            azimuth=30.0, elevation=15.0, distance=28.0), 8, 1354),
    "zbm-5x5": _info("zbm-5x5", "1000 screen-facing diamonds, each two 5x5-pixel edge pairs (ZB/M table 1)",
                     (512, 512), _build_zbm, 3, 1000),
    "snu-100px": _info("snu-100px", "2000 Gouraud triangles of 100 px, random vertex colours (SNU target)",
                       (1280, 1024), _build_snu, 4, 2000),
    "snu-100k": _info("snu-100k", "100,000 Gouraud triangles of 100 px, random vertex colours: the SNU headline "
                      "frame (one second's work)", (1280, 1024),
                      lambda seed: _build_snu(seed, n=100_000, name="snu-100k"), 100, 100_000),
    "experts-1000": _info("experts-1000", "Fr = 1000 front-facing triangles at depth complexity 3 (EXPERTS fig. 4.1)",
                          (512, 512), _build_experts(1000), 1000, 1000),
    "experts-2000": _info("experts-2000", "Fr = 2000 front-facing triangles at depth complexity 3 (EXPERTS fig. 4.1)",
                          (512, 512), _build_experts(2000), 2000, 2000),
    # EXPERTS: tilted, interpenetrating faces (same Fr, Dc), table 2.1's solids, an uneven load
    # (builders in golden_model/experts/scenes.py, imported when a scene is built)
    **{
        f"experts-tilt-{fr}": _info(f"experts-tilt-{fr}", f"Fr = {fr} tilted, interpenetrating triangles at Dc = 3 "
                                    "(EXPERTS fig. 4.1)", (512, 512), _experts_builder("build_tilt", fr), fr, fr)
        for fr in (1000, 2000)
    },
    **{
        f"experts-solid-{k}": _info(f"experts-solid-{k}", f"EXPERTS table 2.1 solid with {k} visible edges",
                                    (512, 512), _experts_builder("build_solid", str(k)), 21, n)
        for k, n in ((5, 4), (9, 6), (15, 9), (20, 12))
    },
    "experts-solids": _info("experts-solids", "the four solids of EXPERTS table 2.1 in one frame",
                            (512, 512), _experts_builder("build_solids"), 21, 31),
    "experts-uneven": _info("experts-uneven", "850 small triangles crowded top-left over 150 large ones "
                            "(EXPERTS load balancing)", (512, 512), _experts_builder("build_uneven"), 8, 1000),
}


def build_scene(name: str, *, seed: int | None = None) -> Scene:
    """Build the built-in scene ``name``; ``seed=None`` uses the scene's fixed default seed."""
    info = SCENES.get(name)
    if info is None:
        raise RasterhwError(f"unknown scene {name!r}; built-in scenes are: {', '.join(SCENES)}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise RasterhwError(f"scene seed must be a non-negative integer, not {seed!r}")
    return info.builder(int(info.default_seed if seed is None else seed))


def list_scenes() -> list[dict]:
    """One row per built-in scene: name, description, polygons, default_width, default_height."""
    return [
        {"name": i.name, "description": i.description, "polygons": i.polygons,
         "default_width": i.default_width, "default_height": i.default_height}
        for i in SCENES.values()
    ]


# --------------------------------------------------------------------------- statistics


def _project(scene: Scene, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Corners -> (P, K, 2) screen pixels (y down) and (P, K) eye depth along the view axis."""
    cam = scene.camera
    eye = np.asarray(cam.eye, dtype=float)
    fwd = _unit(np.asarray(cam.target, dtype=float) - eye)
    side = _unit(np.cross(fwd, np.asarray(cam.up, dtype=float)))
    up = np.cross(side, fwd)
    rel = scene.positions - eye
    xc, yc, zc = rel @ side, rel @ up, rel @ fwd
    f = _focal_px(height, cam.fovy_deg)
    with np.errstate(divide="ignore", invalid="ignore"):
        sxy = np.stack([width / 2 + f * xc / zc, height / 2 - f * yc / zc], axis=-1)
    return sxy, zc


def _clip_area(poly: np.ndarray, width: int, height: int) -> float:
    """Area of a 2-D polygon (M, 2) clipped to the frame (Sutherland-Hodgman)."""
    pts = list(map(tuple, poly))
    for axis, bound, keep_less in ((0, 0.0, False), (0, float(width), True), (1, 0.0, False), (1, float(height), True)):
        out = []
        for k in range(len(pts)):
            a, b = pts[k - 1], pts[k]
            ina = (a[axis] <= bound) if keep_less else (a[axis] >= bound)
            inb = (b[axis] <= bound) if keep_less else (b[axis] >= bound)
            if ina != inb:
                t = (bound - a[axis]) / (b[axis] - a[axis])
                out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
            if inb:
                out.append(b)
        pts = out
        if not pts:
            return 0.0
    p = np.asarray(pts)
    return 0.5 * abs(float(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1))))


def screen_stats(scene: Scene, width: int, height: int) -> dict:
    """Screen-space statistics of a scene, estimated from projected outlines.

    Independent of the rendering pipeline (no rasterisation, no Z test): back-facing polygons
    are found by screen winding; the drawn area of each front-facing polygon is its outline
    clipped to the frame (the pixel count a rasteriser would cover, to within edge effects).

    Returns a dict: ``polygons``, ``behind_near`` (a corner at or behind the near plane; not
    projected), ``back_facing``, ``off_screen`` (front-facing, nothing on screen), ``drawn``,
    ``area_px`` (sum over drawn), ``area_per_drawn_px``, ``depth_complexity``
    (``area_px / (width * height)``), ``empty_rows`` and ``empty_row_fraction`` (scan lines whose
    centre no drawn polygon spans).
    """
    sxy, zc = _project(scene, width, height)
    k = scene.max_corners
    used = np.arange(k)[None, :] < scene.nverts[:, None]
    near_bad = np.any(used & (zc <= scene.camera.near), axis=1)
    # Signed area with y up: positive = counter-clockwise seen from the camera = front-facing.
    x, y = sxy[..., 0], -sxy[..., 1]
    nxt = (np.arange(k)[None, :] + 1) % scene.nverts[:, None]
    xn = np.take_along_axis(x, nxt, axis=1)
    yn = np.take_along_axis(y, nxt, axis=1)
    signed = 0.5 * np.where(used, x * yn - xn * y, 0.0).sum(axis=1)
    ok = ~near_bad
    front = ok & (signed > 0)
    lo = np.where(used[..., None], sxy, np.inf).min(axis=1)
    hi = np.where(used[..., None], sxy, -np.inf).max(axis=1)
    inside = (lo[:, 0] >= 0) & (lo[:, 1] >= 0) & (hi[:, 0] <= width) & (hi[:, 1] <= height)
    area = np.where(front & inside, np.abs(signed), 0.0)
    for p in np.flatnonzero(front & ~inside):
        area[p] = _clip_area(sxy[p, : scene.nverts[p]], width, height)
    drawn = area > 0
    rows = np.zeros(height + 1, dtype=np.int64)
    r0 = np.clip(np.ceil(lo[drawn, 1] - 0.5), 0, height).astype(np.int64)
    r1 = np.clip(np.ceil(hi[drawn, 1] - 0.5), 0, height).astype(np.int64)
    np.add.at(rows, r0, 1)
    np.add.at(rows, r1, -1)
    empty = int(np.count_nonzero(np.cumsum(rows)[:height] == 0))
    total = float(area.sum())
    nd = int(drawn.sum())
    return {
        "polygons": scene.n_polygons,
        "behind_near": int(near_bad.sum()),
        "back_facing": int((ok & (signed <= 0)).sum()),
        "off_screen": int((front & ~drawn).sum()),
        "drawn": nd,
        "area_px": total,
        "area_per_drawn_px": total / nd if nd else 0.0,
        "depth_complexity": total / (width * height),
        "empty_rows": empty,
        "empty_row_fraction": empty / height,
    }


def _main() -> None:  # pragma: no cover - prints the table quoted in docs/scenes.md
    import time

    print(f"{'scene':<13}{'polys':>6}{'size':>10}{'back':>6}{'drawn':>6}{'px/drawn':>9}{'px total':>10}"
          f"{'Dc':>6}{'empty rows':>11}{'build ms':>9}")
    for name, info in SCENES.items():
        t = time.perf_counter()
        sc = build_scene(name)
        ms = (time.perf_counter() - t) * 1e3
        s = screen_stats(sc, *info.size)
        print(f"{name:<13}{s['polygons']:>6}{info.default_width:>5}x{info.default_height:<4}{s['back_facing']:>6}"
              f"{s['drawn']:>6}{s['area_per_drawn_px']:>9.1f}{s['area_px']:>10.0f}{s['depth_complexity']:>6.2f}"
              f"{s['empty_row_fraction']:>10.1%}{ms:>9.1f}")


if __name__ == "__main__":  # pragma: no cover
    _main()
