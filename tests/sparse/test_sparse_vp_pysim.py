"""The HDL video processor in Amaranth pysim (its testbench ``ProcessorBench`` on the generic pysim
engine), bit-exact against the bit-accurate golden model."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave, sparse_render
from rasterhw.sim.sparse.scene import run_processor


def run_matrix(tris, matrix, *, processors=None) -> dict:
    """Every processor (or the listed ``(a, b)``) of the matrix on ``tris``, each on the generic pysim
    engine; the interleaved frame when all ran, the local memories and per-processor results."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    procs = [(a, b) for b in range(q) for a in range(p)] if processors is None else list(processors)
    N = 1 << n
    loc_t = np.full((q, p, N, N), -1, dtype=np.int64)
    loc_z = loc_t.copy()
    per = {}
    for a, b in procs:
        r = run_processor(tris, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, engine="pysim")
        loc_t[b, a], loc_z[b, a] = r["tri"], r["zq"]
        per[(a, b)] = r
    out = {"per_processor": per, "local_tri": loc_t, "local_zq": loc_z}
    if processors is None:
        out["tri"], out["zq"] = interleave(loc_t), interleave(loc_z)
    return out


def _golden(tris, matrix):
    g = sparse_render(tris, matrix, depth="fixed")
    zq = g.depth_words(tris.z_bits)
    return g, zq


@pytest.mark.parametrize("matrix,size,count", [("2x2", (16, 16), 12), ("4x2", (32, 16), 10)])
def test_matrix_bit_exact_and_busy_cycles(matrix, size, count):
    tris = random_triangles(*size, count, mean_area=14.0, seed=21)
    g, zq = _golden(tris, matrix)
    h = run_matrix(tris, matrix)
    assert np.count_nonzero(g.tri_id >= 0) > 50  # a real picture, with overlaps
    assert g.pixels_written > np.count_nonzero(g.tri_id >= 0)
    assert np.array_equal(h["tri"], g.tri_id)
    assert np.array_equal(h["zq"], zq)
    P = g.p * g.q
    for (a, b), r in h["per_processor"].items():
        proc = b * g.p + a
        # busy cycles per stage = coverage tests = 4 * windows entering the level
        assert r["tests"] == [int(v) for v in g.tests_per_proc[proc, 1:]]
    assert sum(r["writes"] for r in h["per_processor"].values()) == g.pixels_written
    assert len(h["per_processor"]) == P


def test_one_processor_sees_only_its_pixels():
    tris = random_triangles(16, 16, 8, mean_area=20.0, seed=3)
    g, zq = _golden(tris, "2x2")
    h = run_matrix(tris, "2x2", processors=[(1, 0)])
    assert np.array_equal(h["local_tri"][0, 1], g.local_tri[0, 1])
    assert (h["local_tri"][1] == -1).all() and (h["local_tri"][0, 0] == -1).all()


def test_bad_parameters():
    from rasterhw.hdl.sparse.vp import VideoProcessor

    for kw in ({"n": 0}, {"n": 3, "p": 3}, {"n": 3, "q": 128}, {"n": 3, "alpha": 16}, {"n": 3, "test": "bbox"},
               {"n": 3, "z_bits": 0}):
        with pytest.raises(ValueError):
            VideoProcessor(**kw)
