"""Where a survivor's fault can show (sim/flow/reach.py): the outputs of the bench it reaches, and
its class; a survivor that reaches no output is equivalent by structure."""

from __future__ import annotations

import json

import pytest
from rasterhw.sim.flow import mutate as M
from rasterhw.sim.flow import reach as R
from rasterhw.sim.report.mutation import RECORD


def _cell(typ, outs, ins, **params):
    conn = {**outs, **ins}
    return {"type": typ, "connections": conn, "parameters": params,
            "port_directions": {**{p: "output" for p in outs}, **{p: "input" for p in ins}}}


def test_a_bit_reaches_the_output_bits_its_cell_lets_it():
    add = _cell("$add", {"Y": [20, 21, 22, 23]}, {"A": [1, 2, 3, 4], "B": [5, 6, 7, 8]})
    assert R._fanout(add, "A", 2) == [22, 23]          # a carry goes up, never down
    shr = _cell("$shr", {"Y": [30, 31]}, {"A": [1, 2, 3, 4, 5, 6], "B": ["0", "0", "1"]})
    assert R._fanout(shr, "A", 5) == [31] and R._fanout(shr, "A", 3) == []   # >> 4: bit 3 is dropped
    ff = _cell("$dff", {"Q": [40, 41]}, {"D": [1, 2], "CLK": [9]})
    assert R._fanout(ff, "D", 1) == [41] and R._fanout(ff, "CLK", 0) == [40, 41]
    lt = _cell("$lt", {"Y": [50]}, {"A": [1, 2], "B": [3, 4]})
    assert R._fanout(lt, "A", 0) == [50]


def test_classes():
    assert R.classify([], {"o"}) == "unobservable"
    assert R.classify(["top status"], {"o"}) == "uncompared"
    assert R.classify(["checker o"], {"o"}) == "uncompared"
    assert R.classify(["words o"], {"o"}) == "compared"
    assert R.classify(["ready i"], {"o"}) == "compared"


@pytest.mark.heavy
def test_a_bit_the_block_drops_reaches_no_output_and_a_killed_mutant_reaches_the_words():
    """zbm-pixel at its small configuration, 30 mutants, seed 1: mutant 1 ties bit 7 of the
    rounding add ``value + 2**23`` (``hdl/zbm/pixel.py:45``) to 0, a bit the ``>> 24`` drops: no
    path to any output (Yosys's equivalence flow proves the same,
    ``test_mutate.py``); mutant 4, which the testbench kills, reaches the output words."""
    p = M.all_configs()["zbm-pixel"]
    m = M.mutated_bench("zbm-pixel", p, mutants=30, seed=1)
    got = M.survivor_reach("zbm-pixel", p, 1, m["dir"], m["mutations"])
    assert got["reaches"][1] == [] and R.classify(got["reaches"][1], set(got["compared"])) == "unobservable"
    assert "words o" in got["reaches"][4]



def test_no_killed_mutant_of_the_record_is_called_unreachable():
    """The analysis over-approximates: a mutant a testbench killed must reach some output. Every
    killed mutant of the record with a ``reaches`` does, and every survivor called equivalent by
    structure reaches nothing."""
    rec = json.loads(RECORD.read_text())["campaign"]["blocks"]
    killed = [k for b in rec for k in b.get("killed_by", []) if "reaches" in k]
    assert killed and all(k["reaches"] for k in killed)
    structural = [s for b in rec for s in b.get("survivors", [])
                  if s.get("equivalence_how", "").startswith("structural: no path")]   # not the toggle pass's constants
    assert structural and all(s["reaches"] == [] and s["reach_class"] == "unobservable" for s in structural)
