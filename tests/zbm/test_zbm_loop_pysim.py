"""Pysim tests of the ZB/M segment loop (segment processor + 8 pixel processors)."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_segments
from rasterhw.golden_model.zbm.words import packets, pixel2_words
from rasterhw.hdl.zbm.loop import LOOP_GAP, ZbmLoop
from rasterhw.hdl.zbm.pixel import ZbmPixelProcessor
from rasterhw.sim.engines.harness import random_gap, stream_protocol_checker, stream_put


def run_loop(interleave, chip, width, segs_list, *, idle_p=0.0, seed=0):
    """Feed each line's packets, swap, read the line back over the merge bus.

    Returns (lines read, header entry cycles per line, len per packet).
    """
    dut = ZbmLoop(interleave=interleave, width=width)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    rng = np.random.default_rng(seed)
    out, entries = [], []

    accepted = []

    async def monitor(ctx):
        cycle = 0
        async for _, _, valid, ready in ctx.tick().sample(dut.i.valid, dut.i.ready):
            if valid and ready:
                accepted.append(cycle)
            cycle += 1

    async def bench(ctx):
        for segs in segs_list:
            n0 = len(accepted)
            for pkt in packets(segs, 0, chip, interleave):
                await stream_put(ctx, dut.i, pkt, gap=random_gap(rng, idle_p))
            entries.append(accepted[n0:])
            await ctx.tick().until(dut.idle)
            ctx.set(dut.swap, 1)
            await ctx.tick()
            ctx.set(dut.swap, 0)
            line = []
            for q in range(dut.chip_pixels):
                ctx.set(dut.mb_addr, q)
                ctx.set(dut.mb_rd, 1)
                await ctx.tick()
                ctx.set(dut.mb_rd, 0)
                line.append(ctx.get(dut.mb_data).as_value().value)
            out.append(line)

    sim.add_testbench(monitor, background=True)
    sim.add_testbench(stream_protocol_checker(dut.i, "i"), background=True)
    sim.add_testbench(bench)
    sim.run()
    return out, entries


@pytest.mark.parametrize("interleave,chip,mode", [(1, 0, F.MODE_COLOUR), (2, 1, F.MODE_MAPPING),
                                                  (4, 3, F.MODE_COLOUR), (16, 5, F.MODE_COLOUR)])
def test_loop_matches_golden(interleave, chip, mode):
    width = 64
    rng = np.random.default_rng(interleave * 10 + chip)
    lines = [random_segments(rng, 14 if interleave < 16 else 40, width, mode) for _ in range(2)]
    got, _ = run_loop(interleave, chip, width, lines, idle_p=0.2, seed=chip)
    for segs, line in zip(lines, got, strict=True):
        buf, st = G.chip_scanline(segs, 0, chip, interleave, width)
        assert st["writes"] > 0
        assert line == pixel2_words(buf)


def test_loop_swap_clears_and_double_buffers():
    """Line 2 must not see line 1's samples: the merge-side read clears the buffer."""
    width, rng = 32, np.random.default_rng(7)
    lines = [random_segments(rng, 6, width), random_segments(rng, 0, width), random_segments(rng, 5, width)]
    got, _ = run_loop(1, 0, width, lines)
    empty = pixel2_words(G.DoubleZ.empty((width,)))
    assert got[1] == empty
    assert got[2] == pixel2_words(G.chip_scanline(lines[2], 0, 0, 1, width)[0])


def test_loop_packet_spacing():
    """Back-to-back packets enter the loop len + 8 cycles apart (paper: len-per-chip + 8).

    The segment processor holds one packet while the previous one travels: packet k+1 is
    accepted the cycle after packet k's 8th flit entered the loop, and packet k enters
    ``len(k-1) + 8`` cycles after packet k-1. So acceptances are 9 apart for the first pair
    (packet 0 entered at once), then ``len(k-1) + 8``."""
    width = 64
    x = np.array([0, 10, 20, 30])
    ln = np.array([5, 1, 12, 3])
    val = np.zeros((4, 5), np.int64)
    inc = np.zeros((4, 5), np.int64)
    z1 = np.zeros(4, np.int64)
    segs = G.Segments(z1, x, ln, val, inc, z1, z1, np.array([0, 4]), z1, z1, F.MODE_COLOUR)
    _, entries = run_loop(1, 0, width, [segs])
    gaps = np.diff(entries[0])
    assert list(gaps) == [1 + F.PACKET_FLITS] + [int(n) + LOOP_GAP for n in ln[:-2]]


def test_bad_parameters():
    with pytest.raises(ValueError, match="interleave must be 1, 2, 4, 8 or 16, not 3"):
        ZbmLoop(interleave=3)
    with pytest.raises(ValueError, match="width"):
        ZbmLoop(width=513)
    with pytest.raises(ValueError, match="index"):
        ZbmPixelProcessor(index=8)
