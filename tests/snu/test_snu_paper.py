"""SNU's paper values: one file (golden_model/snu/paper.py), each printed in seed 004, and every
``paper`` cell of the committed report printed there too; derived values are ``formula`` rows."""

from __future__ import annotations

from rasterhw.golden_model.snu import paper

#: values the seed prints in words: (value -> the seed's words): one second, "초 당"
WORDS = {1.0: "초당 100,000개"}
#: rows whose paper cell used to be arithmetic on table 1 (now formula)
DERIVED = ("clocks per triangle (formula = sum of the paper's table 1 clocks",   # 99, 141, 69
           "polygons/s per 3-processor pipeline")                               # 40 MHz / 141


def _numbers(v):
    if isinstance(v, dict):
        return [x for t in v.values() for x in _numbers(t)]
    return [v]


def test_every_paper_value_is_printed_in_the_seed(pv):
    text = pv.seed_text("004")
    for name in paper.__all__:
        if name in ("QUOTES", "PAPER_TEXT_COUNTS", "PAPER_FRAME_S"):
            continue
        for x in _numbers(getattr(paper, name)):
            assert pv.printed(x, text), (name, x)
        assert name in paper.QUOTES, name


def test_committed_paper_cells_are_printed(pv):
    assert pv.unprinted_paper_cells("snu", "004", WORDS) == []


def test_derived_rows_hold_no_paper_value(pv):
    for needle in DERIVED:
        cells = pv.paper_cells("snu", needle)
        assert cells and set(cells) == {"—"}, (needle, cells)
