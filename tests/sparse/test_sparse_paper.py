"""The sparse matrix's paper values: one file (golden_model/sparse/paper.py), each printed in seed
002, and every ``paper`` cell of the committed report printed there too; no buffer depth is the
paper's (it gives none)."""

from __future__ import annotations

from rasterhw.golden_model.sparse import paper

#: values the seed prints in words or garbled by the scan: (value -> the seed's words)
WORDS = {1.0: "практически до 100 %", 5: "времени пяти тестов покрытия", 4: "количеству видеопроцессоров 4"}
#: rows whose paper cell used to be arithmetic (now None): the limiting level n = m - k at large S
DERIVED = ("limiting level at S=1000",)


def test_every_paper_value_is_printed_in_the_seed(pv):
    assert pv.unprinted_module_values(paper, "002", WORDS) == []


def test_committed_paper_cells_are_printed(pv):
    assert pv.unprinted_paper_cells("sparse", "002", WORDS) == []


def test_derived_rows_hold_no_paper_value(pv):
    assert pv.derived_with_paper_cells("sparse", DERIVED) == []


def test_no_depth_or_processor_is_called_the_papers(pv):
    for r in pv.committed_rows("sparse"):
        q = r["quantity"]
        assert "the paper's processor" not in q and "paper's FIFO" not in q, q


def test_no_option_calls_a_configuration_the_papers():
    """``rasterhw sim --help`` for sparse: no option text calls a depth or processor "the paper's"."""
    from rasterhw.sim.sparse.machine import MACHINE

    for sb in MACHINE.sims:
        for o in sb.options:
            assert "the paper's" not in o.help, (o.name, o.help)
    from rasterhw.golden_model.sparse import vpcycles

    assert not hasattr(vpcycles, "PAPER_FIFO_DEPTH") and vpcycles.HDL_FIFO_DEPTH == 8
