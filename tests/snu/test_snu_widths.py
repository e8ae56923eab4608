# amaranth: UnusedElaboratable=no
"""SNU widths live in golden_model/snu/formats.py: the HDL's ports and defaults equal them."""

from __future__ import annotations

import inspect

from rasterhw.golden_model.snu import formats as F
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.hdl.snu.pixelbus import PixelBus
from rasterhw.hdl.snu.pixelbus_bank import PixelBusBank, bank_write_layout


def test_hdl_widths_equal_the_formats():
    lay = bank_write_layout(addr_bits=18, z_bits=F.Z_BITS)
    assert lay.size == 18 + F.RGB_BITS + F.Z_BITS
    assert lay["rgb"].shape.width == F.RGB_BITS and lay["z"].shape.width == F.Z_BITS
    bus = PixelBus(width=40, height=16)
    assert bus.i_pipe0.payload.shape()["z"].shape.width == F.Z_BITS
    assert len(bus.rd_rgb) == F.RGB_BITS and len(bus.rd_z) == F.Z_BITS
    bank = PixelBusBank(depth=64)
    assert len(bank.rd_rgb) == F.RGB_BITS


def test_defaults_come_from_the_formats():
    bus = inspect.signature(PixelBus).parameters
    assert (bus["width"].default, bus["height"].default) == (F.FRAME_WIDTH, F.FRAME_HEIGHT)
    assert (bus["z_bits"].default, bus["n_banks"].default, bus["mem_cycle"].default) == \
        (F.Z_BITS, F.N_BANKS, F.MEM_CYCLE)
    assert inspect.signature(PixelStream).parameters["z_bits"].default == F.Z_BITS
