"""sim/vlruntime.py: the Verilator runtime is compiled once and reused by the next model build."""

from __future__ import annotations

import json
import subprocess

import pytest
from rasterhw.sim import vlruntime
from rasterhw.sim.runner import build_plain_verilator, build_records

COUNTER = """module tb_count_{k} #(parameter N = 10) (input clk, output reg done, output reg [31:0] cycles);
  initial begin done = 0; cycles = 0; end
  always @(posedge clk) begin
    cycles <= cycles + {k};
    if (cycles >= N * {k}) done <= 1;
  end
endmodule
"""


@pytest.mark.cocotb
def test_second_model_build_reuses_the_runtime(tmp_path, monkeypatch):
    monkeypatch.setenv("RASTERHW_VL_RUNTIME_DIR", str(tmp_path / "rt"))
    built = []
    for k in (1, 2):
        src = tmp_path / f"tb_count_{k}.v"
        src.write_text(COUNTER.format(k=k) + f"// {tmp_path}\n")   # a fresh build folder per test run
        exe, secs = build_plain_verilator(f"vlrt-test-{k}", f"tb_count_{k}", [src], params={"N": 50},
                                          defines={"RASTERHW_CYCLES": 1})
        log = (exe.parent.parent / "build.log").read_text()
        built.append(("verilated.cpp" in log.split("verilated.mk")[-1], log))
        out = json.loads(subprocess.run([str(exe)], capture_output=True, text=True).stdout.strip().splitlines()[-1])
        assert out["done"] == 1 and out["cycles"] >= 50 * k
        # the build's record: time and the compiler's memory peak (a C++ compiler needs > 10 MB)
        rec = json.loads((exe.parent.parent / "build.json").read_text())
        assert rec["model"] == f"vlrt-test-{k}" and rec["build_s"] > 0 and rec["compile_peak_mb"] > 10
        assert exe.parent.parent.name in {r["dir"] for r in build_records()}
    assert built[0][0], "the first build compiles the runtime"
    assert not built[1][0], "the second build compiled verilated.cpp again"
    assert (vlruntime.RUNTIME_OBJECTS[0] in {p.name for p in (tmp_path / "rt").rglob("*.o")})


def test_runtime_key_ignores_the_bench_defines_only():
    a = vlruntime.cache_dir("plain", ["-O2", "-DRASTERHW_TOP=Vtb_a -DRASTERHW_CYCLES=1"])
    b = vlruntime.cache_dir("plain", ["-O2", "-DRASTERHW_TOP=Vtb_b"])
    c = vlruntime.cache_dir("plain", ["-O3", "-DRASTERHW_TOP=Vtb_a"])
    assert a == b and a != c and a != vlruntime.cache_dir("cocotb", ["-O2"])
