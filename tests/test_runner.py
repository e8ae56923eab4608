# amaranth: UnusedElaboratable=no
"""Verilog generation registry, lint and simulator selection (rasterhw.sim.engines.verilog/runner).
The lint is a check of the generated Verilog, not a user path: it lives here."""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterable, Sequence
from pathlib import Path

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import runner
from rasterhw.sim.engines.runner import SimulatorUnavailable, build_dir_for, get_sim
from rasterhw.sim.engines.verilog import block_names, generate_verilog
from rasterhw.sim.engines.verilog_cache import write_verilog
from rasterhw.sim.paths import verilator_bin_dir

# Lint waivers for `verilator --lint-only -Wall` on Amaranth (yosys write_verilog) output,
# each an artefact of the generator, not of the design:
LINT_WAIVERS = [
    # the file is named after the block, the module after the block with '-' -> '_'
    "-Wno-DECLFILENAME",
    # ZB/M's merge-clock crossing: Amaranth's AsyncFIFO resets its read side through
    # lib.cdc.ResetSynchronizer, which asserts asynchronously and releases synchronously, while
    # the segment domain uses the same `rst` synchronously -- the intended reset-bridge pattern
    "-Wno-SYNCASYNCNET",
    # Amaranth writes every register as `reg x = init;` and then assigns it in `always`
    "-Wno-PROCASSINIT",
    # yosys keeps alias wires for every named Amaranth signal and struct field, and
    # intermediate `$n` nets whose upper bits are unused
    "-Wno-UNUSEDSIGNAL",
    # `case` on Amaranth Switch/Array with the default assigned before the case
    "-Wno-CASEINCOMPLETE",
    # yosys prints constants at their minimal width (`x / 3'h5`, `x == 1'h1`) and
    # reduces with `!x[2:0]`; Amaranth has already fixed every operand's width
    "-Wno-WIDTHEXPAND",
    "-Wno-WIDTHTRUNC",
]


def lint_verilog(sources: Iterable[Path], top: str, *, waivers: Sequence[str] = LINT_WAIVERS) -> str:
    """``verilator --lint-only -Wall`` with :data:`LINT_WAIVERS`; returns the output.

    Raises :class:`RasterhwError` (with Verilator's messages) if any warning or error is left.
    """
    cmd = [str(verilator_bin_dir() / "verilator"), "--lint-only", "-Wall", *waivers, runner.INCLUDE_ARG, "--top-module", top]
    cmd += [str(s) for s in sources]
    p = subprocess.run(cmd, capture_output=True, text=True, env=runner.sim_env())
    out = p.stdout + p.stderr
    if p.returncode != 0 or "%Warning" in out or "%Error" in out:
        raise RasterhwError(f"verilator lint failed for {top}:\n{out}")
    return out


def test_registry_has_every_machines_blocks():
    assert {"pixelbus", "pixelbus-bank", "zbm-chip", "zbm-seggen", "zbm-unit"} <= set(block_names())


def test_write_verilog_pixelbus(tmp_path):
    path = write_verilog("pixelbus", tmp_path / "pixelbus.v", width=20, height=4)
    text = path.read_text()
    assert "module pixelbus(" in text or "module pixelbus (" in text
    for port in ("i_pipe0__valid", "i_pipe0__ready", "i_pipe1__payload", "i_cmd__valid",
                 "rd_addr", "rd_rgb", "rd_z", "cycle", "idle", "busy"):
        assert port in text, port
    # 20x4 = 80 pixels -> 7-bit address, payload = 7 + 24 + 24 bits
    assert "input [54:0] i_pipe0__payload" in text


def test_generate_verilog_bank_and_verilog_ram():
    text = generate_verilog("pixelbus-bank", depth=16)
    assert "module pixelbus_bank" in text and "rasterhw_pixelbus_ram" not in text
    text = generate_verilog("pixelbus", width=20, height=4, ram="verilog")
    assert "module rasterhw_pixelbus_ram" in text and text.count("rasterhw_pixelbus_ram ") >= 15


def test_unknown_block_and_bad_params():
    with pytest.raises(RasterhwError, match="unknown block 'no-such-block'"):
        generate_verilog("no-such-block")
    with pytest.raises(RasterhwError, match="no parameter 'banks'"):
        generate_verilog("pixelbus", banks=4)
    with pytest.raises(RasterhwError, match="width must be a positive integer"):
        generate_verilog("pixelbus", width=0, height=4)
    with pytest.raises(RasterhwError, match="mem_cycle"):
        write_verilog("pixelbus-bank", "/nonexistent/never.v", depth=4, mem_cycle=1)


@pytest.mark.parametrize("block,params", [
    ("pixelbus", {"width": 40, "height": 16}),
    ("pixelbus", {"width": 40, "height": 16, "ram": "verilog"}),
    ("pixelbus-bank", {"depth": 100}),
    ("zbm-seggen", {"width": 64, "height": 16}),
    ("zbm-chip", {"interleave": 2, "width": 64}),
    ("zbm-unit", {"interleave": 2, "width": 64, "height": 16}),
])
def test_verilator_lint_clean(tmp_path, block, params):
    path = write_verilog(block, tmp_path / f"{block}.v", **params)
    lint_verilog([path], block.replace("-", "_"))


def test_lint_reports_real_problems(tmp_path):
    bad = tmp_path / "bad.v"
    bad.write_text("module bad(input wire [3:0] a, output wire [1:0] y);\n  assign y = a;\nendmodule\n")
    with pytest.raises(RasterhwError, match="WIDTH"):
        lint_verilog([bad], "bad", waivers=["-Wno-DECLFILENAME"])


def test_simulator_selection(monkeypatch):
    monkeypatch.delenv("SIM", raising=False)
    assert get_sim() == "verilator"
    with pytest.raises(RasterhwError, match="simulator must be one of"):
        get_sim("vcs")
    if shutil.which("iverilog") is None:
        with pytest.raises(SimulatorUnavailable, match="iverilog"):
            get_sim("icarus")
    else:
        assert get_sim("icarus") == "icarus"


def test_build_dir_per_parameter_set():
    a = build_dir_for("pixelbus", "verilator", width=40, height=16)
    b = build_dir_for("pixelbus", "verilator", width=40, height=8)
    assert a != b and a == build_dir_for("pixelbus", "verilator", height=16, width=40)
    assert a.parent.name == "build"
