"""The back-pressure pattern every engine's stream sink uses: a 32-bit xorshift advanced once per
clock (x ^= x << 13; x ^= x >> 17; x ^= x << 5, seeded with the sink's seed); ``ready`` is low on
a clock whose state's low byte is below ``stall``. ``cocotb_tests/harness.v``
(``rasterhw_stream_sink``) draws the same sequence, so a stalled run gives the same cycle
stamps on pysim and Verilator."""

from __future__ import annotations

from collections.abc import Iterator

__all__ = ["ready_pattern", "xorshift32"]

_M = 0xFFFF_FFFF


def xorshift32(x: int) -> int:
    x ^= (x << 13) & _M
    x ^= x >> 17
    x ^= (x << 5) & _M
    return x & _M


def ready_pattern(seed: int, stall: int) -> Iterator[bool]:
    """``ready`` of a sink on clock 0, 1, 2, ... (forever)."""
    x = seed & _M
    while True:
        yield (x & 0xFF) >= stall
        x = xorshift32(x)
