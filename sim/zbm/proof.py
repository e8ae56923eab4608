# amaranth: UnusedElaboratable=no
"""Formal proof of the ZB/M merger (``rasterhw prove zbm-merger``; sim/flow/prove.py runs it).

``zbm-merger`` (two clocks: segment ``sync`` and ``merge``, free-running and unrelated; SBY
``multiclock on``): pick a symbolic transfer number ``k`` (``AnyConst``); record the ``k``-th
own word (segment side) and the ``k``-th merge-input word; the ``k``-th output word must be the
nearest-2-of-4 merge of those two (:func:`rasterhw.hdl.zbm.merger.merge_words`), and there are
never more outputs than inputs on either side. As ``k`` is arbitrary and the payloads are
free, no word is lost, duplicated, reordered or paired with the wrong neighbour word across the
clock crossing.
"""

from __future__ import annotations

from collections.abc import Callable

from amaranth import Signal
from amaranth.hdl import Assert
from amaranth.hdl._ast import AnyConst
from rasterhw.hdl.zbm.merger import merge_words
from rasterhw.sim.flow.prove import Harness, Proof, drive_source, sink_rules

__all__ = ["PROOF", "MergerHarness"]


class MergerHarness(Harness):
    """``ZbmMerger`` under the stream rules and the transfer-``k`` ordering property."""

    domains = ("sync", "merge")

    def __init__(self, dut_factory: Callable, *, count_bits: int = 3):
        super().__init__(dut_factory)
        self._count_bits = count_bits

    def elaborate(self, platform):
        m = self._start()
        m.submodules.dut = dut = self._dut_factory()
        layout = dut.word_layout
        drive_source(m, "sync", dut.i_own, "own")
        drive_source(m, "merge", dut.i_merge, "mrg")
        sink_rules(m, "merge", dut.o_merge, "out")

        w = self._count_bits
        k = AnyConst(w)
        n_own, n_mrg, n_out = Signal(w + 1), Signal(w + 1), Signal(w + 1)
        own_k = Signal(layout)
        mrg_k = Signal(layout)
        own_t = dut.i_own.valid & dut.i_own.ready
        mrg_t = dut.i_merge.valid & dut.i_merge.ready
        out_t = dut.o_merge.valid & dut.o_merge.ready
        # counters saturate at 2**w (past every k): the property is about transfer k < 2**w
        with m.If(own_t & ~n_own[w]):
            m.d.sync += n_own.eq(n_own + 1)
            with m.If(n_own == k):
                m.d.sync += own_k.eq(dut.i_own.payload)
        with m.If(mrg_t & ~n_mrg[w]):
            m.d.merge += n_mrg.eq(n_mrg + 1)
            with m.If(n_mrg == k):
                m.d.merge += mrg_k.eq(dut.i_merge.payload)
        with m.If(out_t & ~n_out[w]):
            m.d.merge += n_out.eq(n_out + 1)
        s0, s1 = merge_words(mrg_k, own_k)
        expect = Signal(layout)
        m.d.comb += [expect.eq(own_k), expect.s0.eq(s0), expect.s1.eq(s1)]
        m.d.comb += [
            Assert(n_out <= n_own, "no output without an own word (none duplicated)"),
            Assert(n_out <= n_mrg, "no output without a merge-input word (none duplicated)"),
        ]
        with m.If(out_t & (n_out == k)):
            m.d.comb += [
                Assert((n_own > k) & (n_mrg > k), "output k comes after input k"),
                Assert(dut.o_merge.payload.as_value() == expect.as_value(),
                       "output k = merge of own word k and merge word k (none lost or reordered)"),
            ]
        return m


PROOF = Proof(
    "zbm-merger", MergerHarness, {"fifo_depth": 4, "z_bits": 3, "colour_bits": 0},
    mode="bmc", depth=16, multiclock=True,
    what="stream rules on o_merge; output k = merge(own k, merge-input k) for every k < 8, "
         "no output without both inputs; two unrelated clocks, every step of the global clock an "
         "edge of either, both or neither (the first output can appear at step 12)")
