"""The vector Z-buffer paper's initial data structures and its set-up (section 2.1, 2.2).

Blocks (seed 001, 2.1), built from a :class:`~rasterhw.golden_model.scene.Scene`:

* :class:`PolygonBlock` -- per polygon: vertex pointer, vertex count, face colour, flag;
  a polygon's vertices are contiguous in the vertex block ("頂点ブロックの連続する領域に格納");
* :class:`VertexBlock` -- per vertex: ``(x, y, z)`` and a pointer into the normal block;
* :class:`NormalBlock` -- normal vectors;
* :class:`ControlBlock` -- eye, view direction, parallel light direction, screen, background,
  ambient intensity ``Ia`` and the constant ``k``.

Set-up (2.2) is :func:`setup`: view + perspective transform, intensity
``I = Ia + k(-N.L)/(|N||L|)`` on lit vertices and ``I = Ia`` on unlit ones, back-face removal and
Sutherland's re-entrant clipping. Those are exactly the jobs of
:func:`rasterhw.golden_model.pipeline.run_geometry` (its ``light`` stage with ``ks = 0``,
``ka = 1`` and white light is the paper's formula, per vertex, from the vertex normals -- i.e.
Gouraud), so :func:`setup` runs it on a copy of the scene whose colours are white: the
"colour" it returns per vertex is the paper's intensity ``I``. The face colour stays in the
polygon block, as in the paper (RGB per face, I per point).

What :func:`setup` adds after ``run_geometry``: the fan triangles are regrouped into the
clipped convex screen polygons, the vertices are snapped to the 1/256-px grid
(``docs/conventions.md``), and each polygon's vertex depths are put back on **one plane**
(least squares through its snapped vertices), because the paper's segment block carries one
``dz/dx`` per polygon: a polygon is planar in screen space. The fan triangles of these planar
polygons (:attr:`ScreenPolygons.tris`) are what the reference rasteriser is compared on.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scene import Light, Material, Scene
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap

__all__ = ["ControlBlock", "NormalBlock", "PolygonBlock", "ScreenPolygons", "VertexBlock",
           "Blocks", "blocks_from_scene", "ground_polygons", "quantise_rgbi", "setup"]

SUB = 1 << SUBPIXEL_BITS
FLAG_GROUND = 1


@dataclass
class PolygonBlock:
    vptr: np.ndarray      # (P,) int64 index of the first vertex in the vertex block
    nvert: np.ndarray     # (P,) int64
    colour: np.ndarray    # (P, 3) float64 face colour in [0, 1]
    flag: np.ndarray      # (P,) int64, bit 0 = ground polygon


@dataclass
class VertexBlock:
    xyz: np.ndarray       # (V, 3) world coordinates
    nptr: np.ndarray      # (V,) int64 index into the normal block


@dataclass
class NormalBlock:
    n: np.ndarray         # (N, 3)


@dataclass
class ControlBlock:
    eye: tuple
    view: tuple           # unit view direction
    light: tuple          # direction the light travels
    width: int
    height: int
    background: tuple
    ia: float             # ambient intensity
    k: float              # proportionality constant of the diffuse term


@dataclass
class Blocks:
    polygon: PolygonBlock
    vertex: VertexBlock
    normal: NormalBlock
    control: ControlBlock


def ground_polygons(scene: Scene) -> np.ndarray:
    """Indices of the ground polygons: every corner at the scene's lowest y, normal up (+y).

    The paper takes "a pointer to the polygon block of the ground" as input; our scenes carry
    no flag, so this rule finds it (cN: polygon 0; sp*: the ground plate pieces).
    """
    used = np.arange(scene.max_corners)[None, :] < scene.nverts[:, None]
    y = scene.positions[..., 1]
    ymin = float(y[used].min())
    flat = np.all(np.where(used, np.abs(y - ymin) <= 1e-9 * max(1.0, abs(ymin)), True), axis=1)
    up = np.einsum("pkc,c->p", np.where(used[..., None], scene.normals, 0.0), np.array([0.0, 1.0, 0.0])) > 0
    return np.flatnonzero(flat & up)


def blocks_from_scene(scene: Scene, width: int, height: int, *, background=(0.0, 0.0, 0.0)) -> Blocks:
    """The paper's four blocks from a scene (normals checked: every vertex needs one)."""
    used = np.arange(scene.max_corners)[None, :] < scene.nverts[:, None]
    nrm = scene.normals[used]
    length = np.sqrt(np.einsum("ij,ij->i", nrm, nrm))
    bad = ~(np.isfinite(length) & (length > 1e-100))
    if bad.any():
        v = int(np.flatnonzero(bad)[0])
        p = int(np.searchsorted(np.cumsum(scene.nverts), v, side="right"))
        raise RasterhwError(f"vzbuf: polygon {p} of scene {scene.name!r} has no normal (vertex normal of length 0)")
    nv = scene.nverts
    vptr = np.cumsum(nv) - nv
    colour = np.where(used[..., None], scene.colours, 0.0).sum(axis=1) / nv[:, None]
    flag = np.zeros(scene.n_polygons, dtype=np.int64)
    flag[ground_polygons(scene)] |= FLAG_GROUND
    cam = scene.camera
    eye = np.asarray(cam.eye, float)
    view = np.asarray(cam.target, float) - eye
    view = view / np.linalg.norm(view)
    if len(scene.lights) != 1:
        raise RasterhwError(f"vzbuf: the paper has one parallel light; scene {scene.name!r} has {len(scene.lights)}")
    amb = np.asarray(scene.ambient, float)
    return Blocks(
        polygon=PolygonBlock(vptr=vptr, nvert=nv.copy(), colour=colour, flag=flag),
        vertex=VertexBlock(xyz=scene.positions[used].copy(), nptr=np.arange(int(nv.sum()))),
        normal=NormalBlock(n=nrm.copy()),
        control=ControlBlock(eye=tuple(eye), view=tuple(view), light=tuple(scene.lights[0].direction),
                             width=int(width), height=int(height), background=tuple(background),
                             ia=float(scene.material.ka * amb.mean()), k=float(scene.material.kd)),
    )


@dataclass
class ScreenPolygons:
    """Clipped convex polygons in screen space, ready for segment building.

    X, Y : (Q, M) snapped vertex coordinates, integers on the 1/256-px grid (as float64).
    z : (Q, M) depth on the polygon's plane (0 = near).
    i : (Q, M) intensity at the vertices.
    nv : (Q,) vertices in use; slots past ``nv`` repeat the last vertex.
    poly : (Q,) scene polygon index.
    plane : (Q, 3) ``z = a x + b y + c`` with x, y in pixels.
    tris : the fan triangles of these polygons (colour = (I, I, I)), the reference's input.
    stats : counts from the pipeline.
    """

    X: np.ndarray
    Y: np.ndarray
    z: np.ndarray
    i: np.ndarray
    nv: np.ndarray
    poly: np.ndarray
    plane: np.ndarray
    tris: ScreenTriangles
    stats: dict


def _white_scene(scene: Scene, ia: float, k: float) -> Scene:
    lt = scene.lights[0]
    return replace(scene, colours=np.ones_like(scene.colours), ambient=(ia, ia, ia),
                   lights=(Light(direction=lt.direction, colour=(1.0, 1.0, 1.0)),),
                   material=Material(ka=1.0, kd=k, ks=0.0, shininess=scene.material.shininess))


def polygons_from_triangles(tris: ScreenTriangles, *, plane_fit: bool = True) -> ScreenPolygons:
    """Regroup fan triangles (consecutive, same ``poly_id``) into snapped, planar polygons.

    A polygon that is not convex after snapping (a sliver made by clipping) is kept as its fan
    triangles, each a polygon of its own with the same ``poly``, so coverage stays exactly the
    reference's.
    """
    T = tris.n_triangles
    W, H = tris.width, tris.height
    if T == 0:
        e = np.zeros((0, 3))
        return ScreenPolygons(e, e, e, e, np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)),
                              tris, dict(tris.stats))
    pid = np.asarray(tris.poly_id)
    start = np.flatnonzero(np.r_[True, pid[1:] != pid[:-1]])
    ntri = np.diff(np.r_[start, T])
    Q = start.size
    M = int(ntri.max()) + 2
    nv = ntri + 2
    # Corner j of polygon q: j = 0 -> tri start.v0, j >= 1 -> tri (start + j - 1).v1, last -> .v2
    j = np.arange(M)[None, :]
    jj = np.minimum(j, nv[:, None] - 1)
    t_idx = start[:, None] + np.clip(jj - 1, 0, None)
    t_idx = np.minimum(t_idx, (start + ntri - 1)[:, None])
    corner = np.where(jj == 0, 0, np.where(jj - 1 < ntri[:, None], 1, 2))
    last = jj == nv[:, None] - 1
    t_idx = np.where(last, (start + ntri - 1)[:, None], t_idx)
    corner = np.where(last, 2, corner)
    xy = tris.xy[t_idx, corner]
    X, Y = snap(xy[..., 0]), snap(xy[..., 1])
    z = tris.z[t_idx, corner]
    inten = tris.colour[t_idx, corner].mean(axis=-1)
    used = j < nv[:, None]
    # Convexity in exact integers: every turn has the sign of the area (or is zero).
    nx = (j + 1) % nv[:, None]
    nn = (j + 2) % nv[:, None]
    Xn, Yn = np.take_along_axis(X, nx, 1), np.take_along_axis(Y, nx, 1)
    Xm, Ym = np.take_along_axis(X, nn, 1), np.take_along_axis(Y, nn, 1)
    turn = np.where(used, (Xn - X) * (Ym - Yn) - (Yn - Y) * (Xm - Xn), 0.0)
    area = np.where(used, X * Yn - Xn * Y, 0.0).sum(axis=1)
    s = np.sign(area)
    convex = np.all(turn * s[:, None] >= 0, axis=1)
    if not convex.all():
        # split the offenders into their triangles (each is its own "polygon")
        bad = np.flatnonzero(~convex)
        keep_t = np.ones(T, dtype=bool)
        parts = []
        for q in bad:
            keep_t[start[q]:start[q] + ntri[q]] = False
            parts.append(np.arange(start[q], start[q] + ntri[q]))
        # recurse: triangles are always convex
        order = np.sort(np.concatenate([np.flatnonzero(keep_t)] + parts))
        # unique ids per split triangle: mark them with a sub-id so they do not regroup
        sub = tris.poly_id[order].astype(np.int64) * 0
        grp = np.r_[True, pid[order][1:] != pid[order][:-1]]
        splitmask = ~keep_t[order]
        grp |= splitmask
        gid = np.cumsum(grp) - 1
        sub = gid
        t2 = replace(tris, xy=tris.xy[order], z=tris.z[order], zq=tris.zq[order], colour=tris.colour[order],
                     poly_id=sub, uv=None)
        sp = polygons_from_triangles(t2, plane_fit=plane_fit)
        real = pid[order][np.r_[np.flatnonzero(grp)]]
        sp.poly = real[sp.poly]
        sp.tris = replace(sp.tris, poly_id=real[sp.tris.poly_id])
        sp.stats = dict(tris.stats)
        sp.stats["nonconvex_split"] = int(bad.size)
        return sp
    # Plane z = a x + b y + c through the snapped vertices (least squares; exact for triangles).
    xs, ys = X / SUB, Y / SUB
    w = used.astype(float)
    cx = (xs * w).sum(1) / nv
    cy = (ys * w).sum(1) / nv
    cz = (z * w).sum(1) / nv
    dxs, dys, dzs = (xs - cx[:, None]) * w, (ys - cy[:, None]) * w, (z - cz[:, None]) * w
    sxx, sxy, syy = (dxs * dxs).sum(1), (dxs * dys).sum(1), (dys * dys).sum(1)
    sxz, syz = (dxs * dzs).sum(1), (dys * dzs).sum(1)
    det = sxx * syy - sxy * sxy
    ok = det > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(ok, (sxz * syy - syz * sxy) / det, 0.0)
        b = np.where(ok, (syz * sxx - sxz * sxy) / det, 0.0)
    c = cz - a * cx - b * cy
    if plane_fit:
        zp = np.where(ok[:, None], a[:, None] * xs + b[:, None] * ys + c[:, None], z)
    else:
        zp = z
    # Fan triangles of the planar polygons for the reference (same order as run_geometry's).
    qi = np.repeat(np.arange(Q), ntri)
    k = np.arange(T) - np.repeat(start, ntri)
    vi = np.stack([np.zeros(T, np.int64), k + 1, k + 2], axis=1)
    txy = np.stack([xs[qi[:, None], vi], ys[qi[:, None], vi]], axis=-1)
    tz = zp[qi[:, None], vi]
    ti = inten[qi[:, None], vi]
    zq = np.minimum(np.rint(np.clip(tz, 0, 1) * (1 << tris.z_bits)), (1 << tris.z_bits) - 1).astype(np.int64)
    new = ScreenTriangles(width=W, height=H, xy=txy, z=tz, zq=zq, colour=np.repeat(ti[..., None], 3, axis=-1),
                          poly_id=pid[start][qi].astype(np.int64), z_bits=tris.z_bits, stats=dict(tris.stats))
    return ScreenPolygons(X=X, Y=Y, z=zp, i=inten, nv=nv.astype(np.int64), poly=pid[start].astype(np.int64),
                          plane=np.stack([a, b, c], axis=1), tris=new, stats=dict(tris.stats))


def setup(scene: Scene, width: int, height: int, blocks: Blocks | None = None) -> ScreenPolygons:
    """The paper's set-up (2.2): transform, intensity, back-face removal, clipping -> polygons."""
    blocks = blocks or blocks_from_scene(scene, width, height)
    white = _white_scene(scene, blocks.control.ia, blocks.control.k)
    tris = run_geometry(white, width, height)
    return polygons_from_triangles(tris)


def quantise_rgbi(face_rgb: np.ndarray, intensity: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """RGBI 3/3/3/7 bits (3.1 d): ``R3 = round(7 r)``, ..., ``I7 = round(127 I)``.

    Returns ``(rgb3 (…, 3) uint8, i7 (…) uint8, rgb8 (…, 3) uint8)`` where the displayed 8-bit
    colour is ``round(255 * (R3 / 7) * (I7 / 127))`` (our display mapping; the paper gives
    only the bit widths). Rounding is half up.
    """
    rgb3 = np.clip(np.floor(np.asarray(face_rgb) * 7 + 0.5), 0, 7).astype(np.uint8)
    i7 = np.clip(np.floor(np.asarray(intensity) * 127 + 0.5), 0, 127).astype(np.uint8)
    rgb8 = np.floor(255.0 * (rgb3 / 7.0) * (i7[..., None] / 127.0) + 0.5).astype(np.uint8)
    return rgb3, i7, rgb8
