# amaranth: UnusedElaboratable=no
"""The pysim stream harness (sim/engines/harness.py) catches broken sources and moves data in order."""

from __future__ import annotations

import pytest
from amaranth import Module, Signal, unsigned
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In
from amaranth.sim import Simulator
from rasterhw.sim.engines.harness import (
    stream_get,
    stream_protocol_checker,
    stream_put,
    stream_sink,
)


class _Port(wiring.Component):
    """A bare stream port to drive from testbenches."""

    def __init__(self):
        super().__init__({"i": In(stream.Signature(unsigned(8)))})

    def elaborate(self, platform):
        m = Module()
        tick = Signal()
        m.d.sync += tick.eq(~tick)    # gives the design its sync domain
        return m


def _run(*benches, background=()):
    dut = _Port()
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    for b in background:
        sim.add_testbench(b(dut), background=True)
    for b in benches:
        sim.add_testbench(b(dut))
    sim.run()


def test_checker_fails_when_valid_drops_before_the_transfer():
    def bad_source(dut):
        async def run(ctx):
            ctx.set(dut.i.payload, 7)
            ctx.set(dut.i.valid, 1)
            await ctx.tick()          # ready is low: no transfer
            ctx.set(dut.i.valid, 0)   # broken: withdrawn
            await ctx.tick().repeat(3)
        return run

    with pytest.raises(AssertionError, match="valid dropped"):
        _run(bad_source, background=[lambda d: stream_protocol_checker(d.i, "i")])


def test_checker_fails_when_the_payload_changes_before_the_transfer():
    def bad_source(dut):
        async def run(ctx):
            ctx.set(dut.i.valid, 1)
            ctx.set(dut.i.payload, 7)
            await ctx.tick()
            ctx.set(dut.i.payload, 8)  # broken: changed while waiting
            await ctx.tick().repeat(3)
        return run

    with pytest.raises(AssertionError, match="payload changed"):
        _run(bad_source, background=[lambda d: stream_protocol_checker(d.i, "i")])


def test_put_get_and_sink_move_every_word_in_order():
    words = list(range(20))
    got, got2, log = [], [], []

    def source(dut):
        async def run(ctx):
            for k, w in enumerate(words):
                await stream_put(ctx, dut.i, w, gap=k % 3)
        return run

    def getter(dut):
        async def run(ctx):
            for k in range(len(words)):
                got.append(await stream_get(ctx, dut.i, gap=k % 2))
        return run

    _run(getter, background=[source, lambda d: stream_protocol_checker(d.i, "i", log)])
    assert got == words and log == words

    def timer(dut):
        async def run(ctx):
            await ctx.tick().repeat(200)
        return run

    _run(timer, background=[source, lambda d: stream_sink(d.i, got2, ready=[0, 1, 0, 0, 1] * 20)])
    assert got2 == words
