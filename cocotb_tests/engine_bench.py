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


class _Clocks:
    """The separate clocks: bit ``k`` of ``dut.clocks`` with half period and first rising edge
    from ``+clock_k=H,F`` (default 1,0)."""

    def __init__(self, dut, n: int):
        self.dut, self.n = dut, n
        self.half, self.next = [1] * n, [0] * n
        for k in range(n):
            arg = cocotb.plusargs.get(f"clock_{k}")
            if arg:
                h, _, f = str(arg).partition(",")
                self.half[k], self.next[k] = int(h), int(f or 0)
        self.level, self.now = 0, 1

    async def event(self) -> int:
        """The next clock event (time ``t`` at ``2 t``, settled at ``2 t + 1``): every clock due
        toggles; returns the bits of the clocks that rose."""
        t = min(self.next)
        await Timer(2 * t - self.now, "ns")
        rose = 0
        for k in range(self.n):
            if self.next[k] == t:
                self.level ^= 1 << k
                self.next[k] += self.half[k]
                rose |= self.level & (1 << k)
        self.dut.clocks.value = self.level
        await Timer(1, "ns")
        self.now = 2 * t + 1
        return rose


async def _cycle(dut) -> None:
    """One clock of the one-clock bench: a rising and a falling edge, one time step each."""
    dut.clk.value = 1
    await Timer(1, "ns")
    dut.clk.value = 0
    await Timer(1, "ns")


@cocotb.test()
async def bench(dut):
    maxcyc = int(cocotb.plusargs.get("maxcyc", 4_000_000_000))
    nclk = int(cocotb.plusargs.get("nclocks", 0))
    clocks = _Clocks(dut, nclk) if nclk else None
    n = 0
    t0 = time.perf_counter()
    if clocks is None:
        dut.clk.value = 0
    else:
        dut.clocks.value = 0
    await Timer(1, "ns")
    while not int(dut.done.value) and n < maxcyc:
        if clocks is None:
            await _cycle(dut)
            n += 1
        else:   # sim_cycles and +maxcyc= count clock 0's rising edges
            n += (await clocks.event()) & 1
    run_s = time.perf_counter() - t0
    status = dut.status.value   # undriven (z) when the testbench has no status values: 0, as on Verilator
    meta = {"sim_cycles": n, "done": int(dut.done.value), "run_s": run_s, "cycles": int(dut.cycles.value),
            "errors": int(dut.errors.value), "status": int(status) if status.is_resolvable else 0}
    # one more rising edge of every clock: a simulator without `final` (Icarus at -g2005) has the
    # sinks dump their words on it (harness.v, RASTERHW_NO_FINAL); read above, so nothing counted changes
    if clocks is None:
        await _cycle(dut)
    else:
        rose = 0
        while rose != (1 << nclk) - 1:
            rose |= await clocks.event()
    with open(cocotb.plusargs["meta"], "w") as f:
        f.write(json.dumps(meta) + "\n")
