"""SNU's paper values: one file (golden_model/snu/paper.py), each printed in seed 004, and every
``paper`` cell of the committed report printed there too; derived values are ``formula`` rows."""

from __future__ import annotations

from rasterhw.golden_model.snu import paper

#: values the seed prints in words: (value -> the seed's words): one second, "초 당"
WORDS = {1.0: "초당 100,000개"}
#: rows whose paper cell used to be arithmetic on table 1 (now formula)
DERIVED = ("clocks per triangle (formula = sum of the paper's table 1 clocks",   # 99, 141, 69
           "polygons/s per 3-processor pipeline")                               # 40 MHz / 141


def test_every_paper_value_is_printed_in_the_seed(pv):
    # the text's per-vertex mix is printed in words and sums ("3 회의 실수 곱셈"): its quote is in QUOTES
    assert pv.unprinted_module_values(paper, "004", WORDS, skip=("PAPER_TEXT_COUNTS",)) == []


def test_committed_paper_cells_are_printed(pv):
    assert pv.unprinted_paper_cells("snu", "004", WORDS) == []


def test_derived_rows_hold_no_paper_value(pv):
    assert pv.derived_with_paper_cells("snu", DERIVED) == []
