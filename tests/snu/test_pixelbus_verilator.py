"""The pixel-bus Verilog on the Verilator engine (sim/engines/verilator.py: the block's testbench,
``sim/snu/testbench.py: BusBench``, its frame memory streamed out by the engines' read-out adapter, ``sim/engines/readout.py``).

Moved from the cocotb bench (``cocotb_tests/snu/pixelbus/``, removed): the frame and the cycle
count against the golden model, with idle gaps, one-bank back-pressure, the Verilog RAM model and
the full frame. The stream rules and the in-order scoreboard the cocotb test checked on the
Verilog are checked on the same stream in pysim (``run_pysim``'s protocol checker), and the
Verilator run is held equal to the pysim engine's, word for word and clock for clock.
The first run builds the bench (~30 s); later runs reuse build/.
"""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.utils import ceil_log2
from rasterhw.golden_model.snu import pixelbus as g
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.sim.engines import run
from rasterhw.sim.snu.scene import simulate_pixelbus
from rasterhw.sim.snu.testbench import frame_of
from rasterhw.sim.testbench import compare, find_testbench
from snu_pixelbus_pysim import run_pysim

pytestmark = pytest.mark.cocotb


def random_stream(seed, w=40, h=16, n=400):
    rng = np.random.default_rng(seed)
    s = PixelStream(w, h, rng.integers(0, w * h, n), rng.integers(0, 1 << 24, n),
                    rng.integers(0, 16, n), rng.integers(0, 2, n))  # small Z: ties across pipes
    gaps = rng.integers(0, 4, n) * (rng.random(n) < 0.3)
    return s, gaps


def check_in_order(s: PixelStream, gaps) -> None:
    """pysim, the same stream: stream rules on both pipelines, every write accepted once, in
    pipeline order, in the golden model's clock (what the cocotb test checked on the Verilog)."""
    logs: list = []
    r = run_pysim(s, gaps=gaps, readback=False, checker_logs=logs)
    assert np.array_equal(r["accept"], g.pixelbus_accept_cycles(s, gaps=gaps))
    aw = max(1, ceil_log2(s.width * s.height))
    for p in range(2):
        idx = np.flatnonzero(s.pipe == p)
        assert logs[p] == [(int(s.z[k]) << (24 + aw)) | (int(s.rgb[k]) << aw) | int(s.addr[k]) for k in idx]


def run_both(s: PixelStream, gaps, ram: str = "auto"):
    """The block's testbench on pysim and on Verilator (with bank RAM ``ram``); returns (expected,
    pysim run, Verilator run)."""
    tb = find_testbench("pixelbus")
    p = tb.params(width=s.width, height=s.height)
    stim = tb.stimulus_of(p, s, gaps)
    exp = tb.expect(p, stim)
    need = {"o": len(exp.words["o"])}
    return exp, run(tb, p, stim, engine="pysim", expect_words=need), run(tb, {**p, "ram": ram}, stim,
                                                                         engine="verilator", expect_words=need)


@pytest.mark.heavy
def test_verilator_random_stream_with_idle_and_protocol():
    s, gaps = random_stream(7)
    check_in_order(s, gaps)
    exp, a, b = run_both(s, gaps)
    assert (a.words, a.stamps) == (b.words, b.stamps)
    r = simulate_pixelbus(s, engine="verilator", gaps=gaps)
    acc = g.pixelbus_accept_cycles(s, gaps=gaps)
    rgb, z = g.pixelbus_frame(s, accept=acc)
    assert r["cycles"] == int(acc.max()) + 5 and r["mismatches"] == 0
    vrgb, vz = frame_of(b, 24, (s.height, s.width))
    assert np.array_equal(vrgb, rgb) and np.array_equal(vz, z)
    assert compare(exp, b)["mismatches"] == 0 and compare(exp, b)["cycle_mismatches"] == 0


def test_verilator_one_bank_stream():
    rng = np.random.default_rng(2)
    n = 400   # ~200 writes per pipeline: the stimulus memories, so the build, of random_stream's runs
    s = PixelStream(40, 16, rng.integers(0, 128, n) * 5, rng.integers(0, 1 << 24, n),
                    rng.integers(1, 1 << 24, n), rng.integers(0, 2, n))
    r = simulate_pixelbus(s, engine="verilator")
    assert r["mismatches"] == 0 and r["cycles"] == g.pixelbus_cycles(s) >= 5 * n


@pytest.mark.slow
def test_verilator_verilog_ram_matches():
    s, gaps = random_stream(8)
    exp, a, b = run_both(s, gaps, ram="verilog")
    rgb, z = g.pixelbus_frame(s, gaps=gaps)
    assert b.stamps["o"][0] - 1 == g.pixelbus_cycles(s, gaps=gaps)
    vrgb, vz = frame_of(b, 24, (s.height, s.width))
    assert np.array_equal(vrgb, rgb) and np.array_equal(vz, z)
    assert (a.words, a.stamps) == (b.words, b.stamps)   # the RAM model is the Memory, clock for clock


@pytest.mark.slow
def test_verilator_full_frame():
    s = g.pattern_stream("random", 1280, 1024, 200_000, seed=1)
    r = simulate_pixelbus(s, engine="verilator")
    assert r["mismatches"] == 0 and r["frame_rgb"].shape == (1024, 1280, 3)
