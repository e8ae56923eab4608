"""Golden geometry pipeline: the SNU paper's transformation and lighting stages.

Stages (seed 004, section 4.2; names as in the report and in ``docs/pipeline.md``),
each vectorised over every vertex or polygon of the scene at once:

``vertex_transform``   4x4 model-view-projection, w fixed at 1 (12 mul + 12 add)
``backface_cull``      orientation of corners 0, 1, 2 in homogeneous clip space
``normal_transform``   3x3 (inverse transpose of the view rotation) into eye space
``normalise``          unit normals: sum of squares, 1/sqrt, scale
``light``              ambient + diffuse + Blinn-Phong specular, directional lights,
                       viewer direction only, exponent from a lookup table
``clip``               Sutherland-Hodgman against the six planes of the view volume
``perspective_divide`` x, y, z times 1/w
``screen_map``         NDC -> pixels (y down), z in [0, 1] with 0 = near, ``zq``

then :func:`fan_triangulate` turns the clipped convex polygons into
:class:`~rasterhw.golden_model.screen.ScreenTriangles` in submission order.

Every floating-point step runs through an :class:`~rasterhw.golden_model.opcount.OpCounter`
so ``ScreenTriangles.ops`` holds what the code really did (see ``opcount.py``).

Conventions decided here (the papers are silent; see ``docs/pipeline.md``):

* a polygon is front-facing when its corners 0, 1, 2 run **counter-clockwise** seen
  from the eye (OpenGL's default); zero-area polygons are culled with the back faces;
* clip space is ``-w <= x, y <= w`` and ``0 <= z <= w`` (z already 0 = near, 1 = far
  after the divide, so the screen mapping needs no z offset);
* on a clip-plane crossing the new corner is interpolated from the inside corner
  toward the outside one, so an edge shared by two polygons is cut at the same point;
  on the near plane the new corner gets ``z = 0`` and ``w = near`` exactly;
* ``zq = min(rint(z * 2**z_bits), 2**z_bits - 1)`` (the paper's "multiply z by
  2^24"), flipped to ``2**z_bits - 1 - zq`` when ``z_far_is_zero``;
* screen x, y are clamped to ``[0, width] x [0, height]`` and z to ``<= 1``: a
  corner made by clipping a huge polygon can land a rounding error outside.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.opcount import OpCounter
from rasterhw.golden_model.scene import Camera, Scene
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = [
    "MAX_SIZE",
    "SPEC_LUT_SIZE",
    "STAGES",
    "Lighting",
    "backface_cull",
    "clip",
    "fan_triangulate",
    "frame_setup",
    "light",
    "normal_transform",
    "normalise",
    "perspective_divide",
    "projection_matrix",
    "run_geometry",
    "screen_map",
    "vertex_transform",
    "view_matrix",
]

STAGES = (
    "vertex_transform",
    "backface_cull",
    "normal_transform",
    "normalise",
    "light",
    "clip",
    "perspective_divide",
    "screen_map",
)
MAX_SIZE = 16384
#: Entries of the specular-exponent table over cos in [0, 1].
SPEC_LUT_SIZE = 1024

# Column layout of the per-corner array that travels through clipping.
_X, _Y, _Z, _W = 0, 1, 2, 3
_RGB = slice(4, 7)


def _ops(ops: OpCounter | None) -> OpCounter:
    return OpCounter() if ops is None else ops


# ----------------------------------------------------------------------------- set-up
def _unit(v: np.ndarray, what: str) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if not (n > 0.0 and math.isfinite(n)):
        raise RasterhwError(f"{what} {tuple(float(x) for x in v)} has no direction")
    return v / n


def view_matrix(camera: Camera) -> np.ndarray:
    """World -> eye space (right-handed, eye at the origin looking down -z, y up)."""
    eye = np.asarray(camera.eye, dtype=float)
    f = _unit(np.asarray(camera.target, dtype=float) - eye, "camera view direction")
    s = np.cross(f, np.asarray(camera.up, dtype=float))
    if not np.linalg.norm(s) > 1e-12:
        raise RasterhwError(f"camera up {camera.up} is parallel to the view direction")
    s = s / np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def projection_matrix(camera: Camera, aspect: float) -> np.ndarray:
    """Eye -> clip space: ``-w <= x, y <= w``, ``0 <= z <= w`` (z = 0 near, w = -z_eye)."""
    f = 1.0 / math.tan(math.radians(camera.fovy_deg) / 2.0)
    n, fa = camera.near, camera.far
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = fa / (n - fa)
    m[2, 3] = fa * n / (n - fa)
    m[3, 2] = -1.0
    return m


@dataclass(frozen=True)
class Lighting:
    """Per-frame lighting constants, all in eye space.

    ambient : (3,) ``ka * Ia``.
    to_light : (L, 3) unit vectors toward each light (``-direction``).
    half : (L, 3) unit Blinn half vectors between ``to_light`` and the viewer
        direction (0, 0, 1) -- the viewer's direction only, no distance.
    diffuse : (L, 3) ``kd * light colour``.
    specular : (L, 3) ``ks * light colour`` (all zero when ``ks == 0``).
    lut : (SPEC_LUT_SIZE,) ``(i / (SPEC_LUT_SIZE - 1)) ** shininess``.
    """

    ambient: np.ndarray
    to_light: np.ndarray
    half: np.ndarray
    diffuse: np.ndarray
    specular: np.ndarray
    lut: np.ndarray

    @property
    def has_specular(self) -> bool:
        return bool(np.any(self.specular > 0.0))


@dataclass(frozen=True)
class FrameSetup:
    """Per-frame constants (not counted: they are per frame, not per triangle)."""

    mvp: np.ndarray
    normal_matrix: np.ndarray
    lighting: Lighting
    near: float


def frame_setup(scene: Scene, width: int, height: int) -> FrameSetup:
    """Matrices and lighting constants for one frame."""
    mat = scene.material
    for name in ("ka", "kd", "ks"):
        v = getattr(mat, name)
        if not (math.isfinite(v) and v >= 0.0):
            raise RasterhwError(f"material {name} must be finite and >= 0, got {v!r}")
    if (
        isinstance(mat.shininess, bool)
        or not isinstance(mat.shininess, (int, np.integer))
        or not (0 <= mat.shininess <= 1024)
    ):
        raise RasterhwError(
            f"material shininess must be an integer in 0..1024, got {mat.shininess!r}"
        )
    amb = np.asarray(scene.ambient, dtype=float)
    if amb.shape != (3,) or not np.all(np.isfinite(amb)) or np.any(amb < 0):
        raise RasterhwError(f"ambient must be three finite values >= 0, got {scene.ambient!r}")

    view = view_matrix(scene.camera)
    proj = projection_matrix(scene.camera, width / height)
    rot = view[:3, :3]
    nmat = np.linalg.inv(rot).T
    to_light, half, dif, spe = [], [], [], []
    for i, lt in enumerate(scene.lights):
        c = np.asarray(lt.colour, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)) or np.any(c < 0):
            raise RasterhwError(
                f"light {i} colour must be three finite values >= 0, got {lt.colour!r}"
            )
        d = rot @ _unit(np.asarray(lt.direction, dtype=float), f"light {i} direction")
        tl = -d / np.linalg.norm(d)
        h = tl + np.array([0.0, 0.0, 1.0])
        hn = np.linalg.norm(h)
        # Light straight from behind the viewer's line: no highlight can face both.
        h = h / hn if hn > 1e-12 else np.zeros(3)
        to_light.append(tl)
        half.append(h)
        dif.append(mat.kd * c)
        spe.append(mat.ks * c)
    shape = (len(to_light), 3)
    lut = (np.arange(SPEC_LUT_SIZE) / (SPEC_LUT_SIZE - 1)) ** int(mat.shininess)
    lighting = Lighting(
        ambient=mat.ka * amb,
        to_light=np.array(to_light).reshape(shape),
        half=np.array(half).reshape(shape),
        diffuse=np.array(dif).reshape(shape),
        specular=np.array(spe).reshape(shape),
        lut=lut,
    )
    return FrameSetup(
        mvp=proj @ view, normal_matrix=nmat, lighting=lighting, near=scene.camera.near
    )


# ----------------------------------------------------------------------------- stages
def _scale_rows(o: OpCounter, a: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``a * s[:, None]`` for (V, d) ``a`` and (V,) ``s``, counted as V*d mul: computed one
    column at a time (same values; a broadcast over a short last axis runs NumPy's inner
    loop once per row)."""
    out = np.empty(np.broadcast_shapes(np.shape(a), (np.shape(s)[0], 1)))
    a = np.broadcast_to(a, out.shape)
    for c in range(out.shape[1]):
        np.multiply(a[:, c], s, out=out[:, c])
    o.count("mul", out.size)
    return out


def vertex_transform(
    positions: np.ndarray, mvp: np.ndarray, *, ops: OpCounter | None = None
) -> np.ndarray:
    """(V, 3) world positions -> (V, 4) clip coordinates; w of the input fixed at 1.

    Per vertex: 12 mul + 12 add (the fourth column is added, not multiplied).
    """
    return _ops(ops).affine(positions, mvp[:, :3], mvp[:, 3])


def normal_transform(
    normals: np.ndarray, normal_matrix: np.ndarray, *, ops: OpCounter | None = None
) -> np.ndarray:
    """(V, 3) normals -> eye space with a 3x3 matrix: 9 mul + 6 add per vertex."""
    return _ops(ops).affine(normals, normal_matrix)


def normalise(v: np.ndarray, *, ops: OpCounter | None = None) -> np.ndarray:
    """(V, 3) -> unit length: 3 mul + 2 add, 1 sqrt, 1 recip, 3 mul per vertex.

    Inputs must have a finite, non-zero length (``run_geometry`` checks the scene).
    """
    o = _ops(ops)
    inv = o.recip(o.sqrt(o.dot(v, v)))
    return _scale_rows(o, v, inv)


def light(
    normals: np.ndarray, base: np.ndarray, lighting: Lighting, *, ops: OpCounter | None = None
) -> np.ndarray:
    """Lit vertex colours (V, 3) from unit eye-space normals and base colours.

    ``I = base * (ka Ia + sum_l kd C_l max(0, N.L_l)) + sum_l ks C_l T[N.H_l]``, clamped
    to 1, where ``L_l`` points toward light ``l``, ``H_l`` is the Blinn half vector
    with the viewer direction (0, 0, 1) and ``T`` the exponent table (entry nearest
    to ``N.H``; zero where ``N.L <= 0`` or ``N.H <= 0``). With ``ks = 0`` and
    ``ka = 1`` this is the vector Z-buffer paper's ``I = Ia + k (-N.L)/(|N||L|)``
    (``L`` the travel direction) for a lit face and ``I = Ia`` for an unlit one,
    times the base colour.

    Per vertex and light: 3 mul + 2 add + 1 cmp (N.L), 3 mul + 3 add (diffuse);
    with specular also 3 mul + 2 add + 1 cmp (N.H), 1 mul + 1 cvt + 1 lookup
    (table), 3 mul (+ 3 add from the second light on). Per vertex once:
    3 mul (+ 3 add with specular) and 3 cmp (clamp).
    """
    o = _ops(ops)
    n_v = normals.shape[0]
    diffuse = np.broadcast_to(lighting.ambient, (n_v, 3))
    spec = None
    for li in range(lighting.to_light.shape[0]):
        ndl = o.dot(normals, lighting.to_light[li])
        lit = o.gt(ndl, 0.0)
        ndl = np.where(lit, ndl, 0.0)
        term = _scale_rows(o, lighting.diffuse[li][None, :], ndl)
        if li == 0:  # ambient (a broadcast row) + term, one column at a time
            for c in range(3):
                np.add(diffuse[:, c], term[:, c], out=term[:, c])
            o.count("add", term.size)
            diffuse = term
        else:
            diffuse = o.add(diffuse, term)
        if lighting.has_specular:
            ndh = o.dot(normals, lighting.half[li])
            on = lit & o.gt(ndh, 0.0)
            idx = o.rint_int(o.mul(np.where(on, ndh, 0.0), SPEC_LUT_SIZE - 1))
            s = np.where(on, o.lookup(lighting.lut, idx), 0.0)
            term = _scale_rows(o, lighting.specular[li][None, :], s)
            spec = term if spec is None else o.add(spec, term)
    col = o.mul(base, diffuse)
    if spec is not None:
        np.add(col, spec, out=col)  # in place: fresh pages cost more than the arithmetic
        o.count("add", col.size)
    np.minimum(col, 1.0, out=col)
    o.count("cmp", col.size)
    return col


def backface_cull(clip_corners: np.ndarray, *, ops: OpCounter | None = None) -> np.ndarray:
    """Front-facing mask (P,) from the clip coordinates of corners 0, 1, 2 (P, 3, 4).

    The determinant of the corners' (x, y, w) rows is a negative multiple of the signed
    volume of (eye, v0, v1, v2) for any signs of w, so no divide is needed and corners
    behind the eye are handled. ``det > 0``: counter-clockwise seen from the eye.
    Per polygon: 9 mul + 5 add + 1 cmp.
    """
    o = _ops(ops)
    x, y, w = clip_corners[:, :, _X], clip_corners[:, :, _Y], clip_corners[:, :, _W]
    m0 = o.sub(o.mul(y[:, 1], w[:, 2]), o.mul(w[:, 1], y[:, 2]))
    m1 = o.sub(o.mul(x[:, 1], w[:, 2]), o.mul(w[:, 1], x[:, 2]))
    m2 = o.sub(o.mul(x[:, 1], y[:, 2]), o.mul(y[:, 1], x[:, 2]))
    det = o.add(o.sub(o.mul(x[:, 0], m0), o.mul(y[:, 0], m1)), o.mul(w[:, 0], m2))
    return o.gt(det, 0.0)


# Clip planes in the order applied: (name, axis, side). side +1: axis <= w, distance
# w - axis; side -1: axis >= -w, distance w + axis; the near plane is z >= 0, distance z.
# Near goes first so every later corner has w >= near > 0.
_PLANES = (
    ("near", _Z, 0),
    ("far", _Z, +1),
    ("left", _X, -1),
    ("right", _X, +1),
    ("bottom", _Y, -1),
    ("top", _Y, +1),
)


def _inside(o: OpCounter, v: np.ndarray, axis: int, side: int) -> np.ndarray:
    if side == 0:
        return o.ge(v[:, axis], 0.0)
    if side > 0:
        return o.le(v[:, axis], v[:, _W])
    return o.ge(v[:, axis], -v[:, _W])  # sign change: not counted


def _distance(o: OpCounter, v: np.ndarray, axis: int, side: int) -> np.ndarray:
    if side == 0:
        return v[:, axis]
    if side > 0:
        return o.sub(v[:, _W], v[:, axis])
    return o.add(v[:, _W], v[:, axis])


def clip(
    corners: np.ndarray, nverts: np.ndarray, near: float, *, ops: OpCounter | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sutherland-Hodgman clipping of convex polygons against the view volume.

    Parameters
    ----------
    corners : (P, K, C) per-corner rows ``x, y, z, w`` (clip space) then attributes,
        which are interpolated linearly along cut edges.
    nverts : (P,) corners in use.
    near : the camera's near distance (``w`` of any point on the near plane).

    Returns
    -------
    out : (P, K + 6, C) clipped corners.
    n_out : (P,) corners in use; 0 for a polygon clipped away.
    cut : (P,) bool, whether a plane cut the polygon (it crossed a plane).

    Work is vectorised over polygons; the loop runs over the six planes. Each plane
    costs one compare per corner of every polygon still alive; only polygons with
    corners on both sides pay for the cut: per new corner 2 distances (0 for near),
    1 add + 1 div for ``t``, and C add + C mul + C add to interpolate (C - 2 on the
    near plane, where z and w are exact).
    """
    o = _ops(ops)
    n_p, k, n_c = corners.shape
    nv = np.asarray(nverts, dtype=np.int64)
    hard = _clip_trivial(corners, nv, o)
    out = np.zeros((n_p, k + 6, n_c))
    out[:, :k] = corners
    n_out = nv.copy()
    cut = np.zeros(n_p, dtype=bool)
    if hard.size:
        out[hard], n_out[hard], cut[hard] = _clip_planes(corners[hard], nv[hard], near, o)
    n_out[n_out < 3] = 0
    return out, n_out, cut


def _clip_trivial(corners: np.ndarray, nv: np.ndarray, o: OpCounter) -> np.ndarray:
    """The polygons that cross a clip plane (indices); the rest come out of :func:`clip`
    unchanged.

    Polygons with every corner inside every plane (most of a scene) are not cut: the planes'
    compares are counted for them as the plane loop would count them (one per corner per
    plane), and only the rest go through Sutherland-Hodgman. Same corners, same counts."""
    n_p, k, _ = corners.shape
    w = corners[..., _W]
    inside = np.ones((n_p, k), dtype=bool)
    for _name, axis, side in _PLANES:
        a = corners[..., axis]
        inside &= (a >= 0.0) if side == 0 else (a <= w) if side > 0 else (a >= -w)
    if nv.size == 0 or int(nv.min()) == k:  # every slot used (k-gons); columns, not a short axis
        trivial = inside[:, 0].copy()
        for j in range(1, k):
            trivial &= inside[:, j]
    else:
        trivial = np.all(inside | ~(np.arange(k)[None, :] < nv[:, None]), axis=1)
    n_trivial = int(nv.sum()) - int(nv[~trivial].sum())
    o.count("cmp", len(_PLANES) * n_trivial)
    return np.flatnonzero(~trivial)


def _clip_flat(corners: np.ndarray, nverts: np.ndarray, near: float, o: OpCounter,
               hard: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`clip` followed by the gather of the used corners of the polygons that survive,
    back to back in polygon order, without building the padded ``(P, K + 6, C)`` array:
    only polygons that cross a plane are clipped (and copied).

    Returns ``(flat (V, C), n_clip (P,) corners per polygon (0 = clipped away), cut (P,))``,
    exactly what ``clip`` and that gather give. ``hard`` is :func:`_clip_trivial` of the
    corners (already counted)."""
    n_p, k, n_c = corners.shape
    nv = np.asarray(nverts, dtype=np.int64)
    n_out = nv.copy()
    cut = np.zeros(n_p, dtype=bool)
    if hard.size == 0 and (nv.size == 0 or int(nv.min()) == k):  # nothing to clip, all slots used
        return corners.reshape(n_p * k, n_c), n_out, cut
    sub = None
    if hard.size:
        sub, n_out[hard], cut[hard] = _clip_planes(corners[hard], nv[hard], near, o)
    n_out[n_out < 3] = 0
    first = np.cumsum(n_out) - n_out
    flat = np.empty((int(n_out.sum()), n_c))
    easy = np.ones(n_p, dtype=bool)
    easy[hard] = False
    _gather_used(flat, first, corners, np.flatnonzero(easy), n_out)
    if sub is not None:
        live = np.flatnonzero(n_out[hard] > 0)
        _gather_used(flat, first[hard[live]], sub, live, n_out[hard[live]], rows_are_local=True)
    return flat, n_out, cut


def _gather_used(flat: np.ndarray, first: np.ndarray, src: np.ndarray, polys: np.ndarray,
                 n: np.ndarray, rows_are_local: bool = False) -> None:
    """Copy the first ``n[p]`` corners of ``src[p]`` for ``p`` in ``polys`` to
    ``flat[first[p]:]`` (``first`` and ``n`` indexed like ``polys`` when ``rows_are_local``,
    else by polygon)."""
    if polys.size == 0:
        return
    cnt = n if rows_are_local else n[polys]
    dst0 = first if rows_are_local else first[polys]
    rows = np.repeat(polys, cnt)
    cols = np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    flat[np.repeat(dst0, cnt) + cols] = src[rows, cols]


def _clip_planes(corners: np.ndarray, nverts: np.ndarray, near: float, o: OpCounter
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plane-by-plane Sutherland-Hodgman loop of :func:`clip` (every polygon through every plane)."""
    n_p, k, n_c = corners.shape
    m = k + 6
    out = np.zeros((n_p, m, n_c))
    out[:, :k] = corners
    n_out = np.asarray(nverts, dtype=np.int64).copy()
    cut = np.zeros(n_p, dtype=bool)
    slots = np.arange(m)
    for _name, axis, side in _PLANES:
        live = np.flatnonzero(n_out > 0)
        if live.size == 0:
            break
        sub = out[live]
        n_sub = n_out[live]
        used = slots[None, :] < n_sub[:, None]
        ins = np.zeros(used.shape, dtype=bool)
        ins[used] = _inside(o, sub[used], axis, side)
        n_in = ins.sum(axis=1)
        n_out[live[n_in == 0]] = 0
        xi = np.flatnonzero((n_in > 0) & (n_in < n_sub))
        if xi.size == 0:
            continue
        polys = live[xi]
        cut[polys] = True
        px, nx, ix = sub[xi], n_sub[xi], ins[xi]
        valid = used[xi]
        prev = (slots[None, :] - 1 + nx[:, None]) % nx[:, None]
        ip = np.take_along_axis(ix, prev, axis=1)
        crossing = valid & (ip != ix)
        keep = valid & ix
        cnt = crossing.astype(np.int64) + keep
        start = np.cumsum(cnt, axis=1) - cnt
        new_n = cnt.sum(axis=1)
        if int(new_n.max()) > m:
            raise RasterhwError(
                "clip: a polygon gained more corners than a convex one can; polygons must be convex"
            )
        qi, si = np.nonzero(crossing)
        pi = prev[qi, si]
        a, b = px[qi, pi], px[qi, si]
        a_in = ix[qi, pi][:, None]
        v_in, v_out = np.where(a_in, a, b), np.where(a_in, b, a)
        d_in = _distance(o, v_in, axis, side)
        d_out = _distance(o, v_out, axis, side)
        t = o.div(d_in, o.sub(d_in, d_out))[:, None]
        new_v = np.empty_like(v_in)
        if side == 0:
            cols = [c for c in range(n_c) if c not in (_Z, _W)]
            new_v[:, _Z], new_v[:, _W] = 0.0, near
        else:
            cols = list(range(n_c))
        new_v[:, cols] = o.add(v_in[:, cols], o.mul(t, o.sub(v_out[:, cols], v_in[:, cols])))
        fresh = np.zeros((xi.size, m, n_c))
        fresh[qi, start[qi, si]] = new_v
        qk, sk = np.nonzero(keep)
        fresh[qk, start[qk, sk] + crossing[qk, sk]] = px[qk, sk]
        out[polys] = fresh
        n_out[polys] = new_n
    return out, n_out, cut


def perspective_divide(clip_xyzw: np.ndarray, *, ops: OpCounter | None = None) -> np.ndarray:
    """(V, 4) clip -> (V, 3) normalised device coordinates: 1 recip + 3 mul per vertex."""
    o = _ops(ops)
    inv_w = o.recip(clip_xyzw[:, _W])
    return _scale_rows(o, clip_xyzw[:, :3], inv_w)


def screen_map(
    ndc: np.ndarray,
    width: int,
    height: int,
    *,
    z_bits: int = 24,
    z_far_is_zero: bool = False,
    ops: OpCounter | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NDC (V, 3) -> pixel xy (V, 2), z (V,) in [0, 1] (0 = near) and zq (V,) int64.

    x = -1 -> 0, +1 -> width; y = +1 -> 0 (top), -1 -> height. Per vertex:
    2 mul + 2 add (x, y), 5 cmp (clamps of x, y, z), 1 mul + 1 cvt + 1 cmp (zq),
    1 add if flipped.
    """
    o = _ops(ops)
    hw, hh = 0.5 * width, 0.5 * height
    # x, y computed in place in their columns of the result (fresh pages cost more than the
    # arithmetic): per column 1 mul, 1 add, 2 cmp, as the formulas read.
    xy = np.empty((ndc.shape[0], 2))
    for c, scale, off, hi in ((0, hw, hw, float(width)), (1, -hh, hh, float(height))):
        v = xy[:, c]
        np.multiply(ndc[:, c], scale, out=v)
        v += off
        np.maximum(v, 0.0, out=v)
        np.minimum(v, hi, out=v)
        o.count("mul", v.size)
        o.count("add", v.size)
        o.count("cmp", 2 * v.size)
    # z >= 0 already: clipping leaves z_clip >= 0 and w > 0, and the product of two
    # non-negative floats is non-negative, so only the top needs a clamp.
    z = o.minimum(ndc[:, 2], 1.0)
    top = (1 << z_bits) - 1
    zq = o.minimum(o.rint_int(o.mul(z, float(1 << z_bits))), top)
    if z_far_is_zero:
        zq = o.sub(top, zq)
    return xy, z, zq.astype(np.int64)


def fan_triangulate(nverts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangles of convex polygons stored back to back.

    Returns (T, 3) indices into the concatenated corner list (polygon ``p``'s corners
    start at ``sum(nverts[:p])``) and (T,) polygon indices: polygon order, and within
    a polygon the fan (0, i, i + 1), i = 1 .. n - 2. Polygons with n < 3 give none.
    """
    n = np.asarray(nverts, dtype=np.int64)
    first = np.cumsum(n) - n
    per = np.maximum(n - 2, 0)
    poly = np.repeat(np.arange(n.size), per)
    j = np.arange(poly.size) - np.repeat(np.cumsum(per) - per, per)
    base = first[poly]
    idx = np.stack([base, base + j + 1, base + j + 2], axis=-1)
    return idx, poly


# ----------------------------------------------------------------------------- top level
def _check_int(name: str, v, lo: int, hi: int) -> int:
    if isinstance(v, bool):
        raise RasterhwError(f"{name} must be an integer in {lo}..{hi}, got {v!r}")
    try:
        i = operator.index(v)
    except TypeError:
        raise RasterhwError(f"{name} must be an integer in {lo}..{hi}, got {v!r}") from None
    if not lo <= i <= hi:
        raise RasterhwError(f"{name} must be in {lo}..{hi}, got {i}")
    return i



def check_geometry_args(who: str, scene, width, height, z_bits) -> tuple[int, int, int]:
    """A geometry run's arguments checked (one-line ``RasterhwError`` naming ``who``) and the
    scene validated: ``(width, height, z_bits)`` as ints."""
    width = _check_int("width", width, 1, MAX_SIZE)
    height = _check_int("height", height, 1, MAX_SIZE)
    z_bits = _check_int("z_bits", z_bits, 1, 32)
    if not isinstance(scene, Scene):
        raise RasterhwError(f"{who} needs a Scene, got {type(scene).__name__}")
    scene.validate()
    return width, height, z_bits

def run_geometry(
    scene: Scene, width: int, height: int, *, z_bits: int = 24, z_far_is_zero: bool = False
) -> ScreenTriangles:
    """Transform, light, cull, clip and map a scene to screen-space triangles.

    Order: vertex_transform -> backface_cull -> (front polygons only) normal_transform
    -> normalise -> light -> clip -> perspective_divide -> screen_map -> fan. The paper's
    table 1 order with the cull moved right after the vertex transform, where the clip
    coordinates it needs first exist, so back faces are not lit.
    """
    width, height, z_bits = check_geometry_args("run_geometry", scene, width, height, z_bits)
    n_p, k = scene.n_polygons, scene.max_corners
    # A scene of k-gons (every corner slot used, e.g. all triangles) takes reshapes where a
    # mixed one takes boolean gathers of the used slots; same values, same order.
    full = int(scene.nverts.min()) == k
    used = np.arange(k)[None, :] < scene.nverts[:, None]

    def used_of(a: np.ndarray) -> np.ndarray:  # (P, K, d) -> (corners in use, d)
        return a.reshape(-1, a.shape[-1]) if full else a[used]

    cols = used_of(scene.colours)
    if np.any(cols < 0.0) or np.any(cols > 1.0):
        raise RasterhwError(f"scene {scene.name!r}: vertex colours must be in [0, 1]")
    nrm = used_of(scene.normals)
    nn = np.einsum("ij,ij->i", nrm, nrm)
    if not np.all((nn > 1e-200) & (nn < 1e200)):
        raise RasterhwError(
            f"scene {scene.name!r}: a vertex normal has zero or absurd length; rescale it"
        )
    setup = frame_setup(scene, width, height)
    o = OpCounter()

    with o.stage("vertex_transform"):
        clip_used = vertex_transform(used_of(scene.positions), setup.mvp, ops=o)
    if full:
        clip_pos = clip_used.reshape(n_p, k, 4)
    else:
        clip_pos = np.zeros((n_p, k, 4))
        clip_pos[used] = clip_used
        # Padding slots repeat the last corner so every slot stays finite.
        last = clip_pos[np.arange(n_p), scene.nverts - 1]
        clip_pos[~used] = np.broadcast_to(last[:, None, :], clip_pos.shape)[~used]

    with o.stage("backface_cull"):
        front = backface_cull(clip_pos[:, :3], ops=o)
    fidx = np.flatnonzero(front)
    every = fidx.size == n_p

    def front_of(a: np.ndarray) -> np.ndarray:  # (P, ...) -> front polygons only
        return a if every else a[fidx]

    with o.stage("normal_transform"):
        n_f = front_of(scene.normals)
        n_eye = normal_transform(n_f.reshape(-1, 3) if full else n_f[used[fidx]],
                                 setup.normal_matrix, ops=o)
    with o.stage("normalise"):
        n_unit = normalise(n_eye, ops=o)
    with o.stage("light"):
        c_f = front_of(scene.colours)
        lit = light(n_unit, c_f.reshape(-1, 3) if full else c_f[used[fidx]], setup.lighting, ops=o)

    n_attr = 7 + (2 if scene.uv is not None else 0)
    clip_f = front_of(clip_pos)
    with o.stage("clip"):
        hard = _clip_trivial(clip_f, scene.nverts[fidx], o)
    if full and hard.size == 0:
        # nothing crosses a plane and every slot is used: the corners go on as they are
        # (what clip and the gather of used corners would give, without the copies)
        n_clip = scene.nverts[fidx].astype(np.int64)
        cut = np.zeros(fidx.size, dtype=bool)
        xyzw = clip_f.reshape(-1, 4)
        rgb = lit
        uv = front_of(scene.uv).reshape(-1, 2) if scene.uv is not None else None
    else:
        corners = np.zeros((fidx.size, k, n_attr))
        corners[:, :, :4] = clip_f
        if full:
            corners[:, :, _RGB] = lit.reshape(fidx.size, k, 3)
        else:
            corners[:, :, _RGB][used[fidx]] = lit
        if scene.uv is not None:
            corners[:, :, 7:9] = front_of(scene.uv)
        with o.stage("clip"):
            # the used corners of the polygons that survive, back to back (only polygons
            # that cross a plane are clipped; see clip)
            flat, n_clip, cut = _clip_flat(corners, scene.nverts[fidx], setup.near, o, hard)
        xyzw, rgb = flat[:, :4], flat[:, _RGB]
        uv = flat[:, 7:9] if scene.uv is not None else None
    drawn = np.flatnonzero(n_clip > 0)
    n_draw = n_clip[drawn]

    with o.stage("perspective_divide"):
        ndc = perspective_divide(xyzw, ops=o)
    with o.stage("screen_map"):
        xy, z, zq = screen_map(
            ndc, width, height, z_bits=z_bits, z_far_is_zero=z_far_is_zero, ops=o
        )

    tri, tri_poly = fan_triangulate(n_draw)
    poly_id = fidx[drawn][tri_poly]
    if tri.shape[0] * 3 == xyzw.shape[0] and drawn.size == tri.shape[0]:
        # triangles only: the fan is the identity, (T, 3) corners back to back
        def corners_of(a: np.ndarray) -> np.ndarray:
            return a.reshape(tri.shape[0], 3, *a.shape[1:])
    else:
        def corners_of(a: np.ndarray) -> np.ndarray:
            return a[tri]
    ops = o.as_dict()
    ops["polygons"] = n_p
    ops["vertices"] = int(scene.nverts.sum())
    ops["triangles"] = int(tri.shape[0])
    stats = {
        "polygons_in": n_p,
        "polygons_culled": int(n_p - fidx.size),
        "polygons_clipped_away": int(fidx.size - drawn.size),
        "polygons_drawn": int(drawn.size),
        "polygons_cut": int(np.count_nonzero(cut[drawn])),
        "triangles": int(tri.shape[0]),
    }
    return ScreenTriangles(
        width=width,
        height=height,
        xy=corners_of(xy),
        z=corners_of(z),
        zq=corners_of(zq),
        colour=np.ascontiguousarray(corners_of(rgb)),
        poly_id=poly_id.astype(np.int64),
        uv=np.ascontiguousarray(corners_of(uv)) if uv is not None else None,
        z_bits=z_bits,
        z_far_is_zero=bool(z_far_is_zero),
        stats=stats,
        ops=ops,
    )
