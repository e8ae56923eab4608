# amaranth: UnusedElaboratable=no
"""StreamBroadcast (hdl/broadcast.py): every output gets every payload in order, under
independent back-pressure per output, with the stream rules checked on every port."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth import unsigned
from amaranth.sim import Simulator
from rasterhw.hdl.broadcast import StreamBroadcast
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put, stream_sink


@pytest.mark.parametrize("n,seed", [(1, 0), (3, 1), (8, 2)])
def test_broadcast_delivers_everything_in_order(n, seed):
    rng = np.random.default_rng(seed)
    words = rng.integers(0, 1 << 16, 60).tolist()
    dut = StreamBroadcast(unsigned(16), n=n)
    got = [[] for _ in range(n)]
    sent = []

    async def source(ctx):
        for w, g in zip(words, rng.integers(0, 3, len(words)), strict=True):
            await stream_put(ctx, dut.i, w, gap=int(g))

    async def bench(ctx):
        await ctx.tick().repeat(60 * 8 + 100)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(source, background=True)
    sim.add_testbench(stream_protocol_checker(dut.i, "i", sent), background=True)
    for k in range(n):
        pattern = (rng.random(2000) < 0.6).astype(int).tolist()
        sim.add_testbench(stream_sink(dut.o[k], got[k], ready=pattern), background=True)
        sim.add_testbench(stream_protocol_checker(dut.o[k], f"o[{k}]"), background=True)
    sim.add_testbench(bench)
    sim.run()
    assert sent == words
    for k in range(n):
        assert got[k] == words, f"output {k}"


def test_broadcast_rejects_bad_n():
    with pytest.raises(ValueError, match="n must be"):
        StreamBroadcast(unsigned(8), n=0)
