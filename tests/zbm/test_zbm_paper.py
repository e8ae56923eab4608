"""ZB/M's paper values: one file (golden_model/zbm/paper.py), each printed in seed 003, and every
``paper`` cell of the committed report printed there too; derived values are ``formula`` rows."""

from __future__ import annotations

from rasterhw.golden_model.zbm import paper

#: values the seed prints in words: (value -> the seed's words)
WORDS = {0.5: "半分の時間は待ち状態"}
#: rows whose paper cell used to be arithmetic on the paper (now formula): quantity needle
DERIVED = ("2 neighbouring units",                 # 148 = 2 x 74
           "speed-up over 1 unit",                 # chain speed-ups 2 / 4 / 8
           "output pixel rate / interleave-1",     # "proportional to the interleave": 2 / 4 / 8 / 16
           "read as 49,152 bits",                  # 49 Kbits read as 48 x 1024
           "chip RAM bits")                        # 49,152 beside our bits


def test_every_paper_value_is_printed_in_the_seed(pv):
    assert pv.unprinted_module_values(paper, "003", WORDS) == []


def test_every_quote_is_located():
    assert all(loc and quote for loc, quote in paper.QUOTES.values())


def test_committed_paper_cells_are_printed(pv):
    assert pv.unprinted_paper_cells("zbm", "003", WORDS) == []


def test_derived_rows_hold_no_paper_value(pv):
    assert pv.derived_with_paper_cells("zbm", DERIVED) == []
