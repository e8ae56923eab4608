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
    gz = f.depth_words(tris.z_bits)
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


def test_param_cycles_add_up_to_formula_5():
    from rasterhw.golden_model.sparse.stack import param_cycles

    for kp in range(0, 7):
        for ke in (1, 2, 3, 4):
            for w in range(0, 20):
                credit, tot = 0, 0
                for _ in range(w):
                    c, credit = param_cycles(credit, kp, ke)
                    tot += c
                    assert 0 <= credit < max(ke, kp + 1)
                assert tot == -(-w * kp // ke), (kp, ke, w)


@pytest.mark.parametrize(("matrix", "a", "b"), [("2x2", 1, 0), ("4x4", 3, 2)])
def test_stack_colour_and_priced_cycles(matrix, a, b):
    from rasterhw.golden_model.sparse.fixed import colour_rgb8

    tris = run_geometry(build_scene("sp27"), 128, 128)
    p, q = (int(v) for v in matrix.split("x"))
    f = sparse_render(tris, matrix, depth="fixed", per_record=True)
    r = stack_processor(tris, matrix, a, b, kp=4, colour=True)
    k = b * p + a
    # cycles priced as formula (5): depth and RGB (k_p = 4) on the k_e = 3 edge adders
    assert np.array_equal(r["cycles"], service_times(f.stats["windows_per_record"], vp="stack", kp=4)[k])
    assert r["busy"] > stack_processor(tris, matrix, a, b)["busy"]
    # colour: bit for bit the golden colour planes at the visible pixels
    assert np.array_equal(r["tri"], f.local_tri[b, a])
    full = colour_rgb8(tris, f.tri_id, p, q).astype(np.int64)
    assert np.array_equal(r["rgb"], full[b::q, a::p])
    assert (r["rgb"][r["tri"] >= 0] > 0).any()
