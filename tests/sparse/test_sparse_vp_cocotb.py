"""One video processor under cocotb (the generic cocotb engine on the processor's testbench,
``ProcessorBench``; Verilator, Icarus when installed): idle input clocks, the processor's own
back-pressure, stream checkers, the local memory and per-level tests read back, against the
bit-accurate golden model (``verilator_run.check_processor``). These tests checked the
processor's own cocotb bench before the generic engine replaced it; their assertions are kept."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from rasterhw.golden_model.reference import random_triangles
from rasterhw.sim.sparse.scene import check_processor

pytestmark = pytest.mark.cocotb

SIMS = ["cocotb-verilator", pytest.param("cocotb-icarus", marks=pytest.mark.skipif(
    shutil.which("iverilog") is None, reason="iverilog not on PATH"))]


@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize(("a", "b", "idle"), [(0, 0, 0), (3, 2, 128)])
@pytest.mark.heavy
def test_cocotb_vp_local_memory_and_tests_exact(sim, a, b, idle):
    tris = random_triangles(32, 32, 40, mean_area=20.0, seed=8)
    r = check_processor(tris, "4x4", a=a, b=b, engine=sim, idle=idle, seed=a + 7)
    assert r["n"] == 3 and r["words_read"] == 64 and r["records"] == 40 and r["mismatches"] == 0


def test_cocotb_vp_bench_catches_a_wrong_word():
    tris = random_triangles(32, 32, 40, mean_area=20.0, seed=8)
    from rasterhw.golden_model.sparse.search import sparse_render
    g = sparse_render(tris, (4, 4), depth="fixed")
    t = g.tri_id[0::4, 0::4].copy()
    k = int(np.flatnonzero(t.ravel() >= 0)[0])
    t.ravel()[k] = (t.ravel()[k] + 1) % 40
    assert check_processor(tris, "4x4", expect={"tri": t})["mismatches"] == 1
