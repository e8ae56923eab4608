# amaranth: UnusedElaboratable=no
"""Formal proof of the SNU pixel-bus bank (``rasterhw prove pixelbus-bank``; sim/flow/prove.py runs it).

``pixelbus-bank``: pick a symbolic address ``A``; a shadow register holds what the bank must hold
at ``A`` after every accepted write in order (written if its Z is nearer, the Z test of the
paper); two clocks after the last accept the read-back port at ``A`` must show the shadow
value, and ``i.ready`` must be low while a memory cycle is in progress (writes are held back,
never dropped). Commands are not offered in this proof (CLEAR/SWAP have their own pysim tests).
"""

from __future__ import annotations

from amaranth import Signal
from amaranth.hdl import Assert, Assume
from amaranth.hdl._ast import AnyConst
from rasterhw.sim.flow.prove import Harness, Proof, drive_source

__all__ = ["PROOF", "BankHarness"]


class BankHarness(Harness):
    """``PixelBusBank`` (Amaranth memories) against a one-address shadow Z buffer."""

    def elaborate(self, platform):
        m = self._start()
        m.submodules.dut = dut = self._dut_factory()
        drive_source(m, "sync", dut.i, "i")
        m.d.comb += dut.i_cmd.valid.eq(0)
        a = AnyConst(dut.addr_bits)
        m.d.comb += Assume(a < dut.depth)
        m.d.comb += [dut.rd_addr.eq(a), dut.rd_buf.eq(0)]
        ref_z, ref_rgb = Signal(dut.z_bits), Signal(24)
        accept = dut.i.valid & dut.i.ready
        p = dut.i.payload
        with m.If(accept & (p.addr == a) & (p.z > ref_z)):
            m.d.sync += [ref_z.eq(p.z), ref_rgb.eq(p.rgb)]
        quiet = Signal(2, init=0)  # clocks since the last accept, saturating at 2
        with m.If(accept):
            m.d.sync += quiet.eq(0)
        with m.Elif(quiet != 2):
            m.d.sync += quiet.eq(quiet + 1)
        busy_prev = Signal()
        m.d.sync += busy_prev.eq(dut.busy)
        m.d.comb += Assert(~dut.busy | ~dut.i.ready, "no write accepted during a memory cycle")
        with m.If(quiet == 2):
            m.d.comb += [
                Assert(dut.rd_z == ref_z, "stored Z = every accepted write, in order, Z-tested"),
                Assert(dut.rd_rgb == ref_rgb, "stored RGB = the nearest accepted write"),
            ]
        return m


PROOF = Proof(
    "pixelbus-bank", BankHarness, {"depth": 4, "z_bits": 3, "mem_cycle": 5, "ram": "memory"},
    mode="prove", depth=12,
    what="unbounded (k-induction): the word at any address = the Z-tested result of every accepted "
         "write to it, in order; no write accepted during a memory cycle")
