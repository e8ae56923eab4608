"""Amaranth views of the ZB/M word formats defined in ``golden_model/zbm/formats.py``.

The golden model is the contract: every ``data.StructLayout`` here is built from its
:class:`~rasterhw.golden_model.zbm.formats.Layout` (same field order, widths, signedness,
LSB first), so a packed golden word and an HDL word are the same integer. Words narrower
than their bus (112-bit loop flits, 168-bit loader words) are padded with a ``pad`` field.
"""

from __future__ import annotations

from amaranth import signed, unsigned
from amaranth.lib import data
from rasterhw.golden_model.zbm import formats as F

# the one interleave check (RasterhwError), where every ZB/M block's signature is built
from rasterhw.golden_model.zbm.formats import GAP_PENDING, SCHEDULES, check_interleave, paper_lead

__all__ = [
    "check_interleave", "struct_of", "EP_HEADER", "EP_CHANNEL", "SEG_HEADER", "FLIT", "PKT_HEADER",
    "SAMPLE", "PIXEL2", "PACKET", "check_schedule", "GAP", "GAP_PENDING", "paper_lead",
]


def struct_of(layout: F.Layout, *, sub: dict | None = None) -> data.StructLayout:
    """Golden :class:`Layout` -> ``data.StructLayout`` (optionally replacing fields by layouts)."""
    sub = sub or {}
    members = {}
    for f in layout.fields:
        members[f.name] = sub.get(f.name, signed(f.width) if f.signed else unsigned(f.width))
    if layout.width > layout.used:
        members["pad"] = unsigned(layout.width - layout.used)
    out = data.StructLayout(members)
    assert out.size == layout.width, (layout.name, out.size, layout.width)
    return out


EP_HEADER = struct_of(F.EP_HEADER)
EP_CHANNEL = struct_of(F.EP_CHANNEL)     # value, ddy, ddx: signed 56, Q.40 (x, len) / Q.24
SEG_HEADER = struct_of(F.SEG_HEADER)     # y: u9, x: u10, len: u10, mode: u1
FLIT = struct_of(F.FLIT)                 # value, inc: signed 56, Q.24
PKT_HEADER = struct_of(F.PKT_HEADER)     # x: u10, len: u10, y: u9, mode: u1, dx: u5
SAMPLE = struct_of(F.SAMPLE)             # z: u24 (0 = near, 0xFFFFFF = empty), a, c0..c3: u8
PIXEL2 = struct_of(F.PIXEL2, sub={"s0": SAMPLE, "s1": SAMPLE})   # s0 nearer or equal
#: one segment packet as the initial processor hands it over: 8 flits of the 112-bit loop,
#: flit 0 = PKT_HEADER
PACKET = data.ArrayLayout(unsigned(F.LOOP_BITS), F.PACKET_FLITS)


#: a chip's ring gap: cycles until its segment processor could start a new packet,
#: ``GAP_PENDING`` while a packet waits in the chip (``ZbmLoop.gap``, ``ZbmChip.gap``)
GAP = unsigned(GAP_PENDING.bit_length())


def check_schedule(schedule) -> None:
    """``schedule`` is ``"overlap"`` (ours) or ``"paper"`` (sec. 6.1's schedule); else ``ValueError``."""
    if schedule not in SCHEDULES:
        raise ValueError(f"schedule must be 'overlap' or 'paper', not {schedule!r}")


