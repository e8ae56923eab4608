# amaranth: UnusedElaboratable=no
"""The one bench adapter of the memory-backed blocks: write streams in, the block's memory out.

A block that keeps what it makes in a memory read through a side port (the SNU pixel bus and its
bank: ``rd_addr`` -> ``rd_rgb``, ``rd_z``; the sparse video processors and matrix: ``rd_addr`` or
``rd_x``, ``rd_y`` -> ``rd_tri``, ``rd_z``) has no output stream of its own. :class:`ReadOut` gives
it one, so the generic engines run it like any other block and compare the memory word for word.
The machines' testbenches say which ports, which read port and which word (``sim/snu/testbench.py``,
``sim/sparse/testbench.py``); :func:`sweep` is the read-out alone, for an adapter that decides
itself when the memory is ready (``sim/snu/frame_adapter.py``). Knows no machine.
"""

from __future__ import annotations

from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.sim.testbench import port_of

__all__ = ["ReadOut", "sweep"]


class ReadOut(wiring.Component):
    """``block`` with an end token on every write stream and its memory streamed out on ``o``.

    Every port in ``ports`` (the block's write streams, same names) carries ``{end, record}``
    (``{config, end, record}`` on the first port with ``config``; ``record_bits`` wide records,
    default the block port's payload): records go to the block's port; a word with ``end`` set is
    taken at once and ends that port. Once every port has ended and the block is idle (``busy``
    low), the read address sweeps ``0 .. words - 1`` (``address(m, block, addr)`` drives the read
    port; one clock of read latency, the next address presented on a transfer) and ``o`` carries
    ``data(block)`` of each address, one word a clock while ``o.ready`` is high (held while it is
    low: the stream rules). Timing: an end token taken at edge ``E`` (the block idle from then on)
    gives word 0 at edge ``E + 2``, word ``k`` at ``E + 2 + k`` when ``o`` is always ready.

    ``fixed``: constant inputs of the block (``{path: value}``, e.g. ``"i_cmd.valid"``).
    ``config``: inputs set at run time (``{name: value before any config word}``): a word with
    ``config`` set is taken at once and loads them from its low bits, in order
    (:meth:`config_word`), so one build serves every value. ``tail``: the block's counters (output
    names) sent after the memory, one word each (zero-extended), in order. ``stats``: ``(cells,
    sels)``: then counter ``stat`` for every ``stat_cell`` and, within it, ``stat_sel``. ``count``:
    then the adapter's own count of the block's cycles: every clock from the first record offered
    until the block is idle after the end (that clock included). The block's hand-written Verilog
    (its ``extra_verilog()``, e.g. a RAM model) or ``extra``: for the Verilator bench."""

    def __init__(self, block, *, words: int, address, data, ports: tuple[str, ...] = ("i",),
                 record_bits: int | None = None, fixed: dict | None = None, config: dict | None = None,
                 tail: tuple[str, ...] = (), stats: tuple[int, int] | None = None, count: bool = False,
                 extra: str | None = None):
        self.block, self._words, self._address, self._data = block, words, address, data
        self._ports, self._fixed, self._config = tuple(ports), dict(fixed or {}), dict(config or {})
        self._rec = {p: len(port_of(block, p).payload.as_value()) if record_bits is None else record_bits
                     for p in self._ports}
        self._tail, self._stats = tuple(tail) + (("$cycles",) if count else ()), stats
        self._extra = extra
        sig = {p: In(stream.Signature(self._rec[p] + 1 + (bool(self._config) and k == 0)))
               for k, p in enumerate(self._ports)}
        sig["o"] = Out(stream.Signature(len(data(block))))
        super().__init__(sig)

    def extra_verilog(self) -> str:
        if self._extra is not None:
            return self._extra
        return self.block.extra_verilog() if hasattr(self.block, "extra_verilog") else ""

    @staticmethod
    def config_word(record_bits: int, widths: dict, values: dict) -> int:
        """The input word that loads ``values`` (``{name: value}``, the ``config`` inputs of widths
        ``widths``, in order) into a :class:`ReadOut` whose records are ``record_bits`` wide."""
        word, at = 0, 0
        for name, w in widths.items():
            v = int(values[name])
            if not 0 <= v < 1 << w:
                raise ValueError(f"config {name}={v} does not fit {w} bits")
            word |= v << at
            at += w
        return word | 1 << (record_bits + 1)

    def elaborate(self, platform):
        m = Module()
        m.submodules.block = b = self.block
        for path, v in self._fixed.items():
            m.d.comb += port_of(b, path).eq(v)
        first = self._ports[0]
        src0, rec0 = port_of(self, first), self._rec[first]
        cfg = src0.payload[rec0 + 1] if self._config else Const(0, 1)
        at = 0
        for name, v in self._config.items():
            port = getattr(b, name)
            reg = Signal(len(port), init=v, name=f"cfg_{name}")
            m.d.comb += port.eq(reg)
            with m.If(src0.valid & cfg):
                m.d.sync += reg.eq(src0.payload[at:at + len(port)])
            at += len(port)
        addr = Signal(range(self._words + 1))
        run_cycles, started = Signal(32), Signal()
        take = self.o.valid & self.o.ready
        seen, offered = [], []
        for p in self._ports:
            src, dst, rec = port_of(self, p), port_of(b, p), self._rec[p]
            end, done = src.payload[rec], Signal(name=f"{p.replace('.', '_')}_ended")
            c = cfg if p == first else Const(0, 1)
            m.d.comb += [dst.payload.eq(src.payload[:rec]), dst.valid.eq(src.valid & ~end & ~c & ~done),
                         src.ready.eq(~done & (end | c | dst.ready))]
            with m.If(src.valid & end & ~c & ~done):
                m.d.sync += done.eq(1)
            seen.append(done)
            offered.append(dst.valid)
        ended = Cat(*seen).all()
        with m.FSM():
            with m.State("FEED"):
                self._address(m, b, addr)
                with m.If(Cat(*offered).any()):
                    m.d.sync += started.eq(1)
                with m.If(Cat(*offered).any() | started | Cat(*seen).any()):
                    m.d.sync += run_cycles.eq(run_cycles + 1)
                with m.If(ended & ~b.busy):
                    m.next = "READ"
            with m.State("READ"):
                # the word of addr is on the read port now; a transfer presents the next address
                self._address(m, b, Mux(take, addr + 1, addr))
                m.d.comb += [self.o.valid.eq(1), self.o.payload.eq(self._data(b))]
                with m.If(take):
                    m.d.sync += addr.eq(addr + 1)
                    with m.If(addr == self._words - 1):
                        m.next = "TAIL" if self._tail else ("STATS" if self._stats else "DONE")
            if self._tail:
                k = Signal(range(len(self._tail)))
                with m.State("TAIL"):
                    m.d.comb += self.o.valid.eq(1)
                    with m.Switch(k):
                        for j, name in enumerate(self._tail):
                            with m.Case(j):
                                m.d.comb += self.o.payload.eq(run_cycles if name == "$cycles" else getattr(b, name))
                    with m.If(self.o.ready):
                        m.d.sync += k.eq(k + 1)
                        with m.If(k == len(self._tail) - 1):
                            m.next = "STATS" if self._stats else "DONE"
            if self._stats:
                cells, sels = self._stats
                c, s = Signal(range(cells)), Signal(range(sels))
                with m.State("STATS"):
                    m.d.comb += [self.o.valid.eq(1), b.stat_cell.eq(c), b.stat_sel.eq(s), self.o.payload.eq(b.stat)]
                    with m.If(self.o.ready):
                        m.d.sync += s.eq(s + 1)
                        with m.If(s == sels - 1):
                            m.d.sync += [s.eq(0), c.eq(c + 1)]
                            with m.If(c == cells - 1):
                                m.next = "DONE"
            with m.State("DONE"):
                pass
        return m


def sweep(m: Module, rd_addr, data, o, words: int, start) -> None:
    """In ``m``: once ``start`` is high, sweep the read address ``rd_addr`` over ``0 .. words - 1``
    and stream ``data`` (the read port's word, one clock after its address) out on ``o``, one per
    clock while ``o.ready`` is high (the address, so the payload, held while the sink stalls); once."""
    sweeping, finished = Signal(), Signal()
    ptr = Signal(range(words + 1))
    take = o.valid & o.ready
    with m.If(start & ~sweeping & ~finished):
        m.d.sync += sweeping.eq(1)
    with m.If(take):
        m.d.sync += ptr.eq(ptr + 1)
        with m.If(ptr == words - 1):
            m.d.sync += [sweeping.eq(0), finished.eq(1)]
    # present the next address on a transfer, so the data is there in the next clock
    m.d.comb += [rd_addr.eq(Mux(take, ptr + 1, ptr)), o.valid.eq(sweeping), o.payload.eq(data)]
