"""Shadows (seed 001, 2.5): Crow's shadow polygons, ray casting with a shadow map, and the
brute-force ray-to-the-light check both are measured against.

**Shadow polygons** (2.5 1)). Input: the ground polygon and, per edge, its two polygons and two
vertices (:func:`edge_table`, built from the scene by matching vertex positions; the paper
takes it as input). A *silhouette* edge joins a lit face (``N.L < 0``, face normal from the
corner order) and an unlit one. Its shadow polygon is the quad swept from the edge along the
light until the ground plane: ``a, b, b + t_b L, a + t_a L``. We wind each quad
counter-clockwise seen from outside the shadow volume, so after the view transform the
pipeline's back-face test is the paper's front/back classification: the quads that survive
culling are the front ones (+1), the same quads wound the other way give the back ones (-1).
After hidden-surface removal every shadow-polygon point in front of the Z-buffer adds its sign
to a count buffer; **a visible pixel with count > 0 gets intensity Ia** (our choice for "この画素
の輝度を落とす": the intensity an unlit face has, ``I = Ia``). The eye is assumed outside every
shadow volume (true of every built-in scene; the brute-force check would show otherwise).

**Ray casting** (2.5 2)). The light's coordinate system is orthographic along the light
(a parallel light): ``u, v`` across, depth ``d = P.lv`` scaled to [0, 1] (0 = nearest the light)
over the scene's extent; the light-space frame is the eye frame's size. Light-facing polygons
are drawn into a shadow buffer with the same hidden-surface algorithm (depth only); every
visible eye pixel ``(Xe, Ye, Ze)`` is taken to light space with one 4x4 matrix (inverse
viewport, inverse view-projection, light transform: 16 mul + 12 add and a divide per pixel)
and is shadowed when ``Z1 - buffer(floor X1, floor Y1) > eps``.

**Brute force** (:func:`ray_shadow`): for every visible pixel, its world point is cast toward
the light against every light-facing polygon but its own (a ray leaving a closed solid leaves
through a light-facing face), found through a uniform grid in light space -- no rasterisation,
no shadow polygons, no buffer.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import frame_setup, run_geometry
from rasterhw.golden_model.scene import Light, Material, Scene
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.vzbuf.blocks import (
    ScreenPolygons,
    ground_polygons,
    polygons_from_triangles,
)

__all__ = ["edge_table", "light_space", "ray_shadow", "screen_to_world", "shadow_polygons",
           "shadow_map_test", "check_light"]


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def face_normals(scene: Scene) -> np.ndarray:
    """Newell normals from the corner order (counter-clockwise -> along the normal)."""
    k = scene.max_corners
    j = np.arange(k)[None, :]
    nxt = (j + 1) % scene.nverts[:, None]
    q = np.take_along_axis(scene.positions, nxt[..., None], axis=1)
    used = (j < scene.nverts[:, None])[..., None]
    return np.where(used, np.cross(scene.positions, q), 0.0).sum(axis=1)


def check_light(scene: Scene, *, for_polygons: bool) -> np.ndarray:
    """The unit light direction, or a one-line error for a light the shadow code cannot take."""
    lv = _unit(scene.lights[0].direction)
    cam = scene.camera
    view = _unit(np.asarray(cam.target, float) - np.asarray(cam.eye, float))
    if for_polygons and abs(float(lv @ view)) < 1e-9:
        raise RasterhwError(
            f"vzbuf: light direction {tuple(scene.lights[0].direction)} is parallel to the screen: "
            "shadow polygons made after the view transform would reach infinity")
    return lv


def edge_table(scene: Scene, exclude: np.ndarray) -> dict:
    """Edges shared by exactly two polygons (not in ``exclude``): polygons p, q; vertices a, b."""
    k = scene.max_corners
    used = np.arange(k)[None, :] < scene.nverts[:, None]
    keep = np.ones(scene.n_polygons, bool)
    keep[exclude] = False
    pos = scene.positions
    _, vid = np.unique(pos.reshape(-1, 3), axis=0, return_inverse=True)
    vid = vid.reshape(pos.shape[:2])
    j = np.arange(k)[None, :]
    nxt = (j + 1) % scene.nverts[:, None]
    va, vb = vid, np.take_along_axis(vid, nxt, axis=1)
    ok = used & keep[:, None] & (va != vb)
    p, c = np.nonzero(ok)
    a, b = va[p, c], vb[p, c]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * (vid.max() + 1) + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    first = np.r_[True, ks[1:] != ks[:-1]]
    cnt = np.diff(np.r_[np.flatnonzero(first), ks.size])
    starts = np.flatnonzero(first)[cnt == 2]
    e0, e1 = order[starts], order[starts + 1]
    pa = pos[p[e0], c[e0]]
    pb = pos[p[e0], (c[e0] + 1) % scene.nverts[p[e0]]]
    return {"p": p[e0], "q": p[e1], "a": pa, "b": pb, "edges": int(starts.size)}


def shadow_polygons(scene: Scene, width: int, height: int) -> dict:
    """Shadow polygons of the scene's silhouette edges, front (+1) and back (-1), on screen."""
    lv = check_light(scene, for_polygons=True)
    ground = ground_polygons(scene)
    if ground.size == 0:
        raise RasterhwError(f"vzbuf: scene {scene.name!r} has no ground polygon (a polygon at the lowest y "
                            "facing up) for the shadow polygons to end on")
    gn = _unit(face_normals(scene)[ground[0]])
    g0 = scene.positions[ground[0], 0]
    ln = float(lv @ gn)
    if ln >= -1e-12:
        raise RasterhwError(f"vzbuf: light direction {tuple(scene.lights[0].direction)} never reaches the ground")
    fn = face_normals(scene)
    et = edge_table(scene, ground)
    lit = fn @ lv < 0
    sil = lit[et["p"]] != lit[et["q"]]
    a, b = et["a"][sil], et["b"][sil]
    ta = ((g0 - a) @ gn) / ln
    tb = ((g0 - b) @ gn) / ln
    keep = (ta > 1e-9) | (tb > 1e-9)
    a, b, ta, tb = a[keep], b[keep], np.maximum(ta[keep], 0), np.maximum(tb[keep], 0)
    p, q = et["p"][sil][keep], et["q"][sil][keep]
    a2, b2 = a + ta[:, None] * lv, b + tb[:, None] * lv
    ns = np.cross(b - a, lv)
    outward = np.einsum("ij,ij->i", ns, _unit_rows(fn[p]) + _unit_rows(fn[q])) > 0
    ns = np.where(outward[:, None], ns, -ns)
    quad = np.stack([a, b, b2, a2], axis=1)
    wn = np.cross(b - a, a2 - a) + np.cross(b2 - b, a - b)
    flip = np.einsum("ij,ij->i", wn, ns) < 0
    quad = np.where(flip[:, None, None], quad[:, [1, 0, 3, 2]], quad)
    n_init = int(quad.shape[0])
    out = {"initial": n_init, "silhouette_edges": int(sil.sum()), "edges": et["edges"]}
    for name, qd, nrm in (("front", quad, ns), ("back", quad[:, ::-1], -ns)):
        if n_init == 0:
            out[name] = None
            continue
        sc = Scene(name=f"{scene.name}-shadow-{name}", positions=qd, normals=np.repeat(nrm[:, None], 4, 1),
                   colours=np.ones_like(qd), nverts=np.full(n_init, 4, np.int64), camera=scene.camera,
                   lights=(Light(direction=tuple(scene.lights[0].direction)),), ambient=(0.0, 0.0, 0.0),
                   material=Material(ka=1.0, kd=0.0, ks=0.0))
        out[name] = polygons_from_triangles(run_geometry(sc, width, height))
    return out


def _unit_rows(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# ----------------------------------------------------------------------------- ray casting
def light_space(scene: Scene, width: int, height: int) -> dict:
    """The light's orthographic frame: basis, the world -> light-pixel 4x4, and its polygons."""
    lv = check_light(scene, for_polygons=False)
    helper = np.array([0.0, 1.0, 0.0]) if abs(lv[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = _unit(np.cross(helper, lv))
    v = np.cross(lv, u)
    used = np.arange(scene.max_corners)[None, :] < scene.nverts[:, None]
    pts = scene.positions[used]
    pu, pv, pd = pts @ u, pts @ v, pts @ lv
    span = max(np.ptp(pu), np.ptp(pv)) * 1.02 + 1e-12
    cu, cv = 0.5 * (pu.max() + pu.min()), 0.5 * (pv.max() + pv.min())
    dmin, dmax = pd.min(), pd.max()
    dr = (dmax - dmin) * 1.02 + 1e-12
    d0 = dmin - 0.01 * (dmax - dmin)
    sx, sy = width / span, height / span
    m = np.zeros((4, 4))
    m[0, :3], m[0, 3] = sx * u, width / 2 - sx * cu
    m[1, :3], m[1, 3] = -sy * v, height / 2 + sy * cv
    m[2, :3], m[2, 3] = lv / dr, -d0 / dr
    m[3, 3] = 1.0
    return {"lv": lv, "matrix": m}


def light_polygons(scene: Scene, width: int, height: int, ls: dict) -> ScreenPolygons:
    """Light-facing polygons in light space (no clipping needed: the frame holds the scene)."""
    fn = face_normals(scene)
    keep = np.flatnonzero(fn @ ls["lv"] < 0)
    m = ls["matrix"]
    pos = scene.positions[keep]
    lp = pos @ m[:3, :3].T + m[:3, 3]
    nv = scene.nverts[keep]
    # fan triangles in polygon order, as run_geometry hands them over
    per = nv - 2
    poly = np.repeat(np.arange(keep.size), per)
    jj = np.arange(poly.size) - np.repeat(np.cumsum(per) - per, per)
    idx = np.stack([np.zeros_like(jj), jj + 1, jj + 2], axis=1)
    tri = lp[poly[:, None], idx]
    t = ScreenTriangles(width=width, height=height, xy=tri[..., :2].copy(), z=tri[..., 2].copy(),
                        zq=np.zeros((poly.size, 3), np.int64), colour=np.zeros((poly.size, 3, 3)),
                        poly_id=keep[poly].astype(np.int64), stats={"polygons_in": int(keep.size)})
    return polygons_from_triangles(t)


def screen_to_world(scene: Scene, width: int, height: int, xs, ys, z) -> np.ndarray:
    """Eye-screen points (pixels, depth 0..1) -> world, through the inverse view-projection."""
    inv = np.linalg.inv(frame_setup(scene, width, height).mvp)
    ndc = np.stack([(np.asarray(xs) - width / 2) / (width / 2), (height / 2 - np.asarray(ys)) / (height / 2),
                    np.asarray(z), np.ones(np.shape(z))], axis=-1)
    w = ndc @ inv.T
    return w[:, :3] / w[:, 3:4]


def screen_to_light_matrix(scene: Scene, width: int, height: int, ls: dict) -> np.ndarray:
    """One 4x4: eye screen (x px, y px, z, 1) -> light screen (homogeneous)."""
    inv = np.linalg.inv(frame_setup(scene, width, height).mvp)
    vp = np.array([[2 / width, 0, 0, -1], [0, -2 / height, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    return ls["matrix"] @ inv @ vp


def shadow_map_test(scene: Scene, width: int, height: int, depth: np.ndarray, visible: np.ndarray,
                    sbuf: np.ndarray, ls: dict, eps: float) -> np.ndarray:
    """Stage 3 of tables 6-7: every visible pixel to light space, ``Z1 - buffer > eps``."""
    if not (isinstance(eps, (int, float)) and np.isfinite(eps) and eps > 0):
        raise RasterhwError(f"vzbuf: shadow-map eps must be a finite number > 0, not {eps!r}")
    rows, cols = np.nonzero(visible)
    mt = screen_to_light_matrix(scene, width, height, ls)
    h = np.stack([cols + 0.5, rows + 0.5, depth[rows, cols], np.ones(rows.size)], axis=0)
    lp = mt @ h
    x1, y1, z1 = lp[0] / lp[3], lp[1] / lp[3], lp[2] / lp[3]
    tx = np.clip(np.floor(x1), 0, sbuf.shape[1] - 1).astype(np.int64)
    ty = np.clip(np.floor(y1), 0, sbuf.shape[0] - 1).astype(np.int64)
    out = np.zeros_like(visible)
    out[rows, cols] = (z1 - sbuf[ty, tx]) > eps
    return out


def ray_shadow(scene: Scene, width: int, height: int, depth: np.ndarray, poly: np.ndarray,
               *, rel_eps: float = 1e-5) -> np.ndarray:
    """Brute force: is the segment from each visible pixel's world point to the light blocked?

    ``poly`` is the scene polygon per pixel (-1 = background). Returns an (H, W) bool array.
    """
    lv = _unit(scene.lights[0].direction)
    rows, cols = np.nonzero(poly >= 0)
    P = screen_to_world(scene, width, height, cols + 0.5, rows + 0.5, depth[rows, cols])
    own = poly[rows, cols]
    fn = face_normals(scene)
    cand = np.flatnonzero(fn @ lv < 0)
    helper = np.array([0.0, 1.0, 0.0]) if abs(lv[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = _unit(np.cross(helper, lv))
    v = np.cross(lv, u)
    k = scene.max_corners
    pos = scene.positions[cand]
    nv = scene.nverts[cand]
    U, V = pos @ u, pos @ v
    pu, pv = P @ u, P @ v
    size = float(np.ptp(scene.positions.reshape(-1, 3), axis=0).max())
    eps = rel_eps * size
    # uniform grid over light space, cell ~ the median polygon extent
    umin = min(U.min(), pu.min())
    vmin = min(V.min(), pv.min())
    ext = np.maximum(U.max(1) - U.min(1), V.max(1) - V.min(1))
    h = max(float(np.median(ext)) * 2.0, 1e-9 * size)
    ci0 = np.floor((U.min(1) - umin) / h).astype(np.int64)
    ci1 = np.floor((U.max(1) - umin) / h).astype(np.int64)
    cj0 = np.floor((V.min(1) - vmin) / h).astype(np.int64)
    cj1 = np.floor((V.max(1) - vmin) / h).astype(np.int64)
    nj = int(max(cj1.max(), np.floor((pv.max() - vmin) / h))) + 1
    ni_ = (ci1 - ci0 + 1)
    nj_ = (cj1 - cj0 + 1)
    cnt = ni_ * nj_
    pid = np.repeat(np.arange(cand.size), cnt)
    off = np.arange(pid.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ci = ci0[pid] + off // nj_[pid]
    cj = cj0[pid] + off % nj_[pid]
    cell = ci * nj + cj
    o = np.argsort(cell, kind="stable")
    cell_s, pid_s = cell[o], pid[o]
    pc = np.floor((pu - umin) / h).astype(np.int64) * nj + np.floor((pv - vmin) / h).astype(np.int64)
    a0 = np.searchsorted(cell_s, pc, side="left")
    a1 = np.searchsorted(cell_s, pc, side="right")
    blocked = np.zeros(rows.size, bool)
    # candidate pairs in chunks of points
    nc = a1 - a0
    chunk = 200_000
    start = 0
    cum = np.cumsum(nc)
    n_pts = rows.size
    j = np.arange(k)
    while start < n_pts:
        base = cum[start - 1] if start else 0
        stop = int(np.searchsorted(cum, base + chunk, side="right"))
        stop = max(stop, start + 1)
        stop = min(stop, n_pts)
        pts = np.arange(start, stop)
        m = nc[pts]
        pt = np.repeat(pts, m)
        kk = np.arange(pt.size) - np.repeat(np.cumsum(m) - m, m)
        cp = pid_s[a0[pt] + kk]
        gp = cand[cp]
        ok = gp != own[pt]
        pt, cp, gp = pt[ok], cp[ok], gp[ok]
        # inside the polygon's projection (convex; either winding)
        Uq, Vq = U[cp], V[cp]
        n_ = nv[cp]
        nxt = (j[None, :] + 1) % n_[:, None]
        Un, Vn = np.take_along_axis(Uq, nxt, 1), np.take_along_axis(Vq, nxt, 1)
        usedm = j[None, :] < n_[:, None]
        cr = (Un - Uq) * (pv[pt][:, None] - Vq) - (Vn - Vq) * (pu[pt][:, None] - Uq)
        cr = np.where(usedm, cr, 0.0)
        inside = np.all(cr >= 0, axis=1) | np.all(cr <= 0, axis=1)
        # ray P - t lv (toward the light) meets the polygon's plane at t > eps
        nrm = fn[gp]
        t = np.einsum("ij,ij->i", nrm, pos[cp, 0] - P[pt]) / (nrm @ (-lv))
        hit = inside & (t > eps)
        blocked[pt[hit]] = True
        start = stop
    out = np.zeros(poly.shape, bool)
    out[rows, cols] = blocked
    return out
