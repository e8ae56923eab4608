"""sim/engines/vlruntime.py: the Verilator runtime is compiled once and reused by the next model build."""

from __future__ import annotations

import json
import subprocess

import pytest
from rasterhw.sim.engines import vlruntime
from rasterhw.sim.engines.runner import build_plain_verilator, build_records

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
        # -O0: the runtime this test builds twice over compiles in a third of the -O2 time
        exe, secs = build_plain_verilator(f"vlrt-test-{k}", f"tb_count_{k}", [src], params={"N": 50},
                                          defines={"RASTERHW_CYCLES": 1}, opt="-O0")
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


VTOP_MK = """default: {exe}
VERILATOR_ROOT = /opt/verilator
VM_SC = 0
VM_PREFIX = Vtop
VM_USER_CFLAGS = \\
  -fcoroutines -std=c++20 -O2 \\

VM_USER_LDLIBS = \\
  -lcocotbvpi_verilator \\

VM_USER_CLASSES = \\
  verilator \\

include Vtop_classes.mk
{exe}: $(VK_USER_OBJS) $(VK_GLOBAL_OBJS) $(VM_PREFIX)__ALL.a
"""
VTOP_CLASSES_MK = """VM_TIMING = {timing}
VM_TRACE = 0
VM_CLASSES_FAST += \\
  Vtop___024root__{design} \\

VM_GLOBAL_FAST += \\
  verilated \\
  verilated_vpi \\

"""
#: stands in for make: compiles (here: writes) each runtime object that is not there yet
FAKE_MAKE = """#!/bin/sh
cd "$2"
for o in verilated.o verilated_vpi.o; do
  if [ -e $o ]; then echo "kept $o"; else echo "compiled $o"; echo obj > $o; fi
done
"""


def test_cocotb_make_step_reuses_the_runtime(tmp_path, monkeypatch):
    """cocotb's runner runs verilator, then make: between the two the runtime objects of an earlier
    build with the same compiler-visible flags go in, and after a good make they are kept."""
    from types import SimpleNamespace

    from rasterhw.sim.engines.runner import _execute_cmds_as_children

    monkeypatch.setenv("RASTERHW_VL_RUNTIME_DIR", str(tmp_path / "rt"))
    make = tmp_path / "bin" / "make"
    make.parent.mkdir()
    make.write_text(FAKE_MAKE)
    make.chmod(0o755)
    runner = SimpleNamespace(env={"MAKEFLAGS": "OPT_FAST=-O2", "PATH": "/usr/bin:/bin"})

    def build(name, *, design, timing=0, makeflags="OPT_FAST=-O2"):
        bdir = tmp_path / name
        bdir.mkdir()
        (bdir / "Vtop.mk").write_text(VTOP_MK.format(exe=name))
        (bdir / "Vtop_classes.mk").write_text(VTOP_CLASSES_MK.format(timing=timing, design=design))
        runner.env["MAKEFLAGS"] = makeflags
        log = tmp_path / f"{name}.log"
        with open(log, "w") as fh:
            _execute_cmds_as_children(runner, [[str(make), "-C", str(bdir), "-f", "Vtop.mk", "VM_TRACE=0"]],
                                      cwd=str(tmp_path), stdout=fh)
        return log.read_text()

    assert build("a", design="x").count("compiled") == 2, "the first build compiles the runtime"
    assert build("b", design="y").count("kept") == 2, "another design with the same flags reuses it"
    assert build("c", design="x", timing=1).count("compiled") == 2, "--timing changes the runtime"
    assert build("d", design="x", makeflags="OPT_FAST=-O0").count("compiled") == 2, "so does OPT_FAST"
    # not a make step (the verilator step, say): nothing goes into its folder, though the
    # runtime of these very flags is kept
    e = tmp_path / "e"
    e.mkdir()
    (e / "Vtop.mk").write_text(VTOP_MK.format(exe="e"))
    (e / "Vtop_classes.mk").write_text(VTOP_CLASSES_MK.format(timing=0, design="x"))
    runner.env["MAKEFLAGS"] = "OPT_FAST=-O2"
    _execute_cmds_as_children(runner, [["true", "-C", str(e), "-f", "Vtop.mk", "VM_TRACE=0"]], cwd=str(tmp_path))
    assert not list(e.glob("*.o"))
