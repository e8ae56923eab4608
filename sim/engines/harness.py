"""The verification harness every block's Amaranth-pysim bench uses.

Streams follow Amaranth's rules (``amaranth.lib.stream``): a source raises ``valid`` without
waiting for ``ready`` and holds its payload until the transfer; a transfer happens at a clock
edge where both are high.  These helpers are the one implementation of that handshake on the
testbench side:

* :func:`stream_put` — offer one payload, hold it until accepted;
* :func:`stream_get` — take one payload, optionally after idle clocks of back-pressure;
* :func:`stream_sink` — a background testbench that drains a stream into a list under a
  ``ready`` pattern (always, ``itertools.cycle([1, 1, 1, 0])``, seeded random ...);
* :func:`stream_protocol_checker` — a background testbench that fails the simulation when a
  source breaks the rules (``valid`` dropped or payload changed before the transfer), and logs
  every transfer for an in-order scoreboard;
* :func:`run_stream` — a one-stream-in, one-stream-out block run word for word: seeded idle gaps
  on ``i``, seeded random back-pressure on ``o``, the rules checked on ``o``.

Usage::

    sim.add_testbench(stream_protocol_checker(dut.o, "o", log), background=True)
    sim.add_testbench(stream_sink(dut.o, got, ready=itertools.cycle([1, 0])), background=True)
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np
from amaranth.lib import data
from amaranth.sim import Simulator

__all__ = ["as_plain", "random_gap", "run_stream", "stream_get", "stream_protocol_checker", "stream_put",
           "stream_sink"]


async def stream_put(ctx, port, payload, *, gap: int = 0, domain: str = "sync") -> None:
    """Offer ``payload`` on stream ``port`` after ``gap`` idle clocks of ``domain``; hold it
    until accepted. A plain integer on a struct-typed port is taken as the packed word.

    Returns in the clock after the one in which the transfer happened.
    """
    for _ in range(gap):
        await ctx.tick(domain)
    target = port.payload.as_value() if isinstance(port.payload, data.View) and isinstance(payload, int) \
        else port.payload
    ctx.set(target, payload)
    ctx.set(port.valid, 1)
    await ctx.tick(domain).until(port.ready)
    ctx.set(port.valid, 0)


def random_gap(rng, p_idle: float) -> int:
    """Idle clocks before a word: each clock idle with probability ``p_idle`` (geometric), drawn
    with one ``rng.random()`` per idle clock plus one (numpy Generator or ``random.Random``)."""
    g = 0
    while rng.random() < p_idle:
        g += 1
    return g


async def stream_get(ctx, port, *, gap: int = 0):
    """Take one payload from stream ``port``, after ``gap`` clocks with ``ready`` low.

    Returns the payload (a plain int or struct view as :func:`as_plain` gives it) in the clock
    after the transfer.
    """
    ctx.set(port.ready, 0)
    for _ in range(gap):
        await ctx.tick()
    ctx.set(port.ready, 1)
    (payload,) = await ctx.tick().sample(port.payload).until(port.valid)
    ctx.set(port.ready, 0)
    return as_plain(payload)


def stream_sink(port, out: list, *, ready: Iterable[int] | None = None):
    """A background testbench that accepts every transfer on ``port`` into ``out``.

    ``ready`` is the back-pressure pattern, one value per clock (``None``: always ready);
    a finite pattern ends in ``ready`` held high.
    """

    async def sink(ctx):
        pattern: Iterator[int] | None = iter(ready) if ready is not None else None
        ctx.set(port.ready, 1)
        async for _clk, _rst, valid, rdy, payload in ctx.tick().sample(port.valid, port.ready, port.payload):
            if valid and rdy:
                out.append(as_plain(payload))
            ctx.set(port.ready, 1 if pattern is None else next(pattern, 1))

    return sink


def stream_protocol_checker(port, name: str = "stream", log: list | None = None, *, domain: str = "sync",
                            errors: list | None = None):
    """A background pysim testbench checking the stream rules on ``port`` at every clock.

    Once ``valid`` is high and ``ready`` low at a clock edge, the next clock must still
    have ``valid`` high and the same payload.  Violations raise ``AssertionError``;
    accepted payloads are appended to ``log`` (if given) for an in-order scoreboard.
    ``domain`` is the clock domain the port lives in. With ``errors`` (a list) a violation is
    appended to it instead of raised, so a run can count them.

    Usage: ``sim.add_testbench(stream_protocol_checker(dut.i, "i", log), background=True)``.
    """

    async def checker(ctx):
        held = None
        async for _clk, _rst, valid, ready, payload in ctx.tick(domain).sample(port.valid, port.ready, port.payload):
            payload = as_plain(payload)
            if held is not None:
                bad = (f"{name}: valid dropped before the transfer of {held}" if not valid else
                       f"{name}: payload changed from {held} to {payload} before the transfer"
                       if payload != held else None)
                if bad and errors is None:
                    raise AssertionError(bad)
                if bad:
                    errors.append(bad)
            if valid and ready:
                if log is not None:
                    log.append(payload)
                held = None
            elif valid:
                held = payload
            else:
                held = None

    return checker


def run_stream(dut, words, *, seed: int = 0, p_stall: float = 0.3, p_gap: float = 0.3, n_out: int | None = None,
               after=None) -> list:
    """Run ``dut`` (streams ``i`` in, ``o`` out, ``sync`` domain) in pysim on ``words``: before
    each word 1-2 idle clocks with probability ``p_gap``, ``o.ready`` low with probability
    ``p_stall`` every clock (both seeded), the stream rules checked on ``o``. Runs until
    ``n_out`` words (default ``len(words)``) came out; then, one clock later, ``await
    after(ctx)`` if given (to read the block's counters). Returns the output words."""
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got: list = []
    n_out = len(words) if n_out is None else n_out
    rng = np.random.default_rng(seed)
    gaps = [int(rng.random() < p_gap) * int(rng.integers(1, 3)) for _ in words]

    async def src(ctx):
        for w, g in zip(words, gaps, strict=True):
            await stream_put(ctx, dut.i, w, gap=g)

    r = np.random.default_rng(seed + 1)
    ready = (int(r.random() >= p_stall) for _ in iter(int, 1))   # random back-pressure, every clock

    async def wait(ctx):
        while len(got) < n_out:
            await ctx.tick()
        if after is not None:
            await ctx.tick()
            await after(ctx)

    sim.add_testbench(src, background=True)
    sim.add_testbench(stream_protocol_checker(dut.o, "o"), background=True)
    sim.add_testbench(stream_sink(dut.o, got, ready=ready), background=True)
    sim.add_testbench(wait)
    sim.run()
    return got


def as_plain(v):
    """Sampled payload (int or data.Const) -> something comparable and printable."""
    if hasattr(v, "as_value"):
        v = v.as_value()
    if hasattr(v, "value"):
        return v.value
    return v
