# amaranth: UnusedElaboratable=no
"""Place and route (``rasterhw fpga``, nextpnr from PyPI): one small block through the flow."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.fpga import FPGA_BLOCKS, paper_clock, place_and_route
from rasterhw.sim.verilog import block_names


def test_merger_places_on_ecp5_with_both_clocks():
    r = place_and_route("zbm-merger", family="ecp5", device="25k", fifo_depth=4, z_bits=8, colour_bits=2)
    assert r["luts"] > 0 and r["ffs"] > 0
    assert set(r["fmax_mhz"]) == {"sync", "merge"}   # the two clocks of the crossing
    assert all(f > 25 for f in r["fmax_mhz"].values())  # the paper's 25 MHz, on a 2016 FPGA
    assert {c["domain"] for c in r["paper_clocks"]} == {"sync", "merge"}
    again = place_and_route("zbm-merger", family="ecp5", device="25k", fifo_depth=4, z_bits=8, colour_bits=2)
    assert again["cached"] and again["luts"] == r["luts"]


def test_paper_clocks_and_blocks():
    assert set(FPGA_BLOCKS) <= set(block_names())
    assert paper_clock("pixelbus-bank")[0][2] == 12.5e6       # 80 ns pixel slot
    assert [d for d, _, _ in paper_clock("zbm-chip")] == ["sync", "merge"]
    assert paper_clock("zbm-pixel")[0][2] == 25e6


def test_bad_input():
    with pytest.raises(RasterhwError, match="family must be"):
        place_and_route("zbm-merger", family="xc3000")
    with pytest.raises(RasterhwError, match="device must be"):
        place_and_route("zbm-merger", device="1k")
    with pytest.raises(RasterhwError, match="black box"):
        place_and_route("pixelbus-bank", depth=16, ram="verilog")
