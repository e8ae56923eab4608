"""A warm run on the plain-Verilator engine (its Verilog cached, its model built) constructs no
block and imports no Amaranth (issue 51): the port widths and status values come from the build
cache (``sim/engines/ports.py``), the factory's parameters too (``verilog_cache.factory_params``),
and they are what the block itself gives."""

from __future__ import annotations

import inspect
import json
import subprocess
import sys

from rasterhw.sim import registry
from rasterhw.sim.engines import run
from rasterhw.sim.engines.ports import ports_of
from rasterhw.sim.engines.verilator import bench_design, memory_depths
from rasterhw.sim.engines.verilog_cache import factory_params
from rasterhw.sim.testbench import compare, find_testbench

#: a small ZB/M unit (two merge ports, two status values) with back-pressure
PARAMS = {"interleave": 2, "width": 32, "height": 16, "capacity": 16}
WARM = """
import json, sys
from rasterhw.sim.engines import run
from rasterhw.sim.testbench import compare, find_testbench
tb = find_testbench("zbm-unit")
p = tb.params(**json.loads(sys.argv[1]))
stim = tb.stimulus(p, seed=12)
exp = tb.expect(p, stim)
got = run(tb, p, stim, engine="verilator", stall=120, seed=9, expect_words={k: len(v) for k, v in exp.words.items()})
print(json.dumps({"amaranth": "amaranth" in sys.modules, "hdl": sorted(m for m in sys.modules if ".hdl." in m),
                  "mismatches": compare(exp, got)["mismatches"], "words": got.words, "stamps": got.stamps,
                  "status": got.status}))
"""


def test_a_warm_verilator_run_imports_no_amaranth_and_gives_the_same_run():
    tb = find_testbench("zbm-unit")
    p = tb.params(**PARAMS)
    stim = tb.stimulus(p, seed=12)
    exp = tb.expect(p, stim)
    need = {k: len(v) for k, v in exp.words.items()}
    first = run(tb, p, stim, engine="verilator", stall=120, seed=9, expect_words=need)   # builds if cold
    assert compare(exp, first)["mismatches"] == 0 and first.status == {"frames_ok": 1, "overflow": 0}
    out = subprocess.run([sys.executable, "-c", WARM, json.dumps(PARAMS)], capture_output=True, text=True,
                         check=True, timeout=600)
    warm = json.loads(out.stdout)
    assert not warm["amaranth"] and warm["hdl"] == []
    assert warm["mismatches"] == 0
    assert (warm["words"], warm["stamps"], warm["status"]) == (first.words, first.stamps, first.status)
    # the cached port widths and status layout are the block's own
    inputs, outputs = memory_depths(tb, p, stim, need)
    design = bench_design(tb, p, inputs, outputs, False)
    from rasterhw.sim.engines.ports import bench_ports

    assert bench_ports(tb, p, design.key, design[1]["rasterhw_bench.v"]) == json.loads(
        json.dumps(ports_of(tb, p, tb.dut(p))))


def test_cached_factory_parameters_are_the_signature():
    """Every registered block's cached (names, defaults) equal its factory's signature, on the
    first call (found) and the second (read from the cache)."""
    for block, ref in sorted(registry.blocks().items()):
        sig = inspect.signature(registry.load(ref))
        want = (list(sig.parameters), {k: v.default for k, v in sig.parameters.items()
                                       if v.default is not inspect.Parameter.empty})
        assert factory_params(block) == want, block
        assert factory_params(block) == want, block
