"""The Amaranth pysim engine: the block itself in the simulator, every clock domain clocked
together; one source per input port (:func:`rasterhw.sim.engines.harness.stream_put` after each word's
gap) and one sink per output port (back-pressure from :mod:`pattern`, every transfer stamped
with its edge)."""

from __future__ import annotations

import time

from amaranth.sim import Simulator
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.harness import as_plain, stream_protocol_checker, stream_put
from rasterhw.sim.engines.pattern import ready_pattern
from rasterhw.sim.engines.waves import declare_streams
from rasterhw.sim.testbench import Run, Stimulus, Testbench, port_of

__all__ = ["run"]


def _source(port, words, gaps, domain):
    async def bench(ctx):
        for w, g in zip(words, gaps, strict=True):
            await stream_put(ctx, port, w, gap=g, domain=domain)
    return bench


def _sink(port, need, words, stamps, ready, domain, max_cycles, name, finished, read_status):
    async def bench(ctx):
        k = 0
        while len(words) < need:
            r = next(ready)
            ctx.set(port.ready, r)
            _, _, valid, payload = await ctx.tick(domain).sample(port.valid, port.payload)
            if valid and r:
                words.append(as_plain(payload))
                stamps.append(k)
            k += 1
            if k > max_cycles:
                raise RasterhwError(f"pysim: {name} gave {len(words)} of {need} words in {max_cycles} cycles")
        ctx.set(port.ready, 0)
        finished.append(name)
        read_status(ctx)   # the last sink to finish reads the status values
    return bench


def run(tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int, expect_words: dict[str, int],
        max_cycles: int) -> Run:
    t0 = time.perf_counter()
    dut = tb.dut(params)
    sim = Simulator(dut)
    for d in tb.domains:
        sim.add_clock(1e-8, domain=d)
    errors: list[str] = []
    for name in tb.inputs_of(params):
        port = port_of(dut, name)
        sim.add_testbench(_source(port, stim.words[name], stim.gaps_of(name), tb.domain_of(name)),
                          background=True)
    words: dict[str, list[int]] = {}
    stamps: dict[str, list[int]] = {}
    outs = tb.outputs_of(params)
    status_values, status, finished = tb.status(dut, params), {}, []

    def read_status(ctx):
        if len(finished) == len(outs):
            status.update({n: int(ctx.get(v)) for n, v in status_values.items()})

    for k, name in enumerate(outs):
        port = port_of(dut, name)
        words[name], stamps[name] = [], []
        d = tb.domain_of(name)
        sim.add_testbench(stream_protocol_checker(port, name, domain=d, errors=errors), background=True)
        sim.add_testbench(_sink(port, expect_words[name], words[name], stamps[name],
                                ready_pattern(tb.sink_seed(params, k, seed), stall), d, max_cycles, name, finished,
                                read_status))
    # with --waves: the GTKWave save file shows these ports, one group each (sim/engines/waves.py)
    declare_streams(sim, {name: port_of(dut, name) for name in (*tb.inputs_of(params), *tb.outputs_of(params))})
    t1 = time.perf_counter()
    sim.run()
    if errors:
        raise RasterhwError(f"pysim: {tb.block} broke the stream rules: {errors[0]}")
    return Run("pysim", words, stamps, wall_s=time.perf_counter() - t0, run_s=time.perf_counter() - t1,
               status=status)
