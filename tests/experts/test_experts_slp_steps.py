"""The SLP's and its set-up's sub-components (issue 46 item 6): each step the paper names is one,
and its docstring quotes the paper's words for it, which stand in seed 000 (spaces aside; pieces
between ``...`` each)."""

from __future__ import annotations

import re

import pytest
from rasterhw.hdl.experts import slp, slp_setup

_JP = re.compile(r"[\u3040-\u30ff\u4e00-\u9fff]")
STEPS = [slp._Band, slp._YSort, slp._AslUpdate, slp._LSort, slp._XMerge, slp._BlockLists,
         slp_setup.ExpertsSlpSetup._datapath, slp_setup.ExpertsSlpSetup._program,
         slp_setup.ExpertsSlpSetup._take, slp_setup.ExpertsSlpSetup._product,
         slp_setup.ExpertsSlpSetup._reciprocal]


def quotes(doc: str) -> list[str]:
    """The quoted passages of ``doc`` that hold Japanese text."""
    return [q for q in re.findall(r'"([^"]{1,400})"', doc) if _JP.search(q)]


@pytest.mark.parametrize("step", STEPS, ids=lambda s: s.__qualname__)
def test_each_step_quotes_the_paper_and_the_quote_stands_in_seed_000(step, pv):
    text = pv._squash(pv.seed_text("000"))
    found = quotes(step.__doc__ or "")
    assert found, f"{step.__qualname__}: no quote of the paper in its docstring"
    missing = [piece for q in found for piece in q.split("...") if pv._squash(piece) not in text]
    assert not missing, missing


def test_the_modules_say_why_the_steps_are_not_joined_by_streams(pv):
    text = pv._squash(pv.seed_text("000"))
    for mod in (slp, slp_setup):
        assert "joined by streams" in " ".join(mod.__doc__.split())
        assert all(pv._squash(p) in text for q in quotes(mod.__doc__) for p in q.split("..."))

