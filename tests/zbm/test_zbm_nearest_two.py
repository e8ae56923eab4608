"""The golden model's double-Z frames without layer-by-layer insertion (``doublez.nearest_two``:
``unit.unit_frame`` for ``chain_frame``, ``render_zbm_float``) equal inserting the fragments one
by one: the layered insertion they replaced, kept here as the specification; ``composite`` worked
out only where a pixel has a sample equals the formula over the whole frame."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.screen import ScreenTriangles, snap
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.doublez import DoubleZ, arrival_layers, nearest_two
from rasterhw.golden_model.zbm.edgepair import _attributes
from rasterhw.golden_model.zbm.unit import _unit_frame_fast, segment_fragments, unit_frame


def _one_by_one(pos, z, empty):
    """Per pixel the (first, second) fragment index kept by inserting in arrival order (strict <)."""
    kept = {}
    for i, (p, v) in enumerate(zip(pos.tolist(), z.tolist(), strict=True)):
        f, s = kept.get(p, (None, None))
        zf = empty if f is None else z[f]
        zs = empty if s is None else z[s]
        if v < zf:
            kept[p] = (i, f)
        elif v < zs:
            kept[p] = (f, i)
    return kept


@pytest.mark.parametrize("kind", ["int", "float", "signed zero"])
def test_nearest_two_equals_one_by_one_insertion(kind):
    rng = np.random.default_rng(5)
    n, npx = 3000, 400
    pos = rng.integers(0, npx, n)
    if kind == "int":
        z, empty = rng.integers(0, 40, n), F.Z_EMPTY            # many ties: the earlier must win
    elif kind == "float":
        z, empty = rng.integers(0, 40, n) / 7.0 - 2.0, np.inf
    else:                                                         # -0.0 == 0.0: a tie, not an order
        z, empty = np.where(rng.random(n) < 0.5, -0.0, 0.0), np.inf
    want = _one_by_one(pos, z, empty)
    pix, first, second = nearest_two(pos, z)
    got = {p: (f, None if s < 0 else s) for p, f, s in zip(pix.tolist(), first.tolist(), second.tolist(), strict=True)}
    assert got == want
    assert [a.size for a in nearest_two(pos[:0], z[:0])] == [0, 0, 0]


def _tied(tris: ScreenTriangles, levels: int, seed: int) -> ScreenTriangles:
    """``tris`` with each triangle's depth one of ``levels`` flat values: many equal depths."""
    lv = np.random.default_rng(seed).integers(0, levels, tris.n_triangles) / levels
    z = np.repeat(lv[:, None], 3, 1)
    return ScreenTriangles(width=tris.width, height=tris.height, xy=tris.xy, z=z,
                           zq=np.rint(z * F.Z_SCALE).astype(np.int64), colour=tris.colour, poly_id=tris.poly_id)


SCENES = [("random", lambda: ref.random_triangles(64, 48, 60, mean_area=150, seed=4)),
          ("tied depths", lambda: _tied(ref.random_triangles(64, 48, 80, mean_area=200, seed=6), 3, 6))]


@pytest.mark.parametrize("name,make", SCENES, ids=[s[0] for s in SCENES])
@pytest.mark.parametrize("mode", [F.MODE_COLOUR, F.MODE_MAPPING])
def test_unit_frame_equals_layered_insertion(name, make, mode):
    tris = make()
    tris.uv = np.random.default_rng(3).random((tris.n_triangles, 3, 2)) * 3 - 1
    segs = G.segment_generator(G.edge_pairs(tris, mode=mode), tris.height, width=tris.width)
    assert segs.mode == mode
    a, b = unit_frame(segs, tris.height, tris.width), _unit_frame_fast(segs, tris.height, tris.width)[0]
    for k in ("z", "a", "c", "tag"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert (a.z[..., 1] != F.Z_EMPTY).any()                      # second samples were kept


def _float_by_insertion(tris, alpha=None, background=(0.0, 0.0, 0.0)) -> dict:
    """``render_zbm_float`` as it was written before ``nearest_two`` (fragments inserted layer by
    layer, composited over the whole frame): the specification of the rewrite."""
    W, H = tris.width, tris.height
    segs = G.segment_generator(G.edge_pairs(tris, alpha=alpha), H, width=W)
    xy = np.asarray(tris.xy, np.float64)
    X, Y = snap(xy[..., 0]) / F.SUB, snap(xy[..., 1]) / F.SUB
    att = _attributes(tris, F.MODE_COLOUR, alpha) / np.array([F.Z_SCALE, 255, 255, 255, 255])
    zb, cb, tg = np.full((H * W, 2), np.inf), np.zeros((H * W, 2, 4)), np.full((H * W, 2), -1, np.int64)
    seg, k = segment_fragments(segs)
    t = segs.tag[seg]
    xc, yc = (segs.x[seg] + k) + 0.5, segs.y[seg] + 0.5
    x0, y0 = X[t], Y[t]
    det = (x0[:, 1] - x0[:, 0]) * (y0[:, 2] - y0[:, 0]) - (x0[:, 2] - x0[:, 0]) * (y0[:, 1] - y0[:, 0])
    w1 = ((xc - x0[:, 0]) * (y0[:, 2] - y0[:, 0]) - (x0[:, 2] - x0[:, 0]) * (yc - y0[:, 0])) / det
    w2 = ((x0[:, 1] - x0[:, 0]) * (yc - y0[:, 0]) - (xc - x0[:, 0]) * (y0[:, 1] - y0[:, 0])) / det
    at = att[t]
    v = at[:, 0] + w1[:, None] * (at[:, 1] - at[:, 0]) + w2[:, None] * (at[:, 2] - at[:, 0])
    pos = segs.y[seg] * W + segs.x[seg] + k
    for ly in arrival_layers(pos):
        p, z, vv, tt = pos[ly], v[ly, 0], v[ly, 1:], t[ly]
        f = z < zb[p, 0]
        sc = (~f) & (z < zb[p, 1])
        pf, psc = p[f], p[sc]
        zb[pf, 1], cb[pf, 1], tg[pf, 1] = zb[pf, 0], cb[pf, 0], tg[pf, 0]
        zb[pf, 0], cb[pf, 0], tg[pf, 0] = z[f], vv[f], tt[f]
        zb[psc, 1], cb[psc, 1], tg[psc, 1] = z[sc], vv[sc], tt[sc]
    zb, cb, tg = zb.reshape(H, W, 2), cb.reshape(H, W, 2, 4), tg.reshape(H, W, 2)
    bg = np.asarray(background, np.float64)
    v0, v1 = np.isfinite(zb[..., 0])[..., None], np.isfinite(zb[..., 1])[..., None]
    a0, a1 = cb[..., 0, 3:4], cb[..., 1, 3:4]
    back = np.where(v1, a1 * cb[..., 1, :3] + (1 - a1) * bg, bg)
    rgb = np.where(v0, a0 * cb[..., 0, :3] + (1 - a0) * back, bg)
    return {"rgb": rgb, "z": zb, "tag": tg}


@pytest.mark.parametrize("name,make", SCENES, ids=[s[0] for s in SCENES])
@pytest.mark.parametrize("translucent", [False, True])
def test_float_twin_equals_layered_insertion(name, make, translucent):
    tris = make()
    alpha = np.random.default_rng(2).uniform(0.3, 1.0, tris.n_triangles) if translucent else None
    bg = (0.25, 0.5, 0.75)
    want, got = _float_by_insertion(tris, alpha, bg), G.render_zbm_float(tris, alpha=alpha, background=bg)
    for k in ("rgb", "z", "tag"):
        assert got[k].dtype == want[k].dtype and got[k].shape == want[k].shape
        assert np.array_equal(got[k].view(np.uint8), want[k].view(np.uint8)), k   # bit for bit
    assert np.isfinite(got["z"][..., 1]).any()


def test_composite_equals_the_formula_over_the_whole_frame():
    rng = np.random.default_rng(11)
    px = DoubleZ.empty((37, 23))
    px.z[:] = np.where(rng.random(px.z.shape) < 0.4, F.Z_EMPTY, rng.integers(0, F.Z_MAX_SAMPLE, px.z.shape))
    px.z[..., 1] = np.where(px.z[..., 0] == F.Z_EMPTY, F.Z_EMPTY, px.z[..., 1])
    px.a[:] = np.where(rng.random(px.a.shape) < 0.5, 255, rng.integers(0, 256, px.a.shape))   # opaque and not
    px.c[:] = rng.integers(0, 256, px.c.shape)
    for bg in ((0, 0, 0), (255, 17, 128)):
        bga = np.asarray(bg, np.int64)
        v0, v1 = (px.z[..., 0] != F.Z_EMPTY)[..., None], (px.z[..., 1] != F.Z_EMPTY)[..., None]
        a0, a1 = px.a[..., 0:1], px.a[..., 1:2]
        back = np.where(v1, (a1 * px.c[..., 1, :3] + (255 - a1) * bga + 127) // 255, bga)
        want = np.where(v0, (a0 * px.c[..., 0, :3] + (255 - a0) * back + 127) // 255, bga).astype(np.uint8)
        got = G.composite(px, bg)
        assert got.dtype == np.uint8 and np.array_equal(got, want)
        assert (got != bga).any() and v0.any() and (~v0).any() and (v0 & ~v1).any()
