"""The whole matrix (``hdl/sparse/matrix.py``: broadcast, every processor's input FIFO, the slowest
holding the broadcast back, interleaved read-out) in Amaranth pysim against the golden model: the
image bit for bit, and frame cycles, broadcast stalls, FIFO peaks, per-processor busy cycles and
per-level tests against the coupled matrix's cycle model (``golden_model/sparse/vpcycles.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.vpcycles import coupled_matrix_vp


def run_matrix_pysim(tris, *, p, q, limit):
    """The matrix's testbench (``MatrixFrameBench``) on the generic pysim engine, input FIFOs built 8 deep."""
    from rasterhw.golden_model.sparse.formats import sparse_geometry
    from rasterhw.sim.sparse.scene import run_matrix

    n = sparse_geometry(tris.width, tris.height, p, q)
    return run_matrix(tris, n=n, p=p, q=q, limit=limit, z_bits=tris.z_bits, in_depth=8, engine="pysim")


@pytest.mark.parametrize(("size", "matrix", "limit", "ntri", "area"), [
    ((16, 16), (2, 2), 1, 12, 16.0),    # shallowest input FIFO: the broadcast waits
    ((16, 16), (2, 2), 8, 12, 16.0),
    ((32, 16), (4, 2), 2, 16, 20.0),    # a non-square matrix
])
def test_matrix_cycle_exact_against_coupled_model(size, matrix, limit, ntri, area):
    p, q = matrix
    tris = random_triangles(*size, ntri, mean_area=area, seed=ntri + limit)
    f = sparse_render(tris, matrix, depth="fixed", trace=True)
    gz = f.depth_words(tris.z_bits)
    h = run_matrix_pysim(tris, p=p, q=q, limit=limit)
    assert np.array_equal(h["tri"], f.tri_id)
    assert np.array_equal(h["zq"], gz)
    g = coupled_matrix_vp(f, limit)
    assert h["cycles"] == g["frame_cycles"]
    assert h["stall_cycles"] == g["stall_cycles"]
    assert h["stats"]["fifo_peak"].tolist() == g["fifo_peak"]
    assert max(g["fifo_peak"]) <= limit
    assert h["stats"]["busy_cycles"].tolist() == g["busy"]
    assert h["stats"]["records"].tolist() == [ntri] * (p * q)
    n = len(g["tests"][0])
    tests = np.stack([h["stats"][f"tests_{i}"] for i in range(1, n + 1)], axis=1)
    assert np.array_equal(tests, np.array(g["tests"]))
    assert np.array_equal(tests, f.tests_per_proc[:, 1:])


def test_depth_one_stalls_the_broadcast():
    tris = random_triangles(16, 16, 12, mean_area=16.0, seed=3)
    h1 = run_matrix_pysim(tris, p=2, q=2, limit=1)
    assert h1["stall_cycles"] > 0
    assert h1["stats"]["fifo_peak"].max() == 1


def test_verilog_holds_one_processor_module_for_256_processors():
    """16 x 16 = 256 processors: the matrix's Verilog instantiates one cell module by name 256 times
    and defines no processor itself (the cell's Verilog is generated once, whatever p*q)."""
    import re

    from amaranth.back import verilog
    from rasterhw.hdl.sparse.matrix import CELL_MODULE, Matrix

    text = verilog.convert(Matrix(n=2, p=16, q=16, cells="instance"), name="sparse_matrix")
    modules = re.findall(r"^module\s+(\w+)", text, flags=re.M)
    assert modules == ["sparse_matrix"]
    assert len(re.findall(rf"^\s*{CELL_MODULE}\s", text, flags=re.M)) == 256
    assert len(text) < 400_000


def test_verilator_matrix_cycle_exact_and_depth_is_run_time():
    """The whole matrix on Verilator at 2x2 (one build, two run-time FIFO depths): image and every
    counter equal to the golden model and its coupled cycle model; depth 1 stalls the broadcast and
    its FIFOs never hold more than one record. The design is the one the colour test
    (``test_sparse_colour_hdl.py``) and the soak's CI rounds build -- the matrix with colour and
    (5)'s k_p = 4 -- so the suite compiles it once; the colour is checked too."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    tris = random_triangles(32, 32, 40, mean_area=40.0, seed=7)
    r1 = simulate_coupled(tris, "2x2", fifo_depth=1, colour=True, kp=4)
    r64 = simulate_coupled(tris, "2x2", fifo_depth=64, colour=True, kp=4)
    for r in (r1, r64):
        assert r["coupled"] and r["mismatches"] == 0 and r["pixels_compared"] == 32 * 32
        assert r["colour_mismatches"] == 0
        # frame, stalls; per processor its FIFO peak, busy cycles and tests of its 4 levels
        assert r["cycle_mismatches"] == 0 and r["cycles_compared"] == 2 + 2 * 4 + 4 * 4
        assert r["tests_match_golden"]
    assert r64["build_s"] == 0.0  # the second depth reused the first one's build
    assert r1["stall_cycles"] > 0 and r1["fifo_peak_max"] == 1
    assert r64["fifo_peak_max"] <= 64 and r1["frame_cycles"] >= r64["frame_cycles"]


def test_bad_depths_are_one_line_errors():
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.sparse.scene import simulate, simulate_coupled

    tris = random_triangles(16, 16, 4, mean_area=10.0, seed=1)
    for kw in ({"fifo_depth": 0}, {"fifo_depth": 65}, {"fifo_depth": 2.5}, {"vp_fifo_depth": 1}):
        with pytest.raises(RasterhwError):
            simulate_coupled(tris, "2x2", **kw)
    with pytest.raises(RasterhwError, match="coupled"):
        simulate("c50", 32, 32, matrix="2x2", coupled=False, fifo_depth=3)
    with pytest.raises(ValueError):
        from rasterhw.hdl.sparse.matrix import Matrix

        Matrix(n=2, cells="flat")


def test_the_default_matrix_has_eight_entry_inner_fifos_and_its_input_fifo_depth_shows(monkeypatch):
    """Unset, ``rasterhw sim sparse`` builds eight-entry FIFOs between the levels (``HDL_FIFO_DEPTH``,
    ours: the paper gives no size) and, on Verilator, a hierarchical build from 4x4 up; with two-entry
    buffers (``SHALLOW_FIFO_DEPTH``, also ours) a one-entry input FIFO costs frame cycles on c300 (the
    golden coupled model, which the HDL equals counter for counter), while eight-entry inner FIFOs
    absorb most of the difference."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.sparse.vpcycles import HDL_FIFO_DEPTH, SHALLOW_FIFO_DEPTH
    from rasterhw.sim.sparse import scene
    from rasterhw.sim.sparse.machine import MACHINE

    opts = {o.name: o.default for o in MACHINE.sims[0].options}   # what the CLI passes when nothing is given
    assert opts["vp_fifo_depth"] is None and opts["hierarchical"] is None
    seen = []
    monkeypatch.setattr(scene, "matrix_job", lambda tris, **kw: seen.append(kw) or 1 / 0)
    for m in ("2x2", "4x4"):
        with pytest.raises(ZeroDivisionError):
            scene.simulate("c50", 64, 64, engine="verilator", matrix=m, fifo_depth=64,
                         vp_fifo_depth=opts["vp_fifo_depth"], hierarchical=opts["hierarchical"])
    assert [(kw["fifo_depth"], kw["hierarchical"]) for kw in seen] == [(HDL_FIFO_DEPTH, False), (HDL_FIFO_DEPTH, True)]
    f = sparse_render(run_geometry(build_scene("c300"), 128, 128), "4x4", depth="fixed", trace=True)
    frame = {(vpd, D): coupled_matrix_vp(f, D, fifo_depth=vpd)["frame_cycles"]
             for vpd in (SHALLOW_FIFO_DEPTH, HDL_FIFO_DEPTH) for D in (1, 64)}
    assert frame[(2, 1)] == 11074 and frame[(2, 64)] == 10721        # +3.3 %
    assert frame[(8, 1)] == 9982 and frame[(8, 64)] == 9894          # +0.9 %
    assert frame[(2, 1)] / frame[(2, 64)] > frame[(8, 1)] / frame[(8, 64)]
