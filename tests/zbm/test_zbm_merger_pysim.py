"""Pysim tests of the ZB/M merger: nearest 2 of 4 across a real clock crossing."""

from __future__ import annotations

import random

import pytest
from amaranth.lib import data
from amaranth.sim import Simulator
from rasterhw.hdl.zbm.merger import ZbmMerger
from rasterhw.sim.engines.harness import random_gap, stream_protocol_checker, stream_put

# Background sources are closed mid-`until` when the sink finishes; that is expected.
pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")

SAMPLE = data.StructLayout({"z": 8, "c": 8})
WORD = data.StructLayout({"s0": SAMPLE, "s1": SAMPLE, "last": 1})


def ref_merge(a, b):
    """a = upstream (wins ties), b = own; each a list [(z, c), (z, c)] sorted near first."""
    both = sorted([(s[0], 0, i, s[1]) for i, s in enumerate(a)] + [(s[0], 1, i, s[1]) for i, s in enumerate(b)])
    return [(z, c) for z, _, _, c in both[:2]]


def rand_word(rng):
    s = sorted([(rng.randrange(8), rng.randrange(256)) for _ in range(2)], key=lambda t: t[0])
    return s


def as_dict(w, last=0):
    return {"s0": {"z": w[0][0], "c": w[0][1]}, "s1": {"z": w[1][0], "c": w[1][1]}, "last": last}


def run(n, period_sync, period_merge, seed, stall_p=0.3):
    rng = random.Random(seed)
    own = [rand_word(rng) for _ in range(n)]
    inp = [rand_word(rng) for _ in range(n)]
    lasts = [rng.randrange(2) for _ in range(n)]
    dut = ZbmMerger(word_layout=WORD)
    sim = Simulator(dut)
    sim.add_clock(period_sync, domain="sync")
    sim.add_clock(period_merge, domain="merge")
    got = []

    async def put_own(ctx):
        r = random.Random(seed + 1)
        gap = 0                   # idle clocks after each transfer, drawn after it
        for w, la in zip(own, lasts, strict=True):
            await stream_put(ctx, dut.i_own, as_dict(w, la), gap=gap)
            gap = random_gap(r, stall_p)

    async def put_in(ctx):
        r = random.Random(seed + 2)
        gap = 0
        for w in inp:
            await stream_put(ctx, dut.i_merge, as_dict(w), gap=gap, domain="merge")
            gap = random_gap(r, stall_p)

    async def get_out(ctx):
        r = random.Random(seed + 3)
        held = None
        while len(got) < n:
            ready = r.random() >= stall_p
            ctx.set(dut.o_merge.ready, ready)
            _, _, valid, payload = await ctx.tick("merge").sample(dut.o_merge.valid, dut.o_merge.payload)
            if held is not None:  # protocol: valid held and payload stable until accepted
                assert valid and payload == held
            if valid and ready:
                got.append(payload)
                held = None
            elif valid:
                held = payload
        ctx.set(dut.o_merge.ready, 0)

    sim.add_testbench(put_own, background=True)
    sim.add_testbench(put_in, background=True)
    sim.add_testbench(stream_protocol_checker(dut.o_merge, "o_merge", domain="merge"), background=True)
    sim.add_testbench(stream_protocol_checker(dut.i_own, "i_own"), background=True)
    sim.add_testbench(get_out)
    sim.run()
    for k in range(n):
        exp = ref_merge(inp[k], own[k])
        p = got[k]
        assert [(p.s0.z, p.s0.c), (p.s1.z, p.s1.c)] == exp, k
        assert p.last == lasts[k]


@pytest.mark.parametrize("period_sync,period_merge", [(1e-8, 1e-8), (1e-8, 2.7e-8), (3.1e-8, 1e-8), (1e-8, 1.3e-8)])
def test_merger_clock_ratios(period_sync, period_merge):
    run(150, period_sync, period_merge, seed=int(period_merge * 1e10))


def test_merger_bad_params():
    with pytest.raises(ValueError, match="fifo_depth"):
        ZbmMerger(word_layout=WORD, fifo_depth=6)
    with pytest.raises(ValueError, match="s1"):
        ZbmMerger(word_layout=data.StructLayout({"s0": SAMPLE}))
