"""The generated Verilog of the video processor on plain Verilator (the generic engine's
``ProcessorBench``): a 4 x 4 matrix of n = 6 processors at 256 x 256 -- the design the soak's
triangle rounds build (``sim/sparse/soak.py``), so the suite compiles it once -- every processor
against the golden model."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.sim.sparse.scene import simulate_tris


def test_verilator_matrix_bit_exact():
    tris = random_triangles(256, 256, 40, mean_area=1280.0, seed=8)
    r = simulate_tris(tris, "4x4", engine="verilator")
    assert r["mismatches"] == 0 and r["pixels_compared"] == 256 * 256
    assert r["tests_match_golden"] and r["writes"] == r["pixels_written_golden"]
    assert np.all(np.array(r["tests_per_level_hdl"]) > 0)


def test_bad_engine():
    from rasterhw.golden_model.errors import RasterhwError

    tris = random_triangles(32, 32, 2, seed=8)
    with pytest.raises(RasterhwError):
        simulate_tris(tris, "4x4", engine="icarus")


def test_verilator_matrix_idle_input_same_frame_more_cycles():
    """Random idle clocks on every processor's input: the same frame and per-level tests (they do
    not depend on timing), a longer frame time; bad idle levels are one-line errors."""
    from rasterhw.golden_model.errors import RasterhwError

    tris = random_triangles(256, 256, 40, mean_area=1280.0, seed=9)
    free = simulate_tris(tris, "4x4", engine="verilator")
    slow = simulate_tris(tris, "4x4", engine="verilator", idle=200, seed=5)
    assert slow["mismatches"] == 0 and slow["tests_match_golden"] and slow["writes"] == slow["pixels_written_golden"]
    assert slow["tests_per_level_hdl"] == free["tests_per_level_hdl"]
    assert slow["sim_cycles"] > free["sim_cycles"]   # the idle clocks cost bench clocks (a compute-bound
    # processor at 256x256 may finish on the same cycle: its count starts at the first record)
    with pytest.raises(RasterhwError, match="idle"):
        simulate_tris(tris, "4x4", engine="verilator", idle=300)
    with pytest.raises(RasterhwError, match="idle"):   # pysim takes idle clocks too (the generic engine)
        simulate_tris(tris, "4x4", engine="pysim", idle=-1)
