"""Every EXPERTS block at its machine's small configuration (``Flow.small``: the size ``mutate --all``,
``prove --all`` and ``synth --all --small`` take) gets a stimulus it can hold and passes its own
testbench on pysim: words and, where the block has a cycle model, cycles. Before, three of them
failed unmutated at that size (the span PXPs overflowed their 16-deep DMM/P banks and stalled for
good; the group's SLP dropped the triangles of a scene bigger than its 64-entry PL and gave 80 wrong
pixels), so ``mutate --all`` called them void; and a stimulus with no line that fits is refused in
one line instead of an ``IndexError``."""

from __future__ import annotations

import pytest
from rasterhw.sim import registry
from rasterhw.sim.engines import run
from rasterhw.sim.testbench import compare, find_testbench

BLOCKS = sorted(b for b in registry.blocks() if b.startswith("experts-"))


@pytest.mark.parametrize("block", BLOCKS)
def test_block_at_its_small_size_passes_its_testbench(block):
    tb = find_testbench(block)
    p = tb.params(**registry.flow(block).small)
    stim = tb.stimulus(p, seed=1)
    exp = tb.expect(p, stim)
    got = run(tb, p, stim, engine="pysim", expect_words={k: len(v) for k, v in exp.words.items()})
    c = compare(exp, got)
    assert c["mismatches"] == 0 and sum(map(len, exp.words.values())) > 0
    assert c["cycle_mismatches"] in (0, None)


def test_a_stimulus_with_no_line_that_fits_is_refused(monkeypatch):
    tb = find_testbench("experts-pxp-span")
    p = tb.params(width=64, depth=16, aj="c")
    monkeypatch.setattr(type(tb), "segments", lambda self, fr, line: 17)   # every line one too many
    with pytest.raises(ValueError, match="fits 16 segments; take a larger depth"):
        tb.stimulus(p, seed=1)
