"""Generated Verilog says what it is: block, parameters, design digest, version, ports."""

from __future__ import annotations

import subprocess
import sys

from rasterhw.sim.engines.verilog_cache import source_digest, verilog_header
from rasterhw.sim.version import version


def _verilog(*args):
    return subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", "verilog", *args],
                          capture_output=True, text=True, timeout=600)


def test_verilog_to_stdout_starts_with_a_header_naming_block_parameters_and_streams():
    r = _verilog("zbm-merger", "-p", "fifo_depth=8", "-o", "-")
    assert r.returncode == 0, r.stderr
    head = r.stdout.splitlines()[:8]
    assert head[0].startswith("// rasterhw ") and "block zbm-merger" in head[0] and "-p fifo_depth=8" in head[0]
    assert head[0].startswith(f"// rasterhw {version()}: ")   # the release and, in a checkout, the commit
    assert "fifo_depth=8" in head[1] and "z_bits=24" in head[1]          # given and default parameters
    assert source_digest("zbm-merger")[:16] in head[2]
    assert any("in  i_own: stream" in ln and "payload {s0: 64, s1: 64}" in ln for ln in head)
    assert any("out o_merge: stream" in ln for ln in head)
    assert "module zbm_merger(" in r.stdout                              # the Verilog follows


def test_header_lists_plain_ports_with_widths():
    h = verilog_header("pixelbus-bank", depth=4096)
    assert "depth=4096" in h and "in  rd_addr: 12 bits" in h and "out busy: 1 bit\n" in h
    assert "in  i: stream" in h and "addr: 12" in h
