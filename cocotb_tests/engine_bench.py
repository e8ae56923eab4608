"""The cocotb engine's one test (``sim/engines/cocotb.py``): clock the generic bench top
(``rasterhw_bench``: the block, a stream source per input, a sink per output, a checker per
port; the stimulus comes from files, the words and stamps are dumped by the sinks' ``final``
blocks) exactly as the plain Verilator main (``cocotb_tests/plain_main.cpp``) does, on any
simulator cocotb drives, and write the main's JSON line to ``+meta=``.

One clock (``+nclocks=0``): ``clk`` low, then per cycle a rising and a falling edge, one time
step each, until ``done`` (or ``+maxcyc=`` rising edges). Separate clocks (``+nclocks=N``): bit
``k`` of ``clocks`` is clock ``k`` with half period ``H`` and first rising edge at time ``F``
(``+clock_k=H,F``); each step goes to the next clock event and toggles every clock due then
together (event time ``t`` is simulated at ``2 t``, the values settle at ``2 t + 1``, where
``done`` is read); ``+maxcyc=`` and ``sim_cycles`` count rising edges of clock 0. After ``done``
every clock rises once more (after the JSON's values are read): a simulator without SystemVerilog
``final`` blocks has the sinks dump on that edge instead (``harness.v``, ``RASTERHW_NO_FINAL``).
"""

from __future__ import annotations

import json
import time

import cocotb
from cocotb.triggers import Timer


def _clocks(n: int) -> tuple[list[int], list[int]]:
    half, nxt = [1] * n, [0] * n
    for k in range(n):
        arg = cocotb.plusargs.get(f"clock_{k}")
        if arg:
            h, _, f = str(arg).partition(",")
            half[k], nxt[k] = int(h), int(f or 0)
    return half, nxt


@cocotb.test()
async def bench(dut):
    maxcyc = int(cocotb.plusargs.get("maxcyc", 4_000_000_000))
    nclk = int(cocotb.plusargs.get("nclocks", 0))
    n = 0
    t0 = time.perf_counter()
    if nclk == 0:
        dut.clk.value = 0
        await Timer(1, "ns")
        while not int(dut.done.value) and n < maxcyc:
            dut.clk.value = 1
            await Timer(1, "ns")
            dut.clk.value = 0
            await Timer(1, "ns")
            n += 1
    else:
        half, nxt = _clocks(nclk)
        level, now = 0, 1
        dut.clocks.value = 0
        await Timer(1, "ns")
        while not int(dut.done.value) and n < maxcyc:
            t = min(nxt)   # the next clock event, at time 2 t: one step after it to settle
            await Timer(2 * t - now, "ns")
            for k in range(nclk):
                if nxt[k] == t:
                    level ^= 1 << k
                    nxt[k] += half[k]
                    if k == 0 and level & 1:
                        n += 1
            dut.clocks.value = level
            await Timer(1, "ns")
            now = 2 * t + 1
    run_s = time.perf_counter() - t0
    status = dut.status.value   # undriven (z) when the testbench has no status values: 0, as on Verilator
    meta = {"sim_cycles": n, "done": int(dut.done.value), "run_s": run_s, "cycles": int(dut.cycles.value),
            "errors": int(dut.errors.value), "status": int(status) if status.is_resolvable else 0}
    # one more rising edge of every clock: a simulator without `final` (Icarus at -g2005) has the
    # sinks dump their words on it (harness.v, RASTERHW_NO_FINAL); read above, so nothing counted changes
    if nclk == 0:
        dut.clk.value = 1
        await Timer(1, "ns")
        dut.clk.value = 0
        await Timer(1, "ns")
    else:
        rose = 0
        while rose != (1 << nclk) - 1:
            t = min(nxt)
            await Timer(2 * t - now, "ns")
            for k in range(nclk):
                if nxt[k] == t:
                    level ^= 1 << k
                    nxt[k] += half[k]
                    rose |= (level & (1 << k))
            dut.clocks.value = level
            await Timer(1, "ns")
            now = 2 * t + 1
    with open(cocotb.plusargs["meta"], "w") as f:
        f.write(json.dumps(meta) + "\n")
