"""cocotb bench: one EXPERTS PXP (the generated ``experts-pxp`` Verilog as the top level).

Driven by ``rasterhw.sim.experts.pxp_cocotb.run_cocotb_bench``, which writes the jobs (one per
PXP line: the range's segments, then an end-of-line token carrying the next line's range) and
the golden pixels and line cycles to PXP_EXPECT (.npz). Python plays the segment stream with
random idle clocks (PXP_IDLE, probability per word) and holds ``o.ready`` low at random
(PXP_STALL, probability per clock), seeded by PXP_SEED; stream checkers watch both ports every
clock (valid held until taken, payload stable) and feed in-order scoreboards. Pixels must equal
the golden PXP's; with no stall on the output the finish-time counter of every line must equal
the golden cycle model's (idle input clocks lengthen a line by exactly the clocks the PXP waited,
so line cycles are compared only when PXP_IDLE is 0 as well).
"""

from __future__ import annotations

import os
import random

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge, with_timeout

from cocotb_tests.common import send, start_checker, to_int

SEG_BITS = 194


@cocotb.test()
async def pxp_lines(dut):
    exp = np.load(os.environ["PXP_EXPECT"])
    words = [int(w, 16) for w in exp["words"]]
    want_pix = [int(p) for p in exp["pixels"]]
    want_cyc = [int(c) for c in exp["cycles"]]
    idle = float(os.environ.get("PXP_IDLE", "0"))
    stall = float(os.environ.get("PXP_STALL", "0"))
    rng = random.Random(int(os.environ.get("PXP_SEED", "1")))
    mask = (1 << SEG_BITS) - 1

    dut.rst.value = 1
    dut.i__valid.value = 0
    dut.o__ready.value = 1
    dut.lo.value = int(exp["lo0"])
    dut.hi.value = int(exp["hi0"])
    Clock(dut.clk, 10, unit="ns").start()
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    await RisingEdge(dut.clk)

    got_in: list[int] = []
    got_out: list[int] = []
    start_checker(dut.clk, dut.i__valid, dut.i__ready, dut.i__payload, name="i", log=got_in, reset=dut.rst)
    start_checker(dut.clk, dut.o__valid, dut.o__ready, dut.o__payload, name="o", log=got_out, reset=dut.rst)

    async def feed():
        for w in words:
            while rng.random() < idle:
                await RisingEdge(dut.clk)
            await send(dut.clk, dut.i__valid, dut.i__ready, dut.i__payload, w & mask)
            if w & 1:  # end-of-line token: the next line's range, sampled as the line ends
                dut.lo.value = (w >> SEG_BITS) & 0x3FF
                dut.hi.value = (w >> (SEG_BITS + 10)) & 0x7FF

    async def sink():
        while True:
            await RisingEdge(dut.clk)
            dut.o__ready.value = 0 if rng.random() < stall else 1

    line_cycles: list[int] = []

    async def lines():
        seen = 0
        while len(line_cycles) < len(want_cyc) or len(got_out) < len(want_pix):
            await FallingEdge(dut.clk)
            n = to_int(dut.lines)
            if n != seen:
                line_cycles.append(to_int(dut.line_cycles))
                seen = n

    cocotb.start_soon(feed())
    cocotb.start_soon(sink())
    budget = 20 * (sum(want_cyc) + len(words)) + 1000
    await with_timeout(cocotb.start_soon(lines()), budget * 10, "ns")

    # in-order scoreboards: every word taken once, in order; every pixel as the golden PXP
    assert got_in == [w & mask for w in words], "the PXP did not take the segment words in order"
    assert len(got_out) == len(want_pix), f"{len(got_out)} pixels out, golden {len(want_pix)}"
    bad = [k for k, (a, b) in enumerate(zip(got_out, want_pix, strict=True)) if a != b]
    assert not bad, f"{len(bad)} pixels differ; first {bad[0]}: {got_out[bad[0]]:#06x} != golden {want_pix[bad[0]]:#06x}"
    if idle == 0 and stall == 0:
        assert line_cycles == want_cyc, f"line cycles {line_cycles[:8]}... != golden {want_cyc[:8]}..."
    else:  # a line can only be slower than the model says, never faster
        assert all(g >= w for g, w in zip(line_cycles, want_cyc, strict=True)), "a line finished faster than the model"
    dut._log.info("%d words, %d pixels, %d lines: 0 mismatches (idle %.2f, stall %.2f)",
                  len(words), len(got_out), len(line_cycles), idle, stall)

