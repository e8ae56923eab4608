"""The Amaranth pysim engine: the block itself in the simulator, every clock domain clocked
together (or each by its own :class:`~rasterhw.sim.testbench.Clock`: ``add_clock`` with its period
and phase, one time unit = 1 ns); one source per input port (:func:`rasterhw.sim.engines.harness.stream_put` after each word's
gap) and one sink per output port (back-pressure from :mod:`pattern`, every transfer stamped
with its edge)."""

from __future__ import annotations

import time

from amaranth.sim import Simulator
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.harness import as_plain, stream_protocol_checker, stream_put
from rasterhw.sim.engines.pattern import ready_pattern
from rasterhw.sim.engines.waves import declare_streams
from rasterhw.sim.packed import as_ints
from rasterhw.sim.testbench import Run, Stimulus, Testbench, port_of

__all__ = ["run"]


def _source(port, words, gaps, domain):
    async def bench(ctx):
        for w, g in zip(words, gaps, strict=True):
            await stream_put(ctx, port, w, gap=g, domain=domain)
    return bench


def _sinks(sinks: list, domain, max_cycles, finished, read_status):
    """One process for every sink of ``domain`` (a block with many output ports, e.g. 8 merge slots,
    costs one await per clock, not one per port). ``sinks``: ``(name, port, need, words, stamps,
    ready pattern)``; each sink draws its pattern once per clock until it has its words, then
    holds ``ready`` low."""
    async def bench(ctx):
        left = [s for s in sinks if len(s[3]) < s[2]]
        for name, port, *_ in sinks:
            if not any(s[0] == name for s in left):
                ctx.set(port.ready, 0)
        sigs = [x for s in left for x in (s[1].valid, s[1].payload)]
        held = {s[0]: None for s in left}   # the ready each port holds (set only when it changes)
        k = 0
        while left:
            rs = [next(s[5]) for s in left]
            for s, r in zip(left, rs, strict=True):
                if held[s[0]] is not r:
                    ctx.set(s[1].ready, r)
                    held[s[0]] = r
            _, _, *vals = await ctx.tick(domain).sample(*sigs)
            for j, (s, r) in enumerate(zip(left, rs, strict=True)):
                if vals[2 * j] and r:
                    s[3].append(as_plain(vals[2 * j + 1]))
                    s[4].append(k)
            k += 1
            done = [s for s in left if len(s[3]) >= s[2]]
            if done:
                for s in done:
                    ctx.set(s[1].ready, 0)
                    finished.append(s[0])
                left = [s for s in left if len(s[3]) < s[2]]
                sigs = [x for s in left for x in (s[1].valid, s[1].payload)]
            if left and k > max_cycles:
                name, _, need, words = left[0][:4]
                raise RasterhwError(f"pysim: {name} gave {len(words)} of {need} words in {max_cycles} cycles")
        read_status(ctx)   # the last sink to finish reads the status values
    return bench


#: seconds per time unit of a run's clocks
_UNIT_S = 1e-9


def run(tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int, expect_words: dict[str, int],
        max_cycles: int, clocks: dict | None = None) -> Run:
    t0 = time.perf_counter()
    dut = tb.dut(params)
    sim = Simulator(dut)
    if clocks:
        # a clock's phase is its first rising edge; every edge after time 0 (the times are relative)
        after = max(c.half for c in clocks.values())
        for d, c in clocks.items():
            sim.add_clock(2 * c.half * _UNIT_S, phase=(after + c.first) * _UNIT_S, domain=d)
    else:
        for d in tb.domains:
            sim.add_clock(1e-8, domain=d)
    errors: list[str] = []
    for name in tb.inputs_of(params):
        port = port_of(dut, name)
        sim.add_testbench(_source(port, as_ints(stim.words[name]), stim.gaps_of(name).tolist(),
                                  tb.domain_of(name)),
                          background=True)
    words: dict[str, list[int]] = {}
    stamps: dict[str, list[int]] = {}
    outs = tb.outputs_of(params)
    status_values, status, finished = tb.status(dut, params), {}, []

    def read_status(ctx):
        if len(finished) == len(outs):
            status.update({n: int(ctx.get(v)) for n, v in status_values.items()})

    by_domain: dict[str, list] = {}
    for k, name in enumerate(outs):
        port = port_of(dut, name)
        words[name], stamps[name] = [], []
        d = tb.domain_of(name)
        sim.add_testbench(stream_protocol_checker(port, name, domain=d, errors=errors), background=True)
        by_domain.setdefault(d, []).append((name, port, expect_words[name], words[name], stamps[name],
                                            ready_pattern(tb.sink_seed(params, k, seed), tb.stall_of(name, stall))))
    for d, sinks in by_domain.items():
        # the watchdog counts reference-clock edges: as many of this domain's as fit in their time
        limit = max_cycles if not clocks else -(-max_cycles * clocks["sync"].half // clocks[d].half)
        sim.add_testbench(_sinks(sinks, d, limit, finished, read_status))
    # with --waves: the GTKWave save file shows these ports, one group each (sim/engines/waves.py)
    declare_streams(sim, {name: port_of(dut, name) for name in (*tb.inputs_of(params), *tb.outputs_of(params))})
    t1, c1 = time.perf_counter(), time.process_time()
    sim.run()
    cpu_s = time.process_time() - c1   # this process's CPU in the simulation (pysim runs in it)
    if errors:
        raise RasterhwError(f"pysim: {tb.block} broke the stream rules: {errors[0]}")
    return Run("pysim", words, stamps, wall_s=time.perf_counter() - t0, run_s=time.perf_counter() - t1,
               cpu_s=cpu_s, status=status, clocks=dict(clocks or {}),
               port_domains={n: tb.domain_of(n) for n in outs} if clocks else {})
