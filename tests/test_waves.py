"""Waves on request (``rasterhw sim ... --waves``): written when asked, never by default."""

from __future__ import annotations

import json

from rasterhw.sim.cli import main

ARGS = ["sim", "pixelbus", "--scene", "experts-solid-5", "--size", "40x16", "--engine", "pysim", "--json"]


def _run(argv) -> int:
    try:
        main(argv)
    except SystemExit as e:
        return e.code or 0
    return 0


def test_waves_written_on_request_only(tmp_path, capsys):
    vcd = tmp_path / "run.vcd"
    assert _run([*ARGS, "-o", str(tmp_path / "a.png"), "--waves", str(vcd)]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["waves"] == [str(vcd)] and res["mismatches"] == 0
    text = vcd.read_text()
    assert "$enddefinitions" in text and "$var" in text
    assert _run([*ARGS, "-o", str(tmp_path / "b.png")]) == 0
    res = json.loads(capsys.readouterr().out)
    assert "waves" not in res
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "b.png", "run.vcd"]


def test_pysim_waves_must_be_vcd(tmp_path, capsys):
    assert _run([*ARGS, "--waves", str(tmp_path / "run.fst")]) == 2
    assert "writes VCD" in capsys.readouterr().err
