"""EXPERTS shadows (Crow shadow polygons, our choice) against a brute-force ray cast to the light."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.experts.shadow import SHADOW_ATTEN, shadow_faces
from rasterhw.golden_model.pipeline import frame_setup, run_geometry
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.scenes import build_scene


def _brute(sc, ref, pix, W, H):
    """In shadow: the ray from the visible point towards the light hits another polygon."""
    mvp = frame_setup(sc, W, H).mvp
    inv = np.linalg.inv(mvp)
    y, x = np.divmod(pix, W)
    ndc = np.stack([(x + 0.5) / W * 2 - 1, 1 - (y + 0.5) / H * 2, ref.depth.ravel()[pix], np.ones(pix.size)], 1)
    w = ndc @ inv.T
    X = w[:, :3] / w[:, 3:4]
    L = np.asarray(sc.lights[0].direction, float)
    L /= np.linalg.norm(L)
    d = -L
    # fan triangles of every polygon
    tri, own = [], []
    for p in range(sc.n_polygons):
        k = int(sc.nverts[p])
        q = sc.positions[p]
        for i in range(1, k - 1):
            tri.append([q[0], q[i], q[i + 1]])
            own.append(p)
    T = np.array(tri)
    own = np.array(own)
    vpoly = ref.poly_id.ravel()[pix]
    out = np.zeros(pix.size, bool)
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    pv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pv)
    for k in range(pix.size):
        tv = X[k] - T[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ij,ij->i", tv, pv) / det
            qv = np.cross(tv, e1)
            v = (qv @ d) / det
            t = np.einsum("ij,ij->i", e2, qv) / det
        hit = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6) & (own != vpoly[k])
        out[k] = hit.any()
    return out


@pytest.mark.parametrize("name,n", [("experts-solids", 1500), ("sp5", 600)])
def test_shadow_polygons_agree_with_ray_casting(name, n):
    sc = build_scene(name)
    tris = run_geometry(sc, 512, 512, z_bits=16)
    ref = rasterise(tris)
    sf = shadow_faces(sc, 512, 512)
    f = render_frame(tris, model="float", shadows=sf)
    cov = np.flatnonzero(ref.tri_id.ravel() >= 0)
    pix = np.random.default_rng(1).choice(cov, n, replace=False)
    b = _brute(sc, ref, pix, 512, 512)
    m = f.shadowed.ravel()[pix]
    assert b.sum() >= 10                       # the sample has shadow in it
    assert np.count_nonzero(b != m) <= 0.005 * n
    # shadowed pixels are darker by the attenuation, the others unchanged
    g = render_frame(tris, model="float")
    s = f.shadowed.ravel()
    assert np.allclose(f.fields[s, 3], SHADOW_ATTEN * g.fields[s, 3])
    assert np.array_equal(f.fields[~s], g.fields[~s])
    assert f.costs["shadows"].sum() > 0


def test_bit_model_shadows_close_to_float():
    sc = build_scene("experts-solids")
    tris = run_geometry(sc, 512, 512, z_bits=16)
    sf = shadow_faces(sc, 512, 512)
    fl = render_frame(tris, model="float", shadows=sf)
    bt = render_frame(tris, model="bit", shadows=sf)
    assert np.count_nonzero(fl.shadowed != bt.shadowed) <= 0.01 * fl.shadowed.sum()
