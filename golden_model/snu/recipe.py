"""SNU geometry as the paper's text counts it (seed 004, 4.2.1-4.2.5): a labelled variant of
``golden_model/pipeline.py``.

The full pipeline (``pipeline.run_geometry``) is what we would build today; this module is the
recipe the paper's operation counts describe, run on the same scenes through the same counted
operations (:class:`~rasterhw.golden_model.opcount.OpCounter`), so that its counts *come out of
the code* and can be set beside table 1. Per vertex:

==================== ============================================ =================
stage                what the recipe does                         counted
==================== ============================================ =================
vertex_transform     4x4 matrix, w fixed at 1; the viewport's      12 mul + 12 add
                     offsets are **folded into the matrix** (clip
                     space is PHIGS NPC: 0 <= x, y, z <= w)
normal_transform     3x3 matrix                                   9 mul + 6 add
normalise            sum of squares, 1/sqrt (sqrt + reciprocal,    6 mul + 2 add
                     the paper's "2 operations"), scale            + 1 sqrt + 1 div
light                **one inner product** d = N.L; the Blinn      12 mul + 10 add
                     term N.H = (d + n_z) / |L + V| because the    + 3 cmp
                     viewer direction is V = (0, 0, 1) ("direction + 1 lookup
                     only"), so it needs an add, not a second dot
                     product; the exponent table is indexed by
                     the mantissa of (d + n_z + magic) (one add,
                     no multiply); per channel
                     min(Cd (A + D d) + S T, 1)
clip                 the paper's "compare part" only: 6 compares   6 cmp
                     against 0 and w; polygons that need cutting
                     go to ``pipeline.clip`` in stage
                     ``clip_cut`` (outside table 1, as in the
                     paper, which counts only the compares)
perspective_divide   1/w, 3 mul                                   3 mul + 1 div
screen_map           x * W, y * (-H) + H (y flip), z * (-2^24) +   3 mul + 2 add
                     2^24 (far = 0)
==================== ============================================ =================

Stages outside table 1 are counted too and reported separately: ``clip_cut`` (the actual
Sutherland-Hodgman cut, only for polygons that cross a plane) and ``to_integer`` (float -> int
of z with the 24-bit clamp, and the colour floor at 0: the paper's recipe has no test of
N.L < 0, so a back-lit vertex gets a diffuse term below the ambient one and can go negative).
There is no back-face cull (the paper has none).

Where the recipe's image differs from the full pipeline's, and why, is measured in
``docs/snu_geometry.md`` (:func:`compare_with_full`).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.opcount import OpCounter
from rasterhw.golden_model.pipeline import (
    check_geometry_args,
    clip,
    fan_triangulate,
    frame_setup,
    normal_transform,
    normalise,
    perspective_divide,
    vertex_transform,
)
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.snu.paper import PAPER_TEXT_COUNTS

__all__ = ["LUT_BITS", "TEXT_PER_TRIANGLE", "TABLE1_STAGES", "npc_matrix", "ops_per_triangle",
           "run_geometry_paper", "light_paper", "compare_with_full"]

#: Table 1's stages in its order.
TABLE1_STAGES = ("vertex_transform", "normal_transform", "normalise", "light", "clip",
                 "perspective_divide", "screen_map")
#: The per-triangle numbers the paper's *text* gives (4.2.1-4.2.5): its per-vertex mix
#: (``paper.PAPER_TEXT_COUNTS``) x 3; table 1 prints 72 for lighting and 24 for clipping instead
#: (same 270 total).
TEXT_PER_TRIANGLE = {s: 3 * sum(PAPER_TEXT_COUNTS[s].values()) for s in TABLE1_STAGES}
#: The exponent table has 2**LUT_BITS entries per unit of (d + n_z) over [-2, 2].
LUT_BITS = 9
_LUT_OFFSET = 2.0  # (d + n_z) >= -2: the offset is folded into the magic constant
_MAGIC = 1.5 * 2.0 ** (52 - LUT_BITS) + _LUT_OFFSET
_MANT = (1 << 52) - 1


def npc_matrix(mvp: np.ndarray) -> np.ndarray:
    """Fold the viewport offsets into the matrix: clip x' = (x + w)/2, y' = (y + w)/2, so that
    after the divide x, y, z all lie in [0, 1] (PHIGS normalised projection coordinates)."""
    fold = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 1, 0], [0, 0, 0, 1]])
    return fold @ mvp


def _lut(shininess: int, c: float) -> np.ndarray:
    s = np.arange(4 * (1 << LUT_BITS) + 1) / float(1 << LUT_BITS) - _LUT_OFFSET
    return np.clip(s * c, 0.0, 1.0) ** int(shininess)


def light_paper(normals: np.ndarray, base: np.ndarray, lighting, shininess: int, *,
                ops: OpCounter | None = None) -> np.ndarray:
    """The paper's lighting: one inner product per vertex (see the module docstring).

    ``lighting`` is :class:`pipeline.Lighting` with exactly one light. Returns (V, 3) colours,
    clamped above at 1 only (the paper's 3 compares), possibly negative for back-lit vertices.
    """
    o = OpCounter() if ops is None else ops
    if lighting.to_light.shape[0] != 1:
        raise RasterhwError(f"the paper's recipe has one directional light, not {lighting.to_light.shape[0]}")
    to_light = lighting.to_light[0]
    lv = np.linalg.norm(to_light + np.array([0.0, 0.0, 1.0]))
    c = 1.0 / lv if lv > 1e-12 else 0.0
    lut = _lut(shininess, c)
    d = o.dot(normals, to_light)  # the one inner product: 3 mul + 2 add
    s = o.add(d, normals[:, 2])  # (N.L + N.V), V = (0, 0, 1): N.H * |L + V|
    u = o.add(s, _MAGIC)  # the mantissa of u holds round((s + 2) * 2**LUT_BITS)
    idx = (u.view(np.int64) & _MANT) - (1 << 51)  # integer bit work (fxfr + and), not counted
    t = o.lookup(lut, idx)
    diff = o.add(o.mul(d[:, None], lighting.diffuse[0]), lighting.ambient)
    col = o.add(o.mul(base, diff), o.mul(t[:, None], lighting.specular[0]))
    return o.minimum(col, 1.0)


def _npc_inside(o: OpCounter, v: np.ndarray) -> np.ndarray:
    """(N, 6) inside flags of 0 <= x, y, z <= w: the paper's 6 compares per vertex."""
    w = v[:, 3]
    cols = []
    for axis in range(3):
        cols.append(o.ge(v[:, axis], 0.0))
        cols.append(o.le(v[:, axis], w))
    return np.stack(cols, axis=1)


def run_geometry_paper(scene: Scene, width: int, height: int, *, z_bits: int = 24) -> ScreenTriangles:
    """The paper's recipe on ``scene``: screen triangles with far = 0 (``z_far_is_zero``) and
    per-stage counts in ``.ops`` (table 1's seven stages plus ``clip_cut`` and ``to_integer``)."""
    width, height, z_bits = check_geometry_args("run_geometry_paper", scene, width, height, z_bits)
    if scene.uv is not None:
        raise RasterhwError("the paper's recipe carries no texture coordinates")
    setup = frame_setup(scene, width, height)
    if setup.lighting.to_light.shape[0] != 1:
        raise RasterhwError(f"the paper's recipe has one directional light; scene {scene.name!r} has "
                            f"{setup.lighting.to_light.shape[0]}")
    n_p, k = scene.n_polygons, scene.max_corners
    used = np.arange(k)[None, :] < scene.nverts[:, None]
    m = npc_matrix(setup.mvp)
    o = OpCounter()
    for s in TABLE1_STAGES:  # table 1 order in .ops even when a stage does no work
        with o.stage(s):
            pass

    with o.stage("vertex_transform"):
        v = vertex_transform(scene.positions[used], m, ops=o)
    with o.stage("normal_transform"):
        n_eye = normal_transform(scene.normals[used], setup.normal_matrix, ops=o)
    with o.stage("normalise"):
        n_unit = normalise(n_eye, ops=o)
    with o.stage("light"):
        lit = light_paper(n_unit, scene.colours[used], setup.lighting, scene.material.shininess, ops=o)

    corners = np.zeros((n_p, k, 7))
    corners[used, :4] = v
    corners[used, 4:7] = lit
    last = corners[np.arange(n_p), scene.nverts - 1]
    corners[~used] = np.broadcast_to(last[:, None, :], corners.shape)[~used]

    with o.stage("clip"):
        ins = np.ones((n_p, k, 6), dtype=bool)
        ins[used] = _npc_inside(o, corners[used])
    # integer work on the compare bits: accept when every corner is inside every plane,
    # reject when every corner is outside one plane
    ins = ins | ~used[:, :, None]
    accept = ins.all(axis=(1, 2))
    out_all = np.zeros((n_p, 6), dtype=bool)
    for p in range(6):
        out_all[:, p] = ~(ins[:, :, p] | ~used).any(axis=1)
    reject = out_all.any(axis=1)
    cut = np.flatnonzero(~accept & ~reject)
    out = np.zeros((n_p, k + 6, 7))
    out[:, :k] = corners
    n_out = np.where(accept, scene.nverts, 0).astype(np.int64)
    if cut.size:
        with o.stage("clip_cut"):
            sub = corners[cut].copy()
            w = sub[:, :, 3]
            for axis in (0, 1):  # back to -w <= x, y <= w for pipeline.clip: x = 2x' - w
                sub[:, :, axis] = o.sub(o.mul(sub[:, :, axis], 2.0), w)
            cc, nc, _ = clip(sub, scene.nverts[cut], setup.near, ops=o)
            for axis in (0, 1):
                cc[:, :, axis] = o.mul(o.add(cc[:, :, axis], cc[:, :, 3]), 0.5)
        out[cut] = cc
        n_out[cut] = nc
    drawn = np.flatnonzero(n_out > 0)
    n_draw = n_out[drawn]
    flat = out[drawn][np.arange(out.shape[1])[None, :] < n_draw[:, None]]

    with o.stage("perspective_divide"):
        npc = perspective_divide(flat[:, :4], ops=o)
    with o.stage("screen_map"):
        sx = o.mul(npc[:, 0], float(width))
        sy = o.add(o.mul(npc[:, 1], -float(height)), float(height))
        zf = o.add(o.mul(npc[:, 2], -float(1 << z_bits)), float(1 << z_bits))
    with o.stage("to_integer"):
        zq = o.minimum(o.rint_int(zf), (1 << z_bits) - 1)
        colour = o.maximum(flat[:, 4:7], 0.0)

    tri, tri_poly = fan_triangulate(n_draw)
    ops = o.as_dict()
    ops["polygons"] = n_p
    ops["vertices"] = int(scene.nverts.sum())
    ops["triangles"] = int(tri.shape[0])
    xy = np.stack([sx, sy], axis=-1)
    stats = {"polygons_in": n_p, "polygons_culled": 0, "polygons_clipped_away": int(n_p - drawn.size),
             "polygons_drawn": int(drawn.size), "polygons_cut": int(np.count_nonzero(n_out[cut] > 0)),
             "triangles": int(tri.shape[0])}
    return ScreenTriangles(width=width, height=height, xy=xy[tri], z=np.clip(npc[:, 2], 0.0, 1.0)[tri],
                           zq=np.asarray(zq, dtype=np.int64)[tri], colour=colour[tri],
                           poly_id=drawn[tri_poly].astype(np.int64), z_bits=z_bits, z_far_is_zero=True,
                           stats=stats, ops=ops)


def ops_per_triangle(scene: Scene | None = None, *, width: int = 1280, height: int = 1024) -> dict:
    """The recipe's per-stage counts for one front-facing, unclipped triangle (the paper's case).

    Returns stage -> {category: n, "total": n} for table 1's stages, ``to_integer`` (outside
    the table) and a ``"total"`` row over table 1's stages.
    """
    from rasterhw.golden_model.opcount import CATEGORIES
    from rasterhw.golden_model.triangle_ops import default_triangle_scene as _default_triangle_scene

    scene = _default_triangle_scene() if scene is None else scene
    if scene.n_polygons != 1 or int(scene.nverts[0]) != 3:
        raise RasterhwError("ops_per_triangle needs a scene of one triangle")
    tris = run_geometry_paper(scene, width, height)
    if tris.stats["polygons_drawn"] != 1 or tris.stats["polygons_cut"] != 0:
        raise RasterhwError(f"ops_per_triangle needs a triangle inside the view volume; stats: {tris.stats}")
    out = {s: dict(tris.ops[s]) for s in (*TABLE1_STAGES, "to_integer")}
    total = dict.fromkeys((*CATEGORIES, "total"), 0)
    for s in TABLE1_STAGES:
        for c in total:
            total[c] += out[s][c]
    out["total"] = total
    return out


def compare_with_full(scene: Scene, width: int, height: int) -> dict:
    """Render ``scene`` through the recipe and through the full pipeline (both into the SNU
    fixed-point scan converter and pixel-bus frame) and say how far apart the frames are.

    Returns ``pixels``, ``differ`` (pixels whose RGB differs), ``coverage_differ`` (pixels
    written by one and not the other), ``max_channel_diff`` and both triangle counts.
    """
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.snu.gouraud import scan_convert
    from rasterhw.golden_model.snu.pixelbus import pixelbus_frame

    a = run_geometry_paper(scene, width, height)
    b = run_geometry(scene, width, height, z_bits=24, z_far_is_zero=True)
    fa, za = pixelbus_frame(scan_convert(a))
    fb, zb = pixelbus_frame(scan_convert(b))
    ch = np.abs(np.stack([(fa >> s) & 255 for s in (16, 8, 0)]) - np.stack([(fb >> s) & 255 for s in (16, 8, 0)]))
    return {"pixels": int(fa.size), "differ": int(np.count_nonzero(fa != fb)),
            "coverage_differ": int(np.count_nonzero((za > 0) != (zb > 0))),
            "max_channel_diff": int(ch.max()) if ch.size else 0,
            "triangles_recipe": a.n_triangles, "triangles_full": b.n_triangles}
