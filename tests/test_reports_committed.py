"""Reports never shrink silently: regenerate each report's fast rows and compare them with the
committed tables in ``docs/reproduction/``.

Compared: every committed row is produced again (by ``row_key``: system, figure, quantity with
decimal numbers masked), with the same ``paper`` value and ``source``; rows from the golden
model or a formula also keep their ``formula`` value. Measured HDL numbers, timings and ratios
are not compared (they are the report's to change); slow rows (synthesis, place and route)
come back unmeasured with their reason.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.report.rows import (
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


def _compare(system: str, tmp_path: Path) -> list[dict]:
    committed = parse_table((DOCS / f"{system}.md").read_text())
    assert committed, f"no table in docs/reproduction/{system}.md"
    rows = run_report(system, out_dir=tmp_path, engine="pysim", fast=True)
    lost = missing_rows(committed, rows)
    assert not lost, f"{system}: {len(lost)} committed rows not produced, first {lost[0]}"
    by_key = {}
    for r in rows:
        by_key.setdefault(row_key(r), []).append(r)
    for c in committed:
        r = by_key[row_key(c)].pop(0)
        assert _fmt(r["paper"]) == c["paper"], (c, r)
        # an HDL row's simulator follows the engine the table was made with (this test runs pysim)
        if str(c["source"]).startswith("hdl:") and str(r["source"]).startswith("hdl:"):
            assert c["source"].split(":")[0] == r["source"].split(":")[0], (c, r)
        else:
            assert r["source"] == c["source"], (c, r)
        if r["source"] in ("golden", "formula"):
            assert _fmt(r["formula"]) == c["formula"], (c, r)
        if r["measured"] is None:
            assert r.get("reason"), r
    return rows


#: the test run's reduced configuration of a fast report (``"module.NAME": value`` set for the run):
#: the same rows come back (a row left unmeasured keeps its name, with its reason), from fewer
#: HDL runs. ZB/M, each left out run checked in every test run elsewhere:
#: - the 2-unit chain is not built (cold, its Verilog conversion, -O0 build and run took 45 s of the
#:   159 s of CPU this test took: docs/speed.md); the skew pair still runs two chained units on
#:   Verilator word for word against the golden model (``skew`` raises on a mismatch);
#: - Table 1 in pysim at interleave 2 (both schedules): tests/zbm/test_zbm_unit_pysim.py::
#:   test_line_log_steady_state_equals_model runs the same measurement against the same model;
#: - the pixel rate at interleave 2 and 4 (pysim, 128-px lines): test_pixel_rate_scales_with_interleave
#:   runs interleave 1 and 4 against the same formula.
#: Warm, those runs were most of this test's 37 s of CPU (pysim elaboration and simulation). The
#: whole fast report: the ``slow`` test below.
REDUCED = {"zbm": {"rasterhw.sim.zbm.scaling.FAST_SKIP_CHAIN": (2, 4, 8),
                   "rasterhw.sim.zbm.report.FAST_SKIP_INTERLEAVES": (2, 8, 16),
                   "rasterhw.sim.zbm.scaling.FAST_SKIP_PIXEL_RATE": (2, 4, 8, 16)}}


@pytest.mark.parametrize("system", [s for s in systems() if s not in SLOW_SYSTEMS])
@pytest.mark.heavy(3)
def test_fast_report_keeps_every_committed_row(system, tmp_path, monkeypatch):
    for name, value in REDUCED.get(system, {}).items():
        monkeypatch.setattr(name, value)
    rows = _compare(system, tmp_path)
    if system == "zbm":   # the reduced run still measures the skew pair and the 1-unit chain on Verilator
        skew = [r for r in rows if r["figure"] == "6.1 cond. 7"]
        chain = {r["quantity"].split(",")[0]: r["measured"] for r in rows
                 if r["figure"] == "6.1 (chain)" and r["quantity"].endswith("speed-up over 1 unit")}
        assert len(skew) == 2 and all(r["measured"] is not None and r["source"] == "hdl:verilator" for r in skew)
        assert chain["1 chained unit"] == 1 and chain["2 chained units"] is None
        t1 = {(r["quantity"].split(", ")[1], r["quantity"].split(", ")[2]): r["measured"] for r in rows
              if r["figure"] == "table 1 / 6.1"}
        assert all(t1[(f"interleave {i}", s)] for i in (1, 4) for s in ("paper schedule", "overlapped schedule (ours)"))
        assert t1[("interleave 2", "paper schedule")] is None


@pytest.mark.slow
@pytest.mark.parametrize("system", sorted(REDUCED))
def test_whole_fast_report_keeps_every_committed_row(system, tmp_path):
    _compare(system, tmp_path)


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
