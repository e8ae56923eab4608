"""The stack-based raster processor (golden_model/sparse/stack.py): depth first, the same image and
counts as the breadth-first golden search, its cycles the stack cycle model's."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.sparse.cycles import service_times
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.stack import stack_processor


@pytest.mark.parametrize(("scene", "size", "matrix"), [("c300", 256, (2, 2)), ("sp27", 128, (4, 4))])
def test_stack_processor_equals_the_breadth_first_search(scene, size, matrix):
    tris = run_geometry(build_scene(scene), size, size)
    p, q = matrix
    f = sparse_render(tris, matrix, depth="fixed", per_record=True)
    gz = np.where(f.tri_id >= 0, np.rint(f.depth * (1 << tris.z_bits)), -1).astype(np.int64)
    s = service_times(f.stats["windows_per_record"], vp="stack")
    writes = 0
    for b in range(q):
        for a in range(p):
            k = b * p + a
            r = stack_processor(tris, matrix, a, b)
            assert np.array_equal(r["tri"], f.local_tri[b, a])
            assert np.array_equal(r["zq"], gz[b::q, a::p])
            assert np.array_equal(r["tests"], f.tests_per_proc[k, 1:])
            assert np.array_equal(r["cycles"], s[k])  # the stack cycle model prices exactly this
            assert 1 < r["max_stack"] <= 3 * (r["n"] - 1)
            writes += r["writes"]
    assert writes == f.pixels_written


def test_stack_processor_rejects_bad_input():
    tris = random_triangles(32, 32, 3, seed=4)
    with pytest.raises(RasterhwError, match="outside"):
        stack_processor(tris, "2x2", 2, 0)
    with pytest.raises(RasterhwError, match="integer"):
        stack_processor(tris, "2x2", 0.5, 0)
    with pytest.raises(RasterhwError, match="power of two"):
        stack_processor(tris, "3x2", 0, 0)
