"""Report framework: rows are well formed, labelled, and measured by running the models."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.triangle_ops import ops_per_triangle
from rasterhw.golden_model.zbm.paper import PAPER_CYCLES, PAPER_KPOLYS
from rasterhw.sim.report.rows import ROW_KEYS, format_table, make_row, ratio, run_report
from rasterhw.sim.snu.report import golden_rows
from rasterhw.sim.zbm.report import polygons_per_s


def test_make_row_checks_source():
    with pytest.raises(ValueError, match="source"):
        make_row("x", "t1", "q", paper=1, formula=1, measured=1, unit="u", source="typed-in")


def test_ratio_and_table():
    r = make_row("x", "t1", "q", paper=4, formula=None, measured=5, unit="u", source="golden")
    assert ratio(r) == 1.25
    assert ratio({**r, "paper": None}) is None
    text = format_table([r], markdown=True)
    assert text.splitlines()[0].startswith("| system") and "1.250" in text


def test_snu_table1_rows_come_from_the_instrumented_pipeline():
    from rasterhw.golden_model.snu import recipe

    rows = golden_rows("snu-100px")
    assert all(set(ROW_KEYS) <= set(r) for r in rows)
    counts = ops_per_triangle()
    paper = recipe.ops_per_triangle()
    by_q = {r["quantity"]: r for r in rows}
    # the measured columns are the pipelines' own counts, stage by stage
    for stage in ("vertex_transform", "normal_transform", "normalise", "light", "clip", "perspective_divide",
                  "screen_map"):
        row = by_q[f"{stage}: operations per triangle, our full pipeline"]
        assert row["measured"] == counts[stage]["total"] and row["source"] == "golden"
        row = by_q[f"{stage}: operations per triangle, paper's recipe (formula = the text)"]
        assert row["measured"] == paper[stage]["total"] and row["source"] == "golden"
    assert by_q["total operations per triangle, paper's recipe"]["measured"] == 270
    clk = next(r for q, r in by_q.items() if q.startswith("total i860 clocks per triangle (i860 model, assembler "
                                                             "schedule, scheduling window 1 triangle"))
    assert clk["paper"] == 309 and clk["source"] == "model:i860" and clk["measured"] == 337
    # the stage errors beside the net total: 74 clocks against 28
    err = next(r for q, r in by_q.items() if q.startswith("per-stage absolute error"))
    net = next(r for q, r in by_q.items() if q.startswith("net total error"))
    assert err["measured"] == 74 and net["measured"] == 28 and err["paper"] is None
    loop = by_q["Gouraud inner loop, integer operations per pixel (executed on snu-100px)"]
    assert loop["measured"] == 8 and loop["source"] == "golden"
    trav = by_q["traversal record per triangle (snu-100px: CSS posted, bytes emitted / triangles)"]
    assert trav["measured"] == 108


def test_zbm_polygons_per_s_is_the_papers_arithmetic():
    # 25 MHz / 54 cycles / 2 (skew) / 2 (edge pairs per polygon) = 115.7 K (paper rounds to 115.8)
    for i, cyc in PAPER_CYCLES.items():
        assert polygons_per_s(cyc) / 1e3 == pytest.approx(PAPER_KPOLYS[i], abs=0.15)


def test_run_report_writes_markdown(tmp_path, monkeypatch):
    from rasterhw.sim.report import rows as report

    def fake(*, engine, progress, out_dir):
        return [make_row("fake", "t1", "q", paper=2, formula=2, measured=2, unit="u", source="golden")], ["extra"]

    monkeypatch.setattr(report, "_load", lambda name: fake)
    rows = run_report("fake", out_dir=tmp_path)
    assert rows[0]["measured"] == 2
    text = (tmp_path / "fake.md").read_text()
    assert "| fake | t1 | q |" in text and "extra" in text


def test_unknown_system_is_a_one_line_error():
    from rasterhw.golden_model.errors import RasterhwError

    with pytest.raises(RasterhwError, match="unknown machine 'nope'"):
        run_report("nope")
