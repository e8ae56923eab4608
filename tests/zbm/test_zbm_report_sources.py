"""The ZB/M report's rows say what produced them in this run (issue 46): a row whose run a
``--fast`` report leaves out has ``source`` "not run" (``rows.NOT_RUN``) and keeps what measures it
in ``source_when_run``; a row that ran names its simulator."""

from __future__ import annotations

import pytest
from rasterhw.sim.report.rows import NOT_RUN, make_row


def test_fast_report_marks_table1_rows_it_did_not_run(monkeypatch, tmp_path):
    """``rows(fast=True)``: Table 1 at interleave 8 and 16 on pysim is left out (``FAST_TABLE1_SKIP``):
    those rows and the polygons/s rows made from them say "not run"; the rows of 1, 2, 4 say
    ``hdl:pysim``. The steady-state runs are stood in for by the exact cycle model's marginal (the
    labels are what is checked here; the runs themselves: test_zbm_report_table1_steady_state_in_pysim),
    the scaling runs by none (their rows: test_zbm_report_measures_its_hdl_rows)."""
    from rasterhw.golden_model.zbm import cycles as C
    from rasterhw.sim.zbm import report, scaling

    ran = []

    def steady(interleave, engine="pysim", schedule="overlap"):
        ran.append((schedule, interleave, engine))
        w = max(4 * interleave, 8)
        m = [C.hdl_cycles(C.paper_workload(k, width=w), 5 * k, width=w, interleave=interleave,
                          schedule=schedule)["cycles"] for k in (4, 5)]
        return {"per_edge_pair": m[1] - m[0], "words_compared": 1, "mismatches": 0}

    monkeypatch.setattr(report, "measure_steady_state", steady)
    monkeypatch.setattr(scaling, "report_tasks", lambda **kw: [])
    monkeypatch.setattr(scaling, "report_rows", lambda **kw: [])
    rows, _ = report.rows(engine="pysim", out_dir=tmp_path, fast=True)
    assert sorted(ran) == sorted((s, i, "pysim") for s in ("paper", "overlap") for i in (1, 2, 4))
    t1 = [r for r in rows if r["figure"] in ("table 1 / 6.1", "table 1")]
    assert len(t1) == 20
    for r in t1:
        i = int(r["quantity"].split("interleave ")[1].split(",")[0].split(" ")[0])
        if i in report.FAST_SKIP_INTERLEAVES:
            assert r["measured"] is None and r["source"] == NOT_RUN and r["reason"] == report.FAST_TABLE1_SKIP, r
            assert r["source_when_run"] == ("hdl:pysim" if r["figure"] == "table 1 / 6.1" else "model"), r
        else:
            assert r["measured"] is not None and r["source"] in ("hdl:pysim", "model") and "source_when_run" not in r
    # every row the fast run left out says so; nothing unmeasured claims a simulator
    assert not [r for r in rows if r["measured"] is None and str(r["source"]).startswith("hdl:")]


def test_not_run_row_needs_no_value():
    r = make_row("x", "t", "q", paper=1, formula=None, measured=None, unit="u", source="hdl:pysim",
                 reason="fast", run=False)
    assert r["source"] == NOT_RUN and r["source_when_run"] == "hdl:pysim"
    with pytest.raises(ValueError, match="not run, yet measured"):
        make_row("x", "t", "q", paper=1, formula=None, measured=3, unit="u", source="hdl:pysim", reason="f", run=False)
