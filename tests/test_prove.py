# amaranth: UnusedElaboratable=no
"""Formal proofs (``rasterhw prove``, SymbiYosys + Yices from PyPI): the real blocks pass, a
deliberately broken variant of each fails with a VCD counterexample."""

from __future__ import annotations

import pytest
from amaranth import Module, Signal
from amaranth.lib import wiring
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.verilog import make_block
from rasterhw.sim.flow.prove import proofs, prove


class LossyMerger(wiring.Component):
    """The merger behind an output register that never stalls its input: when the consumer
    is not ready the register is overwritten -- a word lost, and a payload changed while valid."""

    def __init__(self):
        self._inner = make_block("zbm-merger", **proofs()["zbm-merger"].params)
        super().__init__(self._inner.signature)

    @property
    def word_layout(self):
        return self._inner.word_layout

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self._inner
        wiring.connect(m, wiring.flipped(self.i_own), inner.i_own)
        wiring.connect(m, wiring.flipped(self.i_merge), inner.i_merge)
        m.d.comb += inner.o_merge.ready.eq(1)
        with m.If(self.o_merge.ready):
            m.d.merge += self.o_merge.valid.eq(0)
        with m.If(inner.o_merge.valid):
            m.d.merge += [self.o_merge.valid.eq(1), self.o_merge.payload.eq(inner.o_merge.payload)]
        return m


class ForgetfulBank(wiring.Component):
    """The pixel-bus bank with one flaw: it reports ready one write early (a write offered in
    the last clock of a memory cycle is acknowledged and dropped)."""

    def __init__(self):
        self._inner = make_block("pixelbus-bank", **proofs()["pixelbus-bank"].params)
        for k in ("depth", "z_bits", "addr_bits"):
            setattr(self, k, getattr(self._inner, k))
        super().__init__(self._inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self._inner
        wiring.connect(m, wiring.flipped(self.i_cmd), inner.i_cmd)
        m.d.comb += [inner.i.payload.eq(self.i.payload), inner.rd_addr.eq(self.rd_addr),
                     inner.rd_buf.eq(self.rd_buf), self.rd_rgb.eq(inner.rd_rgb), self.rd_z.eq(inner.rd_z),
                     self.busy.eq(inner.busy), self.draw_buf.eq(inner.draw_buf)]
        was_busy = Signal()
        m.d.sync += was_busy.eq(inner.busy)
        early = was_busy & ~inner.busy   # first free clock: claim ready, but drop the word
        m.d.comb += [self.i.ready.eq(inner.i.ready),
                     inner.i.valid.eq(self.i.valid & ~early)]
        return m


@pytest.mark.parametrize("block", ["pixelbus-bank", "zbm-merger"])
def test_block_proof_passes(block):
    r = prove(block)
    assert r["status"] == "PASS", r
    assert r["trace"] is None


def test_a_finished_proof_is_read_back_and_fresh_proves_again():
    a = prove("pixelbus-bank")
    b = prove("pixelbus-bank")
    assert b["cached"] and (b["status"], b["workdir"], b["wall_s"]) == (a["status"], a["workdir"], a["wall_s"])
    c = prove("pixelbus-bank", fresh=True)
    assert not c["cached"] and c["status"] == "PASS" and (c["workdir"] / "sby.log").exists()
    # a broken variant's record points at its trace; without the trace it is proved again
    f = prove("pixelbus-bank", dut_factory=ForgetfulBank, tag="broken")
    f["trace"].unlink()
    g = prove("pixelbus-bank", dut_factory=ForgetfulBank, tag="broken")
    assert not g["cached"] and g["status"] == "FAIL" and g["trace"].exists()


@pytest.mark.parametrize("block, broken", [("zbm-merger", LossyMerger), ("pixelbus-bank", ForgetfulBank)])
def test_broken_variant_fails_with_a_trace(block, broken):
    r = prove(block, dut_factory=broken, tag="broken")
    assert r["status"] == "FAIL"
    assert r["trace"] is not None and r["trace"].suffix == ".vcd" and r["trace"].stat().st_size > 0
    assert "$var" in r["trace"].read_text()


def test_unknown_proof_is_a_one_line_error():
    with pytest.raises(RasterhwError, match="no proof for block 'zbm-chip'; proofs: "):
        prove("zbm-chip")
