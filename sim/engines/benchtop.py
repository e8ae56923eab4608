"""The plain-Verilator engine's bench top (:class:`BenchTop`): the block with a
``rasterhw_stream_source`` on every input port, a ``rasterhw_stream_sink`` on every output port and
a ``rasterhw_stream_check`` on each (``cocotb_tests/harness.v``). Its own module so that a run whose
Verilog is cached (``verilog_cache``) and whose model is built never imports Amaranth."""

from __future__ import annotations

from amaranth.hdl import (
    Cat,
    ClockDomain,
    ClockSignal,
    Const,
    Elaboratable,
    Instance,
    Module,
    Signal,
)
from rasterhw.sim.engines.ports import GAP_BITS, payload_of, tag
from rasterhw.sim.testbench import port_of

__all__ = ["BenchTop"]


class BenchTop(Elaboratable):
    """The block with a source on every input port and a sink on every output port; ports
    ``clk``, ``done`` (every source played out and every sink full), ``cycles`` (edges so far) and
    ``errors`` (clocks that broke the stream rules, every port: ``rasterhw_stream_check``).

    ``port_domains`` (``{port: domain}`` of every stream port): separate clocks; the top then has
    ``clocks`` (bit ``k``: domain ``domains[k]``'s clock, ``sync`` first) instead of ``clk``, each
    port's source, sink and checker run on its domain's clock and a sink stamps its words with its
    domain's edge count (``cycles`` for ``sync``). None: every domain on ``clk``."""

    def __init__(self, dut, inputs: dict[str, int], outputs: dict[str, int], domains: tuple[str, ...],
                 status: dict | None = None, port_domains: dict[str, str] | None = None):
        self.dut = dut
        self._status = dict(status or {})
        self._inputs, self._outputs, self._domains = inputs, outputs, domains
        self._port_domains = port_domains
        self.cd = ClockDomain("sync", reset_less=True)
        self.done = Signal(name="done")
        self.cycles = Signal(32, name="cycles")
        self.errors = Signal(32, name="errors")
        self.status = Signal(64, name="status")   # the testbench's status values, packed in order
        if port_domains is None:
            self.ports = [self.cd.clk, self.done, self.cycles, self.errors, self.status]
        else:
            self.clocks = Signal(len(domains), name="clocks")
            self.ports = [self.clocks, self.done, self.cycles, self.errors, self.status]

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = self.cd
        separate = self._port_domains is not None
        counters = {"sync": self.cycles}
        for k, d in enumerate(self._domains):
            if d != "sync":
                m.domains += ClockDomain(d, reset_less=True)
            if separate:   # each domain on its own bit of `clocks`, with its own edge count
                m.d.comb += ClockSignal(d).eq(self.clocks[k])
                if d != "sync":
                    counters[d] = Signal(32, name=f"cycles_{d}")
                    m.d[d] += counters[d].eq(counters[d] + 1)
            elif d != "sync":   # every domain of the block runs on the one clock
                m.d.comb += ClockSignal(d).eq(ClockSignal("sync"))
        m.submodules.dut = self.dut
        m.d.sync += self.cycles.eq(self.cycles + 1)

        def dom(name):
            return self._port_domains[name] if separate else "sync"

        dones, errors = [], []
        for name, depth in self._inputs.items():
            port, t = port_of(self.dut, name), tag(name)
            ok = Signal(name=f"{t}_done")
            m.submodules[f"src_{t}"] = Instance(
                "rasterhw_stream_source", p_PW=len(payload_of(port)), p_GW=GAP_BITS, p_DEPTH=depth,
                p_FILE_ARG=f"{t}=%s", p_COUNT_ARG=f"{t}_n=%d", p_BINARY=1,
                i_clk=ClockSignal(dom(name)), i_rst=Const(0, 1), i_base=Const(0, 32), i_count=Const(0, 32),
                i_repeats=Const(1, 32),
                o_valid=port.valid, i_ready=port.ready, o_payload=payload_of(port), o_done=ok)
            dones.append(ok)
            errors.append(_check(m, t, port, dom(name)))
        for name, depth in self._outputs.items():
            port, t = port_of(self.dut, name), tag(name)
            ok = Signal(name=f"{t}_done")
            m.submodules[f"sink_{t}"] = Instance(
                "rasterhw_stream_sink", p_PW=len(payload_of(port)), p_DEPTH=depth,
                p_FILE_ARG=f"{t}=%s", p_CYC_ARG=f"{t}_cyc=%s", p_COUNT_ARG=f"{t}_n=%d",
                p_STALL_ARG=f"{t}_stall=%d", p_SEED_ARG=f"{t}_seed=%d",
                i_clk=ClockSignal(dom(name)), i_cycle=counters[dom(name)], i_valid=port.valid, o_ready=port.ready,
                i_payload=payload_of(port), o_done=ok)
            dones.append(ok)
            errors.append(_check(m, t, port, dom(name)))
        m.d.comb += [self.done.eq(Cat(*dones).all()), self.errors.eq(sum(errors, Const(0, 32)))]
        if self._status:
            m.d.comb += self.status.eq(Cat(*self._status.values()))
        return m


def _check(m: Module, tag: str, port, domain: str = "sync") -> Signal:
    """A stream-rule checker on ``port`` (``rasterhw_stream_check``) on ``domain``'s clock; its
    count of bad clocks."""
    err = Signal(32, name=f"{tag}_errors")
    m.submodules[f"check_{tag}"] = Instance(
        "rasterhw_stream_check", p_PW=len(payload_of(port)), i_clk=ClockSignal(domain), i_rst=Const(0, 1),
        i_valid=port.valid, i_ready=port.ready, i_payload=payload_of(port), o_errors=err,
        o_transfers=Signal(32, name=f"{tag}_transfers"))
    return err
