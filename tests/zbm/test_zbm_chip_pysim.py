"""Pysim tests of one ZB/M chip: segment words in, merged double-Z lines out (two clocks)."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import multi_line_segments, random_doublez
from rasterhw.golden_model.zbm.words import pixel2_words, segment_words
from rasterhw.hdl.zbm.chip import ZbmChip
from rasterhw.sim.engines.harness import random_gap, stream_protocol_checker, stream_put

pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


def run_chip(dut, words, merge_in, *, period_merge=1e-8, idle_p=0.0, stall_p=0.0, seed=0):
    """Drive segment words (sync) and merge-input words (merge); collect merge output words."""
    sim = Simulator(dut)
    sim.add_clock(1e-8, domain="sync")
    sim.add_clock(period_merge, domain="merge")
    rng = np.random.default_rng(seed)
    got = []
    n_out = len(merge_in)

    async def seg_src(ctx):
        for w in words:
            await stream_put(ctx, dut.i_seg, w, gap=random_gap(rng, idle_p))

    async def merge_src(ctx):
        for w in merge_in:
            await stream_put(ctx, dut.i_merge, w, domain="merge")

    async def sink(ctx):
        r = np.random.default_rng(seed + 1)
        held = None
        for _ in range(200_000):     # a hang fails instead of running forever
            if len(got) >= n_out:
                break
            ready = r.random() >= stall_p
            ctx.set(dut.o_merge.ready, ready)
            _, _, valid, payload = await ctx.tick("merge").sample(dut.o_merge.valid, dut.o_merge.payload)
            if held is not None:     # stream rule: valid held, payload stable until accepted
                assert valid and payload == held
            held = payload if (valid and not ready) else None
            if valid and ready:
                got.append(payload.as_value().value)

    sim.add_testbench(seg_src, background=True)
    sim.add_testbench(merge_src, background=True)
    sim.add_testbench(stream_protocol_checker(dut.i_seg, "i_seg"), background=True)
    sim.add_testbench(stream_protocol_checker(dut.o_merge, "o_merge", domain="merge"), background=True)
    sim.add_testbench(sink)
    sim.run()
    assert len(got) == n_out, f"timeout: {len(got)} of {n_out} words"
    return got


@pytest.mark.parametrize("interleave,chip,mode,period_merge", [
    (1, 0, F.MODE_COLOUR, 1e-8), (2, 1, F.MODE_MAPPING, 2.3e-8), (8, 3, F.MODE_COLOUR, 0.7e-8),
    (16, 15, F.MODE_MAPPING, 1.7e-8)])
def test_chip_matches_golden(interleave, chip, mode, period_merge):
    width = 64
    rng = np.random.default_rng(interleave + chip)
    counts = [6, 0, 9] if interleave < 8 else [20, 0, 25]
    segs = multi_line_segments(rng, counts, width, mode)
    dut = ZbmChip(interleave=interleave, chip=chip, width=width)
    npx = dut.chip_pixels
    words = [w for y in range(len(counts)) for w in segment_words(segs, y)]
    ups = [random_doublez(rng, npx) for _ in counts]
    merge_in = [w for u in ups for w in pixel2_words(u)]
    got = run_chip(dut, words, merge_in, period_merge=period_merge, idle_p=0.2, stall_p=0.3, seed=chip)
    exp = []
    for y, u in enumerate(ups):
        own, _ = G.chip_scanline(segs, y, chip, interleave, width)
        exp += pixel2_words(G.merge(u, own))
    assert got == exp


def test_chip_bad_parameters():
    with pytest.raises(ValueError, match="interleave must be 1, 2, 4, 8 or 16, not 32"):
        ZbmChip(interleave=32)
    with pytest.raises(ValueError, match="chip must be in 0..3, not 4"):
        ZbmChip(interleave=4, chip=4)
    with pytest.raises(ValueError, match="width"):
        ZbmChip(width=0)
