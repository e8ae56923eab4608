"""The table-2 calibration (sim/vzbuf/calibrate.py) and the report rows issue 52 asks for."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.facom import LINEAR, PARAMS, price
from rasterhw.golden_model.vzbuf.paper import RUNS
from rasterhw.golden_model.vzbuf.render import render_frame, table_stages
from rasterhw.golden_model.vzbuf.trace import Trace
from rasterhw.sim.report.rows import parse_table
from rasterhw.sim.vzbuf.calibrate import error_factors, fit, predict, stage_components, summary

W = H = 512
SCENES = ("c50", "sp8")
REPORT = Path(__file__).resolve().parents[2] / "docs" / "reproduction" / "vzbuf.md"


@pytest.fixture(scope="module")
def comps():
    out = {}
    for table in ("table 2", "table 3"):
        alg, sh = RUNS[table]
        for n in SCENES:
            tr = Trace()
            render_frame(build_scene(n), W, H, alg=alg, shadows=sh, trace=tr)
            out[(table, n)] = stage_components(tr, alg, sh)
    return out


def _tables_from(comps, theta, scale=None):
    """Paper-shaped tables ({table: {machine: {stage: {scene: ms}}}}) made by the model at theta."""
    T = {}
    for (table, n), comp in comps.items():
        for m, d in predict(comp, theta).items():
            pm = {"scalar": "scalar", "vp100": "VP100", "vp200": "VP200"}[m]
            for st, v in d.items():
                f = scale(table) if scale else 1.0
                T.setdefault(table, {}).setdefault(pm, {}).setdefault(st, {})[n] = v * f
    return T


def test_components_add_up_to_the_price(comps):
    tr = Trace()
    render_frame(build_scene("c50"), W, H, alg=1, trace=tr)
    start = {k: PARAMS[k].value for k in LINEAR}
    got = predict(stage_components(tr, 1, "none"), start)
    for m in ("scalar", "vp100", "vp200"):
        ph = price(tr, m)["phases"]
        for label, phases in table_stages(1, "none").items():
            assert got[m][label.split()[0]] == pytest.approx(1e3 * sum(ph.get(p, 0.0) for p in phases))


def test_fit_recovers_known_parameters_and_reads_table_2_only(comps):
    start = {k: PARAMS[k].value for k in LINEAR}
    true = {"scalar_clock_ns": 21.0, "startup_ns": 260.0, "fp_pipes": 5.0}
    tables = _tables_from(comps, true)
    got = fit(comps, tables, start)
    for k in LINEAR:
        assert got[k] == pytest.approx(true[k], rel=1e-5), k
    # table 3 ten times off changes nothing: only table 2 is read ...
    skewed = _tables_from(comps, true, scale=lambda t: 10.0 if t == "table 3" else 1.0)
    assert fit(comps, skewed, start) == pytest.approx(got, rel=1e-9)
    # ... and then shows as out-of-sample error, none in sample
    pred = {k: predict(c, got) for k, c in comps.items()}
    med2, _ = summary(error_factors(pred, skewed, "table 2"))
    med3, gm3 = summary(error_factors(pred, skewed, "table 3"))
    assert med2 == pytest.approx(1.0) and med3 == pytest.approx(10.0) and gm3 == pytest.approx(10.0)
    # a table-2 cell moved moves the fit
    tables["table 2"]["scalar"]["2"]["c50"] *= 3
    assert fit(comps, tables, start)["scalar_clock_ns"] > 1.01 * got["scalar_clock_ns"]


def test_error_factors_by_hand():
    pred = {("table 9", "x"): {"scalar": {"1": 2.0, "total": 2.0}, "vp200": {"1": 1.0, "total": 1.0}}}
    tables = {"table 9": {"scalar": {"1": {"x": 1.0}, "total": {"x": 4.0}}, "VP200": {"1": {"x": 1.0}, "total": {}}}}
    f = sorted(error_factors(pred, tables, "table 9"))
    assert f == [1.0, 2.0, 2.0]
    med, gm = summary(f)
    assert med == 2.0 and gm == pytest.approx(math.exp((2 * math.log(2)) / 3))


def _must_show(rows):
    """Issue 52's must-show rows, on report rows (dicts with figure, quantity, source)."""
    q = [(r["figure"], r["quantity"], r["source"]) for r in rows]
    for table in ("table 3", "table 4", "table 5", "table 6", "table 7"):
        assert any(f == table and s == "fit:table2" and ", VP200 (calibrated on table 2)" in x and ": total" in x
                   for f, x, s in q), table
        assert any(f == table and "out-of-sample error" in x and "median factor" in x and s == "fit:table2"
                   for f, x, s in q), table
    for table in ("table 2", "table 3", "table 4", "table 5", "table 6", "table 7"):
        assert any(f == table and "geometric mean model / paper" in x and s == "model:vp200" for f, x, s in q), table
    for half in ("first", "second"):
        assert any(f == "conclusions" and f"conclusion (c), {half} half" in x and s.startswith("model:")
                   for f, x, s in q), half
    # conclusions are never drawn from a fit, and each names the model it reads
    assert all(s.startswith("model:vp") for f, _x, s in q if f in ("conclusions", "sensitivity"))
    assert sum(f == "calibration" and x.startswith("fitted ") and "(bounds " in x for f, x, _s in q) == len(LINEAR)


@pytest.mark.slow
def test_report_rows_carry_the_calibration_and_the_split_conclusions(tmp_path):
    from rasterhw.sim.vzbuf.report import rows

    out, _ = rows(scenes=("c50",), out_dir=tmp_path)
    _must_show(out)
    # a fit row for every stage and total of tables 3-7, on every machine the paper has
    fits = {(r["figure"], r["quantity"]) for r in out if r["source"] == "fit:table2"}
    for table in ("table 3", "table 4", "table 5", "table 6", "table 7"):
        alg, sh = RUNS[table]
        for st in (*table_stages(alg, sh), "total"):
            assert (table, f"c50: {st}, scalar (calibrated on table 2)") in fits, (table, st)
def test_the_committed_report_carries_the_calibration_and_the_split_conclusions():
    rows = parse_table(REPORT.read_text())
    assert rows
    _must_show(rows)
    fits = {(r["figure"], r["quantity"]) for r in rows if r["source"] == "fit:table2"}
    for table in ("table 3", "table 4", "table 5", "table 6", "table 7"):
        alg, sh = RUNS[table]
        for n in ("c300", "sp8"):
            for st in (*table_stages(alg, sh), "total"):
                assert (table, f"{n}: {st}, VP200 (calibrated on table 2)") in fits, (table, n, st)
