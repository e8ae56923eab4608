"""A chain of ZB/M units in the Amaranth simulator (small frames): the pysim engine of
``rasterhw sim zbm``, stream-rule checkers on every input and output."""

from __future__ import annotations

import numpy as np
from amaranth.sim import Simulator
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.words import edge_pair_words, split_merge_words
from rasterhw.hdl.zbm.chain import ZbmChain
from rasterhw.hdl.zbm.unit import ZbmUnit
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put

__all__ = ["run_units_pysim"]


def run_units_pysim(eps_per_unit: list[G.EdgePairs], *, width: int, height: int, interleave: int,
                    capacity: int = F.AEP_CAPACITY, max_cycles: int = 2_000_000,
                    schedule: str = "overlap") -> dict:
    """The same chain in the Amaranth simulator (small frames): returns ``{"s0", "s1", "cycles",
    "proto_errors"}`` (stream-rule violations counted by checkers on every input and output)."""
    units = [ZbmUnit(interleave=interleave, width=width, height=height, capacity=capacity, head=(k == 0),
                     schedule=schedule) for k in range(len(eps_per_unit))]
    sim = Simulator(ZbmChain(units))
    sim.add_clock(1e-8, domain="sync")
    sim.add_clock(1e-8, domain="merge")
    last = units[-1]
    got = {c: [] for c in range(interleave)}
    need = {c: last.chip_pixels(c) * height for c in range(interleave)}
    out: dict = {}

    def src(u, words):
        async def bench(ctx):
            for w in words:
                await stream_put(ctx, u.i, w)
        return bench

    async def sink(ctx):
        for c in got:
            ctx.set(last.o_merge[c].ready, 1)
        sigs = [s for c in got for s in (last.o_merge[c].valid, last.o_merge[c].payload)]
        n = 0
        while any(len(got[c]) < need[c] for c in got):
            _, _, *vals = await ctx.tick("merge").sample(*sigs)
            n += 1
            if n > max_cycles:
                raise RasterhwError(f"ZB/M pysim: no complete frame after {max_cycles} cycles")
            for i, c in enumerate(got):
                if vals[2 * i] and len(got[c]) < need[c]:
                    got[c].append(vals[2 * i + 1].as_value().value)
        out["cycles"] = int(ctx.get(units[0].cycles))

    violations: list[str] = []   # stream-rule violations on every unit input and merge output
    for u, e in zip(units, eps_per_unit, strict=True):
        sim.add_testbench(src(u, edge_pair_words(e)), background=True)
        sim.add_testbench(stream_protocol_checker(u.i, "i", errors=violations), background=True)
    for c in range(interleave):
        sim.add_testbench(stream_protocol_checker(last.o_merge[c], f"o_merge[{c}]", errors=violations,
                                                  domain="merge"), background=True)
    sim.add_testbench(sink)
    sim.run()
    s0 = np.zeros((height, width), np.uint64)
    s1 = np.zeros((height, width), np.uint64)
    for c in got:
        s0[:, c::interleave], s1[:, c::interleave] = split_merge_words(np.array(got[c], dtype=object).reshape(height, -1))
    return {"s0": s0, "s1": s1, "cycles": out["cycles"], "proto_errors": len(violations)}
