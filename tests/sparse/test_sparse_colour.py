"""Surface parameters as linear functions: the bit-accurate colour planes (golden_model/sparse/fixed.py)
against the reference rasteriser's colour and coverage."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import random_triangles, rasterise
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.sparse.edges import edge_setup
from rasterhw.golden_model.sparse.fixed import colour_planes, colour_rgb8
from rasterhw.golden_model.sparse.search import sparse_render


@pytest.mark.parametrize(("scene", "matrix"), [("c300", "4x4"), ("sp27", "2x2"), ("sp8", "8x4")])
def test_colour_planes_within_one_level_of_the_reference(scene, matrix):
    W, H = (256, 128) if matrix == "8x4" else (256, 256)
    tris = run_geometry(build_scene(scene), W, H)
    ref = rasterise(tris)
    f = sparse_render(tris, matrix, depth="fixed")
    assert np.array_equal(f.tri_id >= 0, ref.tri_id >= 0)  # coverage: the reference's, exactly
    p, q = (int(v) for v in matrix.split("x"))
    c = colour_rgb8(tris, f.tri_id, p, q).astype(int)
    same = (f.tri_id >= 0) & (f.tri_id == ref.tri_id)
    d = np.abs(c - ref.to_rgb8().astype(int)).max(axis=-1)
    assert d[same].max() <= 1
    assert (d[same] > 0).mean() < 0.01
    assert (c[f.tri_id < 0] == 0).all()


def test_colour_is_the_same_whatever_the_matrix():
    # per-processor rewriting (C0 = C00 + a Cx + b Cy, Cu = p Cx, Cv = q Cy) is exact
    tris = random_triangles(64, 64, 60, mean_area=40.0, seed=7)
    f = sparse_render(tris, "1x1", depth="fixed")
    ref = colour_rgb8(tris, f.tri_id, 1, 1)
    for p, q in ((2, 2), (4, 4), (8, 8), (4, 2)):
        g = sparse_render(tris, (p, q), depth="fixed") if p == q else None
        tid = f.tri_id if g is None else g.tri_id
        if g is not None:
            assert np.array_equal(tid, f.tri_id)
        assert np.array_equal(colour_rgb8(tris, tid, p, q), ref)


def test_colour_planes_reproduce_vertex_colours():
    tris = random_triangles(64, 64, 20, mean_area=200.0, seed=3)
    xy, _, vcol = tris.validate(who="t")
    es = edge_setup(xy)
    pl = colour_planes(tris, es).astype(np.float64) / (1 << 16)  # (3, 3, T)
    from rasterhw.golden_model.screen import SUBPIXEL_BITS, snap

    X = snap(xy[es.tri, :, 0]) / float(1 << SUBPIXEL_BITS) - 0.5  # pixel index whose centre is the vertex
    Y = snap(xy[es.tri, :, 1]) / float(1 << SUBPIXEL_BITS) - 0.5
    for ch in range(3):
        at_v = pl[ch, 0][:, None] + pl[ch, 1][:, None] * X + pl[ch, 2][:, None] * Y
        assert np.abs(at_v - 255.0 * vcol[es.tri, :, ch]).max() < 0.05


@pytest.mark.parametrize(("tid", "pq", "match"), [
    (np.full((32, 32), 99, dtype=np.int64), (2, 2), "outside"),
    (np.full((16, 32), -1, dtype=np.int64), (2, 2), "array"),
    (np.full((32, 32), -1.0), (2, 2), "array"),
    (np.full((32, 32), -1, dtype=np.int64), (3, 2), "does not divide"),
])
def test_colour_rejects_bad_input(tid, pq, match):
    tris = random_triangles(32, 32, 4, seed=1)
    with pytest.raises(RasterhwError, match=match):
        colour_rgb8(tris, tid, *pq)
