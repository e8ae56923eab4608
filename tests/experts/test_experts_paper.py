"""EXPERTS's paper values: one file (golden_model/experts/paper.py), each printed in seed 000 with
its quote and location; the report's derived (b)/(c) ratio is a formula, not a paper cell."""

from __future__ import annotations

import importlib

from rasterhw.golden_model.experts import paper

#: string-valued constants (our stage names for the paper's stages), checked by their quotes
NAMES = ("PAPER_SLP", "PAPER_PXP")


def test_every_paper_value_is_printed_in_the_seed(pv):
    assert pv.unprinted_module_values(paper, "000", {}, skip=NAMES) == []
    text = pv.seed_text("000")
    assert all(f"《{w}》" in text for w in ("Y-sort", "X-merge", "L-sort", "span cull", "depth search"))


def test_every_quote_is_located_and_in_the_seed(pv):
    assert pv.unquoted(paper, "000") == []   # the same check for all five machines: tests/test_paper_quotes.py


def test_no_other_experts_module_defines_a_paper_constant():
    for mod in ("golden_model.experts.model", "golden_model.experts.cost", "sim.experts.report"):
        m = importlib.import_module(f"rasterhw.{mod}")
        own = [k for k, v in vars(m).items() if k.startswith("PAPER_") and getattr(paper, k, None) is not v]
        assert own == [], (mod, own)


def test_derived_rows_hold_no_paper_value(pv):
    # (b) / (c) = 1.15 / 3.35 is arithmetic on the paper: a formula
    assert pv.derived_with_paper_cells("experts", ("(b) / (c) work ratio",)) == []
