"""The bench's read port of a processor's local memory (``read_lanes`` > 0): ``read_lanes``
consecutive sparse addresses a clock, beside the video controller's one.

Not the paper's (seed 002 says only that the video controller sees the local memories "как единая
память с расслоением по двум координатным осям", no rate): it lets a testbench take the raster out
of the simulation in ``2**(2n) / read_lanes`` clocks. ``read_lanes = 0`` (the hardware as the flow
takes it) adds no port and no logic."""

from __future__ import annotations

from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import TRI_BITS

__all__ = ["bench_read_ports", "check_lanes", "forward_bench_read", "lane_bits"]

#: the most sparse addresses the bench port reads a clock
MAX_LANES = 64


def lane_bits(z_bits: int, colour: bool) -> int:
    """Bits of one local-memory word on the bench port: ``{rgb, tri, z}`` (``z`` lowest; ``rgb``
    only with ``colour``)."""
    return z_bits + 1 + TRI_BITS + (24 if colour else 0)


def check_lanes(n: int, lanes: int) -> int:
    """``lanes`` checked (0, or a power of two up to ``min(MAX_LANES, 2**(2n))``); returns its log2
    (0 for no port)."""
    if (isinstance(lanes, bool) or not isinstance(lanes, int) or lanes < 0 or lanes & (lanes - 1)
            or lanes > min(MAX_LANES, 1 << (2 * n))):
        raise ValueError(f"read_lanes must be 0 or a power of two up to {min(MAX_LANES, 1 << (2 * n))}, not {lanes!r}")
    return max(lanes.bit_length() - 1, 0)


def bench_read_ports(n: int, z_bits: int, colour: bool, lanes: int) -> dict:
    """The bench port's members (none for ``lanes = 0``): ``rdw_addr`` In(2n - log2 lanes), the
    group ``g``; ``rdw_data`` Out(lanes * lane_bits), one clock later the words of sparse addresses
    ``g * lanes + j``, ``j = 0 .. lanes - 1``, word ``j`` in lane ``j`` (lane 0 lowest)."""
    if not lanes:
        return {}
    return {"rdw_addr": In(2 * n - check_lanes(n, lanes)), "rdw_data": Out(lanes * lane_bits(z_bits, colour))}


def forward_bench_read(m, outer, inner, lanes: int) -> None:
    """In ``m``: ``outer``'s bench port is ``inner``'s (a processor and the block holding it)."""
    if lanes:
        m.d.comb += [inner.rdw_addr.eq(outer.rdw_addr), outer.rdw_data.eq(inner.rdw_data)]
