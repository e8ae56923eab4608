"""The plain-Verilator engine: a bench top generated from Amaranth around the block (one
``rasterhw_stream_source`` per input port, one ``rasterhw_stream_sink`` per output port, both in
``cocotb_tests/harness.v``; every clock domain of the block driven by the one clock), built once
per design and memory depth with the one C++ main (``cocotb_tests/plain_main.cpp``), the stimulus
loaded at run time (``$fread`` of each port's packed ``{gap, word}`` records, :mod:`packed`: no
Python int or text line per word) and the words and cycle stamps dumped at the end
(``$writememh``)."""

from __future__ import annotations

import hashlib
import inspect
import time
from pathlib import Path

import numpy as np
from amaranth.back import verilog
from amaranth.hdl import (
    Cat,
    ClockDomain,
    ClockSignal,
    Const,
    Elaboratable,
    Instance,
    Module,
    Signal,
)
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.engines.packed import as_bytes, records
from rasterhw.sim.engines.runner import HARNESS_V, build_plain_verilator, run_plain_verilator
from rasterhw.sim.engines.verilog import canonical_port_lists
from rasterhw.sim.engines.verilog_cache import convert_cached
from rasterhw.sim.testbench import Run, Stimulus, Testbench, port_of
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["GAP_BITS", "BenchTop", "run"]

GAP_BITS = 8          # idle clocks before a word: 0..255
_SELF = hashlib.sha1(Path(__file__).read_bytes()).hexdigest()[:12]   # this file is part of the design


def _tag(path: str) -> str:
    """Port path -> plusarg stem: ``o_merge[3]`` -> ``o_merge_3``."""
    return path.replace("[", "_").replace("]", "").replace(".", "_")


def _depth(n: int) -> int:
    """Memory words for ``n`` words (and one spare): the next power of two, at least 16, so runs of
    similar size share one build."""
    d = 16
    while d < n + 2:
        d *= 2
    return d


def _payload(port):
    p = port.payload
    return p.as_value() if hasattr(p, "as_value") else p


class BenchTop(Elaboratable):
    """The block with a source on every input port and a sink on every output port; ports
    ``clk``, ``done`` (every source played out and every sink full) and ``cycles`` (edges so far)."""

    def __init__(self, dut, inputs: dict[str, int], outputs: dict[str, int], domains: tuple[str, ...]):
        self.dut = dut
        self._inputs, self._outputs, self._domains = inputs, outputs, domains
        self.cd = ClockDomain("sync", reset_less=True)
        self.done = Signal(name="done")
        self.cycles = Signal(32, name="cycles")
        self.ports = [self.cd.clk, self.done, self.cycles]

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = self.cd
        for d in self._domains:
            if d != "sync":   # every domain of the block runs on the one clock
                m.domains += ClockDomain(d, reset_less=True)
                m.d.comb += ClockSignal(d).eq(ClockSignal("sync"))
        m.submodules.dut = self.dut
        m.d.sync += self.cycles.eq(self.cycles + 1)
        dones = []
        for name, depth in self._inputs.items():
            port, t = port_of(self.dut, name), _tag(name)
            ok = Signal(name=f"{t}_done")
            m.submodules[f"src_{t}"] = Instance(
                "rasterhw_stream_source", p_PW=len(_payload(port)), p_GW=GAP_BITS, p_DEPTH=depth,
                p_FILE_ARG=f"{t}=%s", p_COUNT_ARG=f"{t}_n=%d", p_BINARY=1,
                i_clk=ClockSignal("sync"), i_rst=Const(0, 1), i_base=Const(0, 32), i_count=Const(0, 32),
                i_repeats=Const(1, 32),
                o_valid=port.valid, i_ready=port.ready, o_payload=_payload(port), o_done=ok)
            dones.append(ok)
        for name, depth in self._outputs.items():
            port, t = port_of(self.dut, name), _tag(name)
            ok = Signal(name=f"{t}_done")
            m.submodules[f"sink_{t}"] = Instance(
                "rasterhw_stream_sink", p_PW=len(_payload(port)), p_DEPTH=depth,
                p_FILE_ARG=f"{t}=%s", p_CYC_ARG=f"{t}_cyc=%s", p_COUNT_ARG=f"{t}_n=%d",
                p_STALL_ARG=f"{t}_stall=%d", p_SEED_ARG=f"{t}_seed=%d",
                i_clk=ClockSignal("sync"), i_cycle=self.cycles, i_valid=port.valid, o_ready=port.ready,
                i_payload=_payload(port), o_done=ok)
            dones.append(ok)
        m.d.comb += self.done.eq(Cat(*dones).all())
        return m


def _build(tb: Testbench, params: dict, inputs: dict[str, int], outputs: dict[str, int]) -> tuple[Path, float]:
    # the testbench's own module builds the DUT's adapter (e.g. a read-out): its bytes are design too
    tb_src = hashlib.sha1(Path(inspect.getfile(type(tb))).read_bytes()).hexdigest()[:12]
    key = {**params, "inputs": inputs, "outputs": outputs, "bench": _SELF, "testbench": tb_src}
    text = convert_cached(
        tb.block, lambda: BenchTop(tb.dut(params), inputs, outputs, tb.domains), params=key, module="rasterhw_bench",
        convert=lambda top, mod: canonical_port_lists(verilog.convert(top, name=mod, ports=top.ports)) + _extra(top.dut))
    return build_plain_verilator(f"tb-{tb.block}", "rasterhw_bench", [HARNESS_V], params={}, opt=tb.verilator_opt,
                                 defines={"RASTERHW_CYCLES": 1}, generated={"rasterhw_bench.v": text})


def run(tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int, expect_words: dict[str, int],
        max_cycles: int) -> Run:
    t0 = time.perf_counter()
    outs = tb.outputs_of(params)
    inputs = {n: _depth(len(stim.words[n])) for n in tb.inputs}
    outputs = {n: _depth(expect_words[n]) for n in outs}
    dut = tb.dut(params)
    widths = {n: len(_payload(port_of(dut, n))) for n in tb.inputs}
    exe, build_s = _build(tb, params, inputs, outputs)
    run_dir = temp_run_folder(exe.parent.parent)
    try:
        plus = []
        for n in tb.inputs:
            t, words, gaps = _tag(n), stim.words[n], stim.gaps_of(n)
            g_arr = np.asarray(gaps, dtype=np.int64)
            if g_arr.size and (g_arr.min() < 0 or g_arr.max() >= 1 << GAP_BITS):
                raise RasterhwError(f"{tb.block}: gaps on {n} must lie in 0..{(1 << GAP_BITS) - 1}")
            pw = widths[n]
            (run_dir / f"{t}.bin").write_bytes(records(as_bytes(words, pw), pw, g_arr, GAP_BITS).tobytes())
            plus += [f"+{t}={run_dir / f'{t}.bin'}", f"+{t}_n={len(words)}"]
        for k, n in enumerate(outs):
            t = _tag(n)
            plus += [f"+{t}={run_dir / f'{t}.out'}", f"+{t}_cyc={run_dir / f'{t}.cyc'}", f"+{t}_n={expect_words[n]}",
                     f"+{t}_stall={stall}", f"+{t}_seed={seed + k}"]
        meta = run_plain_verilator(exe, plus, run_dir=run_dir, maxcyc=max_cycles)
        words, stamps = {}, {}
        for n in outs:
            t, k = _tag(n), expect_words[n]
            words[n] = _ints(read_memh(run_dir / f"{t}.out", None)) if k else []
            stamps[n] = _ints(read_memh(run_dir / f"{t}.cyc", None)) if k else []
            words[n], stamps[n] = words[n][:k], stamps[n][:k]
    finally:
        release(run_dir)
    return Run("verilator", words, stamps, wall_s=time.perf_counter() - t0, build_s=build_s, run_s=meta["run_s"])


def _extra(dut) -> str:
    """Hand-written Verilog the block instantiates (its ``extra_verilog()``, e.g. a RAM model), if any."""
    return dut.extra_verilog() if hasattr(dut, "extra_verilog") else ""


def _ints(b) -> list[int]:
    """Dumped words (``read_memh`` rows) as Python ints; words of up to 64 bits in one NumPy pass
    (a million-word frame read-out: 0.3 s instead of 4 s)."""
    if 0 < b.shape[1] <= 8:
        return memh_uint64(b, 0, b.shape[1]).tolist()
    return [int.from_bytes(row.tobytes(), "big") for row in b]
