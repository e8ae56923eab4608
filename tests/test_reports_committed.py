"""Reports never shrink silently: regenerate each report's fast rows and compare them with the
committed tables in ``docs/reproduction/``.

Compared: every committed row is produced again (by ``row_key``: system, figure, quantity with
decimal numbers masked), with the same ``paper`` value and ``source``; rows from the golden
model or a formula also keep their ``formula`` value. Measured HDL numbers, timings and ratios
are not compared (they are the report's to change); slow rows (synthesis, place and route)
come back unmeasured with their reason.

That check needs no simulation: it runs rows-only (``run_report(..., rows_only=True)``: the
golden, model and formula rows computed, every HDL and synthesis row kept unmeasured with its
reason) for the systems whose rows function takes ``rows_only``, records-only (``fast``) for the
others. That the HDL rows are measured is checked apart: ZB/M's in
``test_zbm_report_measures_its_hdl_rows`` (fast) and in the whole fast report (``slow``).
"""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.report.rows import (
    NOT_RUN,
    ROWS_ONLY,
    _fmt,
    make_row,
    missing_rows,
    parse_table,
    row_key,
    run_report,
    systems,
)

DOCS = Path(__file__).resolve().parents[1] / "docs" / "reproduction"
#: reports whose regeneration takes minutes even in a fast run (HDL frames, big sweeps): not run
#: here; ``rasterhw report all`` checks them the same way (it refuses to drop a committed row)
SLOW_SYSTEMS = {"experts", "sparse", "vzbuf", "snu"}


def _compare(system: str, tmp_path: Path, *, rows_only: bool = False) -> list[dict]:
    committed = parse_table((DOCS / f"{system}.md").read_text())
    assert committed, f"no table in docs/reproduction/{system}.md"
    rows = run_report(system, out_dir=tmp_path, engine="pysim", fast=True, rows_only=rows_only)
    lost = missing_rows(committed, rows)
    assert not lost, f"{system}: {len(lost)} committed rows not produced, first {lost[0]}"
    by_key = {}
    for r in rows:
        by_key.setdefault(row_key(r), []).append(r)
    for c in committed:
        r = by_key[row_key(c)].pop(0)
        assert _fmt(r["paper"]) == c["paper"], (c, r)
        # a row this run left out says "not run" (rows.NOT_RUN) and what measures it when run
        src = r.get("source_when_run", r["source"])
        assert (r["source"] == NOT_RUN) == ("source_when_run" in r) and (r["source"] != NOT_RUN or r["measured"] is None)
        # an HDL row's simulator follows the engine the table was made with (this test runs pysim)
        if c["source"] == NOT_RUN:   # the committed table's own run left it out (e.g. a configuration not placed)
            assert r["measured"] is None or src.startswith("hdl:"), (c, r)
        elif str(c["source"]).startswith("hdl:") and str(src).startswith("hdl:"):
            assert c["source"].split(":")[0] == src.split(":")[0], (c, r)
        else:
            assert src == c["source"], (c, r)
        if src in ("golden", "formula"):
            assert _fmt(r["formula"]) == c["formula"], (c, r)
        if r["measured"] is None:
            assert r.get("reason"), r
    return rows


def _takes_rows_only(system: str) -> bool:
    from rasterhw.sim.report.rows import _load

    return "rows_only" in inspect.signature(_load(system)).parameters


@pytest.mark.parametrize("system", [s for s in systems() if s not in SLOW_SYSTEMS or _takes_rows_only(s)])
def test_rows_only_report_keeps_every_committed_row(system, tmp_path):
    """Row names, paper values, sources and formulas of the committed table, without simulating."""
    rows = _compare(system, tmp_path, rows_only=True)
    if _takes_rows_only(system):   # nothing simulated or synthesised: every HDL row says so
        hdl = [r for r in rows if str(r.get("source_when_run", r["source"])).startswith("hdl:")]
        assert hdl and all(r["measured"] is None and r["reason"] == ROWS_ONLY and r["source"] == NOT_RUN for r in hdl)


@pytest.mark.heavy(2)
def test_zbm_report_measures_its_hdl_rows(monkeypatch):
    """The ZB/M report's HDL rows come back measured, word for word against the golden model: the
    skew pair (two chained units, twice) and the 1-unit chain on Verilator through the report's
    own rows (``skew`` and ``chain`` raise on a differing word), Table 1's steady state on pysim
    at interleave 1 and 4, both schedules, each run comparing every merge word (the test below,
    one case per run, so that they run beside the Verilator runs under ``-n 2``). The skew's unit
    "alone" is Table 1's paper-schedule unit at interleave 1 on Verilator (its frame 2 lines
    taller): its steady state is the paper's 74 cycles per edge pair (it stands in the fast suite
    for test_table1_paper_schedule_verilator[1], now slow: one build fewer). The other runs of a
    fast report, each checked in every test run elsewhere: Table 1 in pysim at interleave 2,
    tests/zbm/test_zbm_unit_pysim.py::test_line_log_steady_state_equals_model (and at 8 on
    Verilator, tests/zbm/test_zbm_cocotb.py::test_table1_paper_schedule_verilator); the pixel rate
    at interleave 1 and 4, test_pixel_rate_scales_with_interleave; all of them through the
    report: the ``slow`` test below."""
    from rasterhw.golden_model.zbm.cycles import formula_cycles_per_edge_pair
    from rasterhw.sim.zbm import scaling

    monkeypatch.setattr(scaling, "FAST_SKIP_PIXEL_RATE", (1, 2, 4, 8, 16))
    monkeypatch.setattr(scaling, "FAST_SKIP_CHAIN", (2, 4, 8))
    rows = scaling.report_rows(engine="verilator", fast=True)
    skew = [r for r in rows if r["figure"] == "6.1 cond. 7"]
    chain = {r["quantity"].split(",")[0]: r["measured"] for r in rows
             if r["figure"] == "6.1 (chain)" and r["quantity"].endswith("speed-up over 1 unit")}
    assert len(skew) == 2 and all(r["measured"] is not None and r["source"] == "hdl:verilator" for r in skew)
    # the unit alone on Verilator (its value is in the pair row's label; measured, as the pair is)
    (pair,) = [r for r in skew if "alone" in r["quantity"]]
    assert f"(interleave 1, paper schedule; alone {formula_cycles_per_edge_pair(1):.1f};" in pair["quantity"]
    assert chain["1 chained unit"] == 1 and chain["2 chained units"] is None
    assert all(r["measured"] is None for r in rows if r["figure"] == "5.3")


@pytest.mark.parametrize("sched", ["paper", "overlap"])
@pytest.mark.parametrize("interleave", [1, 4])   # the interleaves a fast report measures on pysim besides 2
def test_zbm_report_table1_steady_state_in_pysim(interleave, sched):
    """The ZB/M report's Table 1 runs on pysim (``report.measure_steady_state``): every merge word
    golden, the steady state = the exact model's marginal, and on the paper schedule = the paper's
    Table 1 formula (74 cycles per edge pair at interleave 1, 59 at 4)."""
    from rasterhw.golden_model.zbm.cycles import formula_cycles_per_edge_pair
    from rasterhw.sim.zbm import report

    r = report.measure_steady_state(interleave, "pysim", sched)
    assert r["words_compared"] > 0 and r["mismatches"] == 0
    assert r["per_edge_pair"] == r["model_marginal"]
    if sched == "paper":
        assert r["per_edge_pair"] == formula_cycles_per_edge_pair(interleave)


@pytest.mark.slow
@pytest.mark.parametrize("system", ["zbm"])
def test_whole_fast_report_keeps_every_committed_row(system, tmp_path):
    """The whole fast report with its HDL runs: the committed rows, and every HDL row a fast run
    measures measured (Table 1 on pysim at interleave 1, 2, 4, each carrying its compared words)."""
    rows = _compare(system, tmp_path)
    t1 = {(r["quantity"].split(", ")[1], r["quantity"].split(", ")[2]): r for r in rows
          if r["figure"] == "table 1 / 6.1"}
    for i in (1, 2, 4):
        for s in ("paper schedule", "overlapped schedule (ours)"):
            r = t1[(f"interleave {i}", s)]
            assert r["measured"] and r["words_compared"] > 0 and r["mismatches"] == 0, r
    assert all(r["measured"] is not None for r in rows if r["figure"] in ("6.1 cond. 7", "6.1 (chain)")
               and not r["quantity"].startswith(("4 chained", "8 chained")))


def test_every_report_has_a_committed_table():
    for s in systems():
        assert parse_table((DOCS / f"{s}.md").read_text()), s


def test_a_report_that_would_drop_a_row_fails_and_keeps_the_file(tmp_path, monkeypatch):
    from rasterhw.sim.report import rows as report

    two = [make_row("fake", "t1", "a", paper=1, formula=None, measured=1, unit="u", source="golden"),
           make_row("fake", "t1", "b (mean 2.5 px)", paper=1, formula=None, measured=1, unit="u", source="golden")]
    monkeypatch.setattr(report, "_load", lambda name: lambda **kw: (two, []))
    run_report("fake", out_dir=tmp_path)
    # the label's decimal changes: the same row
    two[1] = {**two[1], "quantity": "b (mean 3.7 px)"}
    run_report("fake", out_dir=tmp_path)
    before = (tmp_path / "fake.md").read_text()
    monkeypatch.setattr(report, "_load", lambda name: lambda **kw: (two[:1], []))
    with pytest.raises(RasterhwError, match=r"report fake would drop 1 row.*t1 / b"):
        run_report("fake", out_dir=tmp_path)
    assert (tmp_path / "fake.md").read_text() == before


def test_an_unmeasured_row_stays_with_its_reason(tmp_path, monkeypatch):
    from rasterhw.sim.report import rows as report

    rows = [make_row("fake", "t1", "a", paper=1, formula=None, measured=None, unit="u",
                     source="hdl:yosys", reason="no time")]
    monkeypatch.setattr(report, "_load", lambda name: lambda **kw: (rows, []))
    run_report("fake", out_dir=tmp_path)
    text = (tmp_path / "fake.md").read_text()
    assert "| fake | t1 | a | 1 | — | — |" in text and "t1 / a: no time" in text
    with pytest.raises(ValueError, match="say why"):
        make_row("fake", "t1", "a", paper=1, formula=None, measured=None, unit="u", source="golden")
