"""Shared cocotb helpers: stream-protocol checker and value conversion."""

from __future__ import annotations

import cocotb
from cocotb.triggers import FallingEdge, RisingEdge

__all__ = ["check_stream_protocol", "send", "to_int"]


def to_int(handle) -> int:
    """Current value of a signal handle as an unsigned int."""
    v = handle.value
    if hasattr(v, "to_unsigned"):
        return v.to_unsigned()
    return int(v)


def _in_reset(handle) -> bool:
    try:
        return bool(to_int(handle))
    except ValueError:  # X/Z before time-zero initialisation (Icarus): treat as reset
        return True


async def check_stream_protocol(
    clk, valid, ready, payload, name: str = "stream", log: list | None = None, reset=None
) -> None:
    """Check the stream rules on (valid, ready, payload) in every clock of ``clk``.

    Samples once per clock at the falling edge, where a design clocked on the rising
    edge has settled (no race with the rising-edge updates on any simulator).  Once a clock has
    ``valid`` high and ``ready`` low, the next clock must keep ``valid`` high and the same
    payload.  Transferred payloads are appended to ``log`` (an in-order scoreboard input).
    Clocks with ``reset`` (a handle, optional) high are skipped.
    Start with ``cocotb.start_soon(check_stream_protocol(...))``; it runs until the test ends.
    """
    held = None
    while True:
        await FallingEdge(clk)
        if reset is not None and _in_reset(reset):
            held = None
            continue
        v = to_int(valid)
        # the payload of an idle stream may be X: only look at it when valid
        p = to_int(payload) if v or held is not None else None
        r = to_int(ready) if v else 0
        if held is not None:
            assert v, f"{name}: valid dropped before the transfer of {held:#x}"
            assert p == held, f"{name}: payload changed from {held:#x} to {p:#x} before the transfer"
        if v and r:
            if log is not None:
                log.append(p)
            held = None
        else:
            held = p if v else None


def start_checker(*args, **kwargs):
    """``cocotb.start_soon(check_stream_protocol(*args, **kwargs))``."""
    return cocotb.start_soon(check_stream_protocol(*args, **kwargs))


async def send(clk, valid, ready, payload, value: int) -> int:
    """Offer ``value`` on a stream until it is taken; returns the clocks it waited.

    Call just after a rising edge: inputs change only there, and ``ready`` is read at the
    falling edge (settled), where :func:`check_stream_protocol` reads it too, so no coroutine
    writes at a falling edge. Returns just after the rising edge that took the word, with
    ``valid`` low again."""
    payload.value = value
    valid.value = 1
    waited = 0
    while True:
        await FallingEdge(clk)
        taken = to_int(ready)
        await RisingEdge(clk)
        if taken:
            break
        waited += 1
    valid.value = 0
    return waited
