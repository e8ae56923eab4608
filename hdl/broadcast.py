"""A stream broadcast (fork): one input stream to ``n`` output streams, every output gets every
payload, in order, with the stream rules kept on every port."""

from __future__ import annotations

from amaranth import Cat, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["StreamBroadcast"]


class StreamBroadcast(wiring.Component):
    """Copy each input payload to ``n`` outputs; the input is taken once every output has it.

    Parameters
    ----------
    shape : shape-castable
        Payload shape.
    n : int
        Number of outputs, >= 1.

    Members
    -------
    i : In(stream.Signature(shape))
    o : Out(stream.Signature(shape)).array(n)

    ``o[k].valid`` is ``i.valid`` while output ``k`` has not yet taken the current payload; it
    never depends on any ``ready``. ``i.ready`` is high in the cycle the last outstanding output
    takes it. When every output is ready the transfer takes one cycle on all of them at once
    (no added latency); an output that is ready early takes the payload early and then waits.
    """

    def __init__(self, shape, *, n: int):
        if not (isinstance(n, int) and n >= 1):
            raise ValueError(f"n must be an integer >= 1, not {n!r}")
        self._n = n
        super().__init__({"i": In(stream.Signature(shape)), "o": Out(stream.Signature(shape)).array(n)})

    @property
    def n(self) -> int:
        return self._n

    def elaborate(self, platform):
        m = Module()
        taken = Signal(self._n)          # outputs that already took the current payload
        done = Signal(self._n)
        for k, o in enumerate(self.o):
            m.d.comb += [o.payload.eq(self.i.payload), o.valid.eq(self.i.valid & ~taken[k]),
                         done[k].eq(taken[k] | o.ready)]
        m.d.comb += self.i.ready.eq(done.all())
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += taken.eq(0)
        with m.Elif(self.i.valid):
            m.d.sync += taken.eq(taken | Cat(o.valid & o.ready for o in self.o))
        return m
