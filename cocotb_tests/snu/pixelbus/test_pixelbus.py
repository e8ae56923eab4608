"""cocotb bench: the pixel-bus Verilog inside tb_pixelbus.v, stimulus from files.

Driven by ``rasterhw.sim.snu.pixelbus`` (which writes the stimulus and the expected result)
through ``rasterhw.sim.engines.runner``; run it with ``pytest tests/snu/test_pixelbus_cocotb.py``.
Environment: PIXELBUS_OUT (frame dump written by the wrapper), PIXELBUS_EXPECT (.npz with
the golden ``rgb``, ``z``, ``cycles``, ``n0``, ``n1``), PIXELBUS_TIMEOUT_NS,
PIXELBUS_CHECK_PROTOCOL=1 to check both pixel streams every clock (slow; small runs).
"""

from __future__ import annotations

import os

import cocotb
import numpy as np
from cocotb.triggers import RisingEdge, with_timeout
from rasterhw.sim.snu.pixelbus import read_frame_dump

from cocotb_tests.common import start_checker, to_int


@cocotb.test()
async def pixelbus_stream(dut):
    """Play the stimulus files, wait for the read-back, compare with the golden model."""
    exp = np.load(os.environ["PIXELBUS_EXPECT"])
    logs: list[list[int]] = [[], []]
    if os.environ.get("PIXELBUS_CHECK_PROTOCOL") == "1":
        for p, (v, r, c) in enumerate(((dut.v0, dut.r0, dut.pay0), (dut.v1, dut.r1, dut.pay1))):
            start_checker(dut.clk, v, r, c, name=f"i_pipe{p}", log=logs[p], reset=dut.rst)
    timeout = int(os.environ.get("PIXELBUS_TIMEOUT_NS", "100000000"))
    await with_timeout(RisingEdge(dut.finished), timeout, "ns")
    cycles = to_int(dut.cycles)
    size = int(exp["rgb"].size)
    h, w = exp["rgb"].shape
    rgb, z, dump_cycles = read_frame_dump(os.environ["PIXELBUS_OUT"], w, h)
    assert rgb.size == size
    assert dump_cycles == cycles
    if os.environ.get("PIXELBUS_CHECK_PROTOCOL") == "1":
        # in-order scoreboard: every write transferred exactly once, in pipeline order
        assert len(logs[0]) == int(exp["n0"]) and len(logs[1]) == int(exp["n1"]), (len(logs[0]), len(logs[1]))
        for p in range(2):
            want = [int(x, 16) for x in exp[f"payload{p}"]]
            diff = [k for k, (a, b) in enumerate(zip(logs[p], want, strict=True)) if a != b]
            assert not diff, f"pipe {p}: transfer {diff[0]} is {logs[p][diff[0]]:#x}, stimulus {want[diff[0]]:#x}"
    bad = int(np.count_nonzero((rgb != exp["rgb"]) | (z != exp["z"])))
    dut._log.info("cycles %d (golden %d), %d pixels, %d mismatches", cycles, int(exp["cycles"]), size, bad)
    assert cycles == int(exp["cycles"]), f"cycles {cycles} != golden {int(exp['cycles'])}"
    assert bad == 0, f"{bad} of {size} pixels differ from the golden frame"
