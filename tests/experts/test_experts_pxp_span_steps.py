"""The PXPs' sub-components (issue 46 item 6): the span PXP's and the coherent span PXP's resolve
side, one sub-component per step the paper names (initial processing, span cull, depth search,
S.S., the DSLB hand-over) or per step of ours where the paper is silent, and likewise the line
Z-buffer PXP (``pxp.py``) and the DMM/P's writer and reader (``dmm.py``); each docstring quotes the
paper's words for it, which stand in seed 000 (spaces aside; pieces between ``...`` each), and each
state of a PXP's one FSM is emitted by exactly one step."""

from __future__ import annotations

import inspect
import re

import pytest
from rasterhw.hdl.experts import dmm, pxp, pxp_coherent, pxp_span

_JP = re.compile(r"[\u3040-\u30ff\u4e00-\u9fff]")
STEPS = [pxp_span._Resolve, pxp_span._Multiply, pxp_span._Initial, pxp_span._SpanCull,
         pxp_span._DepthSearch, pxp_span._ShadeWrite, pxp_span.hand_over,
         pxp_coherent._Visible, pxp_coherent._Multiply, pxp_coherent._Initial, pxp_coherent._Enter,
         pxp_coherent._DepthSearch, pxp_coherent._ShadeWrite,
         pxp._Line, pxp._StartValues, pxp._DepthCompare, dmm.ExpertsDmm._writer, dmm.ExpertsDmm._reader]
#: each PXP module, its top class and the enum of its FSM's states
PXPS = {"pxp_span": (pxp_span, "ExpertsPxpSpan", "_R"), "pxp_coherent": (pxp_coherent, "ExpertsPxpCoherent", "_R"),
        "pxp": (pxp, "ExpertsPxp", "_S")}


def quotes(doc: str) -> list[str]:
    """The quoted passages of ``doc`` that hold Japanese text."""
    return [q for q in re.findall(r'"([^"]{1,400})"', doc) if _JP.search(q)]


def _squashed_seed(pv) -> str:
    return pv._squash(pv.seed_text("000"))


@pytest.mark.parametrize("step", STEPS, ids=lambda s: f"{s.__module__.rsplit('.', 1)[-1]}.{s.__qualname__}")
def test_each_step_quotes_the_paper_and_the_quote_stands_in_seed_000(step, pv):
    text = _squashed_seed(pv)
    found = quotes(step.__doc__ or "")
    assert found, f"{step.__qualname__}: no quote of the paper in its docstring"
    missing = [piece for q in found for piece in q.split("...") if pv._squash(piece) not in text]
    assert not missing, missing


@pytest.mark.parametrize("mod", [pxp_span, pxp_coherent, pxp], ids=lambda m: m.__name__.rsplit(".", 1)[-1])
def test_the_modules_say_why_the_steps_are_not_joined_by_streams(mod, pv):
    text = _squashed_seed(pv)
    assert "joined by streams" in " ".join(mod.__doc__.split())
    assert all(pv._squash(p) in text for q in quotes(mod.__doc__) for p in q.split("..."))


@pytest.mark.parametrize("name", list(PXPS))
def test_each_state_is_emitted_by_exactly_one_step(name):
    """Every state of the PXP's FSM has its ``m.Case`` in one step's ``states`` or, for the few
    one-line steps (the hand-over, the Z-buffer PXP's clear), in ``elaborate`` (which calls the
    step's function), never in two places."""
    mod, top, enum_name = PXPS[name]
    case = re.compile(rf"m\.Case\({enum_name}\.(\w+)\)")
    owners = {}
    for c in vars(mod).values():
        if inspect.isclass(c) and c.__module__ == mod.__name__ and hasattr(c, "states"):
            for state in case.findall(inspect.getsource(c.states)):
                owners.setdefault(state, []).append(c.__name__)
    elab = inspect.getsource(getattr(mod, top).elaborate)
    for state in case.findall(elab):
        owners.setdefault(state, []).append("elaborate")
    assert sorted(owners) == sorted(s.name for s in getattr(mod, enum_name)), owners
    assert all(len(v) == 1 for v in owners.values()), owners
    assert owners["HAND"] == ["elaborate"] and "hand_over(" in elab
