"""cocotb bench: one sparse-raster video processor (the generated ``sparse-vp`` Verilog as the top).

Driven by ``rasterhw.sim.sparse.vp_cocotb.run_cocotb_bench``, which writes the broadcast records
(hex words) and the golden local memory of processor (a, b) with its coverage tests per level to
VP_EXPECT (.npz). Python plays the records with random idle clocks (VP_IDLE, probability per
record, seed VP_SEED) under a stream checker on ``i`` (valid held until taken, payload stable)
feeding an in-order scoreboard; the processor's own FIFOs push back on ``i`` when the levels
fall behind. After ``busy`` drops the local memory is read through the video-controller port
(one cycle of latency) and compared with the golden model word for word, and each level's
coverage-test counter with the golden count.
"""

from __future__ import annotations

import os
import random

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge

from cocotb_tests.common import send, start_checker, to_int


@cocotb.test()
async def vp_frame(dut):
    exp = np.load(os.environ["VP_EXPECT"])
    words = [int(w, 16) for w in exp["words"]]
    n = int(exp["n"])
    idle = float(os.environ.get("VP_IDLE", "0"))
    rng = random.Random(int(os.environ.get("VP_SEED", "1")))
    Clock(dut.clk, 10, unit="ns").start()
    dut.rst.value = 1
    dut.i__valid.value = 0
    dut.a.value = int(exp["a"])
    dut.b.value = int(exp["b"])
    dut.rd_addr.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)
    taken: list[int] = []
    start_checker(dut.clk, dut.i__valid, dut.i__ready, dut.i__payload, name="i", log=taken, reset=dut.rst)
    waited = 0
    for w in words:
        while rng.random() < idle:
            await RisingEdge(dut.clk)
        waited += await send(dut.clk, dut.i__valid, dut.i__ready, dut.i__payload, w)
    budget = 400 * (len(words) + 10) * (n + 1) + 100_000
    for _ in range(budget):
        await FallingEdge(dut.clk)
        if not to_int(dut.busy):
            break
    else:
        raise AssertionError(f"still busy {budget} clocks after the last record")
    assert taken == words, "the processor did not take the records once each, in order"
    tests = [to_int(getattr(dut, f"tests_{i}")) for i in range(1, n + 1)]
    assert tests == [int(t) for t in exp["tests"]], f"coverage tests per level {tests} != golden {list(exp['tests'])}"
    assert to_int(dut.writes) >= int(np.count_nonzero(exp["tri"] >= 0)), "fewer writes than covered pixels"
    want_t, want_z = exp["tri"].ravel(), exp["zq"].ravel()
    empty = (1 << int(exp["tri_bits"])) - 1
    bad = []
    for k in range(want_t.size):
        dut.rd_addr.value = k      # registered at the next edge: the word is there one clock later
        await RisingEdge(dut.clk)
        await FallingEdge(dut.clk)
        t, z = to_int(dut.rd_tri), to_int(dut.rd_z)
        gt, gz = (int(want_t[k]), int(want_z[k])) if want_t[k] >= 0 else (empty, None)
        if t != gt or (gz is not None and z != gz):
            bad.append((k, t, z, gt, gz))
        await RisingEdge(dut.clk)
    assert not bad, f"{len(bad)} local-memory words differ; first (addr, tri, z, golden tri, golden z): {bad[0]}"
    dut._log.info("%d records (%d clocks of back-pressure), %d words read back: 0 mismatches",
                  len(words), waited, want_t.size)
