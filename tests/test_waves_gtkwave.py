"""Waves GTKWave opens (issue 53 item 1): a Verilator and a pysim trace of the ZB/M unit, each
with its save file, loaded in GTKWave (Debian's ``gtkwave``) under ``xvfb-run``; any VCD parse
error, any signal of the save file GTKWave does not show, fails. Skipped where GTKWave or
xvfb-run is not installed (as the Icarus tests are where ``iverilog`` is not)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from rasterhw.sim.engines import waves
from wave_helpers import run_cli

GTKWAVE = pytest.mark.skipif(shutil.which("gtkwave") is None or shutil.which("xvfb-run") is None,
                             reason="gtkwave or xvfb-run not on PATH (Debian: apt install gtkwave xvfb)")

#: prints what GTKWave shows, then quits
TCL = """puts "RHW traces [gtkwave::getTotalNumTraces]"
for {set i 0} {$i < [gtkwave::getTotalNumTraces]} {incr i} { puts "RHW trace [gtkwave::getTraceNameFromIndex $i]" }
puts "RHW dumpfile [gtkwave::getDumpFileName]"
gtkwave::/File/Quit
"""


def gtkwave_load(gtkw: Path, tmp_path: Path) -> tuple[str, list[str]]:
    """Open ``gtkw`` in GTKWave under a virtual X server from another folder (the dump path in
    the save file is relative to it); GTKWave's whole output and the traces it shows."""
    tcl = tmp_path / "check.tcl"
    tcl.write_text(TCL)
    p = subprocess.run(["xvfb-run", "-a", "gtkwave", "--script", str(tcl), str(gtkw.resolve())],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path)
    out = p.stdout + p.stderr
    assert p.returncode == 0, out[-2000:]
    return out, [ln.split(" ", 2)[2] for ln in out.splitlines() if ln.startswith("RHW trace ")]


def _asked(gtkw: Path) -> tuple[list[str], set[str]]:
    """The traces a save file asks for, as GTKWave lists them (the last part of each name; a
    combined trace ``#{alias} ...`` by its alias), and its groups (GTKWave lists a group's start
    and end as traces of that name)."""
    names, groups = [], set()
    for ln in gtkw.read_text().splitlines():
        if ln.startswith("#{"):
            names.append(ln[2:ln.index("}")].rsplit(".", 1)[-1])
        elif ln.startswith("-"):
            groups.add(ln[1:])
        elif ln and ln[0] not in "[@*":
            names.append(ln.rsplit(".", 1)[-1])
    return names, groups


@GTKWAVE
@pytest.mark.heavy
@pytest.mark.parametrize("engine", ["verilator", "pysim"])
def test_gtkwave_opens_the_trace_and_shows_every_signal_of_the_save_file(tmp_path, capsys, engine):
    vcd = tmp_path / "w" / "run.vcd"
    args = ["sim", "zbm", "--scene", "c50", "--size", "40x40", "--interleave", "1", "--engine", engine,
            "--waves", str(vcd), "--json"]
    assert run_cli(args) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["mismatches"] == 0 and res["waves"] == [str(vcd)]
    text = vcd.read_text()
    assert "$auto$" not in text
    assert not waves.gtkwave_unreadable(waves.vcd_header(vcd))
    gtkw = vcd.with_suffix(".gtkw")
    save = gtkw.read_text()
    assert '[dumpfile] "run.vcd"' in save and '[savefile] "run.gtkw"' in save   # relative: the pair moves
    assert re.search(r"^\*-\d+\.0+ ", save, re.M)                                 # zoomed to the whole trace
    out, shown = gtkwave_load(gtkw, tmp_path)
    assert "parse error" not in out.lower() and "error" not in out.lower(), out[-2000:]
    assert f"RHW dumpfile {vcd.resolve()}" in out
    # clock, reset and cycle counter first, then the stream ports, the input payload in fields
    assert shown[:3] == ["clk", "rst", "cycles[31:0]" if engine == "verilator" else "cycle[31:0]"], shown[:6]
    assert shown.count("z[23:0]") == 2, shown   # the output payload's fields: s0.z and s1.z
    asked, groups = _asked(gtkw)
    assert [n for n in shown if n not in groups] == asked   # GTKWave found every signal it was asked for


@GTKWAVE
def test_gtkwave_rejects_the_yosys_names_this_test_is_for(tmp_path):
    """The check above can fail: a VCD with Yosys's ``$auto$...:N:...`` name makes GTKWave report
    a parse error, and :func:`waves.gtkwave_unreadable` names it."""
    vcd = tmp_path / "bad.vcd"
    vcd.write_text("$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! clk $end\n"
                   "$var reg 1 \" $auto$verilog_backend.cc:2355:dump_module$5 $end\n$upscope $end\n"
                   "$enddefinitions $end\n#0\n0!\n0\"\n#5\n1!\n")
    assert waves.gtkwave_unreadable(waves.vcd_header(vcd)) == ["top.$auto$verilog_backend.cc:2355:dump_module$5"]
    gtkw = waves.write_gtkw(vcd)
    tcl = tmp_path / "check.tcl"
    tcl.write_text(TCL)
    p = subprocess.run(["xvfb-run", "-a", "gtkwave", "--script", str(tcl), str(gtkw)],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert "parse error" in (p.stdout + p.stderr)
