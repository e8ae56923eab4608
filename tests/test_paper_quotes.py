"""Paper figures in one place per machine: ``golden_model/NAME/paper.py`` for each of the five, every
quote of its ``QUOTES`` standing in the machine's seed (tests/paper_values.py: ``unquoted``), and no
``PAPER_`` constant defined anywhere else under ``sim/`` or ``golden_model/``."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MACHINES = ("zbm", "snu", "sparse", "experts", "vzbuf")


@pytest.mark.parametrize("machine", MACHINES)
def test_every_quote_stands_in_the_seed(pv, machine):
    mod = importlib.import_module(f"rasterhw.golden_model.{machine}.paper")
    assert mod.QUOTES
    assert pv.unquoted(mod, pv.SEED_OF[machine]) == []


def test_unquoted_finds_a_quote_not_in_the_seed(pv):
    class Fake:
        __all__ = ["PAPER_X", "PAPER_Y", "QUOTES"]
        QUOTES = {"PAPER_X": ("2.4", "表 2.1 ... not a word of the paper"), "PAPER_Y": ("", "表"),
                  "PAPER_Z": ("1", "表")}
    assert pv.unquoted(Fake, "000") == [("PAPER_X", " not a word of the paper"), ("PAPER_Y", ""), ("PAPER_Z", "")]


def test_no_paper_constant_outside_paper_py():
    every = [p for tree in ("sim", "golden_model") for p in (ROOT / tree).rglob("*.py")]
    own = re.compile(r"^\s*PAPER_\w+\s*(:[^=\n]*)?=(?!=)", re.M)
    elsewhere = [str(p.relative_to(ROOT)) for p in every
                 if p.name != "paper.py" and own.search(p.read_text(encoding="utf-8"))]
    assert elsewhere == []
    assert all((ROOT / "golden_model" / m / "paper.py").is_file() for m in MACHINES)
