# amaranth: UnusedElaboratable=no
"""ZB/M initial processor (hdl/zbm/initial.py) against the golden initial_processor, bit for bit,
under input gaps and output back-pressure, with the stream rules checked on both ports."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_segments
from rasterhw.golden_model.zbm.words import packets, segment_words
from rasterhw.hdl.zbm.initial import ZbmInitialProcessor
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put, stream_sink


def _run(interleave: int, chip: int, seed: int, ready) -> tuple[list, list, int]:
    segs = random_segments(np.random.default_rng(seed), 12, 64, mode=seed % 2)
    words = segment_words(segs, 0)
    expect = packets(segs, 0, chip, interleave)
    dut = ZbmInitialProcessor(interleave=interleave, chip=chip)
    got, eols = [], []
    gaps = np.random.default_rng(seed + 1).integers(0, 3, len(words))

    async def source(ctx):
        for w, g in zip(words, gaps, strict=True):
            await stream_put(ctx, dut.i, w, gap=int(g))

    async def eol_counter(ctx):
        async for _clk, _rst, e in ctx.tick().sample(dut.eol):
            if e:
                eols.append(1)

    async def bench(ctx):
        await ctx.tick().repeat(12 * len(words) + 50)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(source, background=True)
    sim.add_testbench(stream_sink(dut.o, got, ready=ready), background=True)
    sim.add_testbench(stream_protocol_checker(dut.i, "i"), background=True)
    sim.add_testbench(stream_protocol_checker(dut.o, "o"), background=True)
    sim.add_testbench(eol_counter, background=True)
    sim.add_testbench(bench)
    sim.run()
    return expect, got, len(eols)


@pytest.mark.parametrize("interleave,chip", [(1, 0), (2, 1), (8, 5), (16, 15)])
@pytest.mark.parametrize("ready", [None, "pattern"])
def test_initial_processor_matches_golden(interleave, chip, ready):
    pattern = itertools.cycle([1, 1, 0, 1, 0, 0]) if ready else None
    expect, got, eols = _run(interleave, chip, seed=interleave * 31 + chip, ready=pattern)
    assert len(expect) > 0
    mask = (1 << F.LOOP_BITS) - 1
    got_flits = [[(int(p) >> (F.LOOP_BITS * k)) & mask for k in range(F.PACKET_FLITS)] for p in got]
    assert got_flits == expect
    assert eols == 1


def test_initial_processor_rejects_bad_parameters():
    with pytest.raises(ValueError, match="interleave"):
        ZbmInitialProcessor(interleave=3)
    with pytest.raises(ValueError, match="chip"):
        ZbmInitialProcessor(interleave=4, chip=4)
