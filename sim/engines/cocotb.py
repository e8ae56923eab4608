"""The cocotb engine: the Verilator engine's bench top around the block (``BenchTop``: a
``rasterhw_stream_source`` per input, a ``rasterhw_stream_sink`` per output, a stream checker per
port, all in ``cocotb_tests/harness.v``; the stimulus read from ``$fread`` files, the words and
cycle stamps dumped by the sinks' ``final`` blocks), simulated by cocotb on Verilator
(``cocotb-verilator``) or Icarus (``cocotb-icarus``), its clocks toggled by one generic cocotb test
(``cocotb_tests/engine_bench.py``) on the plain main's schedule. So any registered testbench runs
on either simulator with no bench of its own, and gives the same words and the same cycle stamps
as the pysim and plain-Verilator engines (``tests/test_engines.py``).

A design is built once per simulator (``build/tb-<block>-cocotb-<sim>-<digest>``, keyed by the
bench top's Verilog and the harness); each run gets its own folder for the stimulus, the dumps
and the simulator's log (kept, and named in the error, when the run fails)."""

from __future__ import annotations

import hashlib
import json
import time

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import runner
from rasterhw.sim.engines.verilator import (
    bench_design,
    collected,
    memory_depths,
    status_of,
    stream_plusargs,
    unpack_status,
)
from rasterhw.sim.outfile import write_if_changed
from rasterhw.sim.testbench import Run, Stimulus, Testbench
from rasterhw.sim.workdirs import keep, release, temp_run_folder

__all__ = ["run"]


def run(tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int, expect_words: dict[str, int],
        max_cycles: int, clocks: dict | None = None, build: dict | None = None, sim: str = "verilator") -> Run:
    """One run of ``stim`` through ``tb``'s block under cocotb on ``sim`` (``verilator`` or
    ``icarus``); the arguments as :func:`rasterhw.sim.engines.run` checked them. ``build``:
    ``{"depth": N, "out_depth": M}`` as on the Verilator engine (memories of at least so many
    words: one build for runs of many sizes)."""
    t0 = time.perf_counter()
    b = build or {}
    inputs, outputs = memory_depths(tb, params, stim, expect_words, depth=b.get("depth", 0),
                                    out_depth=b.get("out_depth", 0))
    name, generated, _ = bench_design(tb, params, inputs, outputs, speed=False, separate=bool(clocks))
    text = generated["rasterhw_bench.v"]
    bdir = runner.build_dir_for(f"{name}-cocotb", sim, verilog=hashlib.sha256(text.encode()).hexdigest())
    bdir.mkdir(parents=True, exist_ok=True)
    vpath = bdir / "rasterhw_bench.v"
    write_if_changed(vpath, text)
    dut = tb.dut(params)   # the port widths and the status values' names and widths (not simulated)
    run_dir = temp_run_folder(bdir)
    timings: dict = {}
    ok = False
    try:
        plus = stream_plusargs(run_dir, tb, params, stim, stall=stall, seed=seed, expect_words=expect_words,
                               inputs=inputs, dut=dut, clocks=clocks)
        meta_file = run_dir / "meta.json"
        plus += [f"+maxcyc={max_cycles}", f"+meta={meta_file}", f"+nclocks={len(clocks) if clocks else 0}"]
        runner.run_cocotb(sources=[vpath, runner.HARNESS_V], toplevel="rasterhw_bench",
                          test_module="cocotb_tests.engine_bench", build_dir=bdir, test_dir=run_dir, sim=sim,
                          plusargs=plus, timings=timings)
        meta = json.loads(meta_file.read_text())
        if not meta["done"]:
            keep(run_dir)   # the error names its log
            raise RasterhwError(f"{tb.block} on cocotb ({sim}): no `done` within {max_cycles} cycles "
                                f"(see {run_dir / 'sim.log'})")
        words, stamps = collected(run_dir, tb.outputs_of(params), expect_words)
        ok = True
    finally:
        if ok:   # a failed run's folder stays if kept (its log is named), else goes at exit
            release(run_dir)
    status = unpack_status(status_of(tb, dut, params), int(meta.get("status", 0)))
    return Run(f"cocotb-{sim}", words, stamps, wall_s=time.perf_counter() - t0, build_s=timings.get("build_s", 0.0),
               run_s=float(meta["run_s"]), protocol_errors=int(meta.get("errors", 0)), status=status,
               clocks=dict(clocks or {}),
               port_domains={n: tb.domain_of(n) for n in tb.outputs_of(params)} if clocks else {})
