"""The HDL stack processor (hdl/sparse/stack_vp.py) in pysim, bit and cycle for cycle the golden
stack processor (golden_model/sparse/stack.py): local memory, the cycle each record is taken, busy
cycles (= the stack cycle model's 3 + tests per record), tests per level, the stack's depth."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.cycles import service_times
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.stack import stack_processor
from sparse_stack_run import compare_stack, run_stack_pysim


@pytest.mark.parametrize(("matrix", "size", "count", "area", "procs"), [
    ("2x2", (16, 16), 10, 14.0, [(0, 0), (1, 1)]),
    ("4x2", (32, 16), 8, 60.0, [(3, 1)]),
    ("1x1", (32, 32), 4, 150.0, [(0, 0)]),   # n = 5: a deep stack
])
def test_stack_hdl_bit_and_cycle_exact(matrix, size, count, area, procs):
    tris = random_triangles(*size, count, mean_area=area, seed=21)
    f = sparse_render(tris, matrix, depth="fixed", per_record=True)
    s = service_times(f.stats["windows_per_record"], vp="stack")
    for a, b in procs:
        h = run_stack_pysim(tris, matrix, a, b)
        g = stack_processor(tris, matrix, a, b)
        assert compare_stack(h, g) == {"mismatches": 0, "cycle_mismatches": 0}
        assert np.count_nonzero(h["tri"] >= 0) > 5 and h["writes"] > 5    # a real picture
        k = b * f.p + a
        assert h["busy"] == int(s[k].sum())                                # the stack cycle model
        assert np.array_equal(np.diff(h["accept"]), s[k][:-1])             # record t+1 taken 3 + tests later
        assert h["records"] == len(g["cycles"])
        assert h["cycles"] >= h["busy"] and h["cycles"] <= h["busy"] + 4   # pixel pipeline drain only
        assert 1 < h["max_stack"] <= 3 * (f.n - 1)


@pytest.mark.parametrize(("matrix", "size", "procs"), [("2x2", (16, 16), [(1, 0)]), ("1x1", (16, 16), [(0, 0)])])
def test_stack_hdl_colour_and_formula_5_cycles(matrix, size, procs):
    """Depth and R, G, B as linear functions; (5)'s k_p = 4 parameters on k_e = 3 edge adders."""
    from rasterhw.golden_model.sparse.fixed import colour_rgb8

    tris = random_triangles(*size, 6, mean_area=40.0, seed=5)
    f = sparse_render(tris, matrix, depth="fixed", per_record=True)
    s4 = service_times(f.stats["windows_per_record"], vp="stack", kp=4)
    full = colour_rgb8(tris, f.tri_id, f.p, f.q).astype(np.int64)
    for a, b in procs:
        h = run_stack_pysim(tris, matrix, a, b, colour=True, kp=4)
        g = stack_processor(tris, matrix, a, b, colour=True, kp=4)
        assert compare_stack(h, g) == {"mismatches": 0, "cycle_mismatches": 0}
        assert np.array_equal(h["rgb"], full[b::f.q, a::f.p])      # colour: bit for bit
        assert (h["rgb"][h["tri"] >= 0] > 0).any()
        k = b * f.p + a
        assert h["busy"] == int(s4[k].sum())                       # 3 + tests + ceil(w_i k_p / k_e)
        assert np.array_equal(np.diff(h["accept"]), s4[k][:-1])
        assert h["busy"] > stack_processor(tris, matrix, a, b)["busy"]


def test_stack_hdl_rejects_bad_parameters():
    from rasterhw.hdl.sparse.stack_vp import StackProcessor

    for kw in ({"n": 0}, {"n": 3, "p": 3}, {"n": 3, "q": 128}, {"n": 3, "alpha": 16}, {"n": 3, "z_bits": 0},
               {"n": 3, "kp": -1}, {"n": 3, "ke": 0}, {"n": 3, "colour": 1}, {"n": 3, "kp": True}):
        with pytest.raises(ValueError):
            StackProcessor(**kw)


@pytest.mark.parametrize("limit", [1, 8])
def test_coupled_matrix_of_stack_processors_cycle_exact(limit):
    """hdl/sparse/matrix.py with vp="stack": every cell a stack processor behind its input FIFO,
    cycle for cycle cycles.coupled_matrix on the stack processors' service times (frame, broadcast
    stalls, FIFO peaks, busy cycles), the frame's end moved only by the last pixels' drain."""
    from rasterhw.golden_model.sparse.cycles import coupled_matrix
    from rasterhw.sim.sparse.scene import run_matrix

    tris = random_triangles(16, 16, 12, mean_area=16.0, seed=12 + limit)
    f = sparse_render(tris, "2x2", depth="fixed", per_record=True)
    gz = f.depth_words(tris.z_bits)
    h = run_matrix(tris, n=f.n, p=2, q=2, limit=limit, z_bits=tris.z_bits, in_depth=8, vp="stack", engine="pysim")
    assert np.array_equal(h["tri"], f.tri_id) and np.array_equal(h["zq"], gz)
    s = service_times(f.stats["windows_per_record"], vp="stack")
    g = coupled_matrix(s, limit)
    tail = np.stack([stack_processor(tris, "2x2", k % 2, k // 2)["tail"] for k in range(4)])
    assert h["cycles"] == int((g.pop + s + tail).max())
    assert h["cycles"] - g.frame_cycles in (0, 1, 2)
    assert h["stall_cycles"] == g.stall_cycles and (limit > 1 or g.stall_cycles > 0)
    assert h["stats"]["fifo_peak"].tolist() == g.fifo_peak.tolist()
    assert h["stats"]["busy_cycles"].tolist() == g.busy.tolist()
    assert h["stats"]["records"].tolist() == [f.triangles] * 4
    tests = np.stack([h["stats"][f"tests_{i}"] for i in range(1, f.n + 1)], axis=1)
    assert np.array_equal(tests, f.tests_per_proc[:, 1:])


def test_sim_sparse_vp_stack_pysim_and_bad_options():
    """``rasterhw sim sparse --vp stack``: the coupled matrix of stack processors against its golden
    coupled model (cycle_mismatches 0); --vp belongs to the coupled matrix."""
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.sparse.scene import simulate, simulate_coupled

    tris = random_triangles(16, 16, 10, mean_area=16.0, seed=9)
    r = simulate_coupled(tris, "2x2", engine="pysim", fifo_depth=1, vp="stack")
    assert r["vp"] == "stack" and r["mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["cycles_compared"] > 10 and r["stall_cycles"] > 0 and r["fifo_peak_max"] == 1
    with pytest.raises(RasterhwError, match="--vp must be"):
        simulate_coupled(tris, "2x2", engine="pysim", vp="tree")
    with pytest.raises(RasterhwError, match="no inner FIFOs"):
        simulate_coupled(tris, "2x2", engine="pysim", vp="stack", vp_fifo_depth=8)
    with pytest.raises(RasterhwError, match="drop --no-coupled"):
        simulate("c50", 32, 32, engine="pysim", matrix="2x2", coupled=False, vp="stack")
