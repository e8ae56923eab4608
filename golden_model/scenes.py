"""Built-in, seeded scenes named after the papers' test data.

Every builder is a whole-array NumPy function of one integer seed; the same seed gives
byte-identical arrays. The recipes, and what we decided where the papers are silent, are in
``docs/scenes.md``; ``python -m rasterhw.golden_model.scenes`` prints the screen statistics
quoted there.

Winding: every polygon is counter-clockwise seen from the side its normal points to (from
outside a closed solid), so back-face culling by screen-space winding and by ``N . view``
agree.

Each machine's own scenes live in ``golden_model/NAME/scenes.py`` (a ``SCENES`` table of
:class:`SceneInfo`), found by :data:`SCENES` on first use. Pixel-exact scenes (``zbm-5x5``,
``snu-100px``, ``experts-*``) are built in screen
coordinates and lifted into the world through the camera: a point meant for pixel position
``(sx, sy)`` at eye distance ``d`` goes to ``X = (sx - w/2) d / F``, ``Y = (h/2 - sy) d / F``,
``Z = D - d`` with the eye at ``(0, 0, D)`` looking down ``-z`` and
``F = (h/2) / tan(fovy/2)`` the focal length in pixels. A standard perspective projection
(vertical ``fovy``, aspect ``w/h``, centre of the frame at ``(w/2, h/2)``, y down) maps it back
to ``(sx, sy)`` up to rounding in the last bits; vertices are kept 0.25 px away from pixel
centres in x (and on integer rows in y) so that rounding never decides coverage.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Camera, Light, Material, Scene
from rasterhw.golden_model.scenekit import project

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


_CUBE_SEED = 1987
_SHARED: dict[str, SceneInfo] = {
    **{
        f"c{n}": SceneInfo(f"c{n}", f"{n} random cubes on a ground plate (vector Z-buffer paper, table 1)",
                           512, 512, _build_cubes(n), _CUBE_SEED, 6 * n + 1)
        for n in (50, 100, 150, 200, 250, 300)
    },
    "sp27": SceneInfo("sp27", "3x3x3 stacked spheres of 10x10 polygons on a ground plate (vector Z-buffer paper)",
                      512, 512, _build_spheres("sp27", _grid(3, 3, 3), 10, 10, ground_half=5.0, ground_pieces=1,
                                               azimuth=30.0, elevation=25.0, distance=15.0), 27, 2701),
    "sp5": SceneInfo("sp5", "5 spheres of 20x20 polygons spread down the screen on a ground plate "
                     "(vector Z-buffer paper)", 512, 512,
                     _build_spheres("sp5", _SP5_CENTRES, 20, 20, ground_half=8.5, ground_pieces=1,
                                    azimuth=45.0, elevation=75.0, distance=35.0), 5, 2001),
    "sp8": SceneInfo("sp8", "a column of 8 spheres of 13x13 polygons, small on screen (vector Z-buffer paper)",
                     512, 512, _build_spheres("sp8", _grid(1, 8, 1), 13, 13, ground_half=2.0, ground_pieces=2,
                                              azimuth=30.0, elevation=15.0, distance=28.0), 8, 1354),
}


class _Scenes(Mapping[str, SceneInfo]):
    """Every built-in scene by name: the shared ones above, then each machine's
    ``golden_model/NAME/scenes.py`` ``SCENES`` (found by looking, in folder order, on first use:
    no machine is named here)."""

    def __init__(self) -> None:
        self._all: dict[str, SceneInfo] | None = None

    def _load(self) -> dict[str, SceneInfo]:
        if self._all is None:
            found = dict(_SHARED)
            root = Path(__file__).parent
            for pkg in sorted(p.parent.name for p in root.glob("*/scenes.py")):
                table = importlib.import_module(f"{__package__}.{pkg}.scenes").SCENES
                for name in table:
                    if name in found:
                        raise RuntimeError(f"scene {name!r} is defined twice (golden_model/{pkg}/scenes.py)")
                found.update(table)
            self._all = found
        return self._all

    def __getitem__(self, name: str) -> SceneInfo:
        return self._load()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._load())

    def __len__(self) -> int:
        return len(self._load())


SCENES: Mapping[str, SceneInfo] = _Scenes()


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
    sxy, zc = project(scene, width, height)
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
