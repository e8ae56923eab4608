"""Waves on request (``rasterhw sim ... --waves``): written when asked, never by default."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from wave_helpers import counter_verilog, run_cli

ARGS = ["sim", "pixelbus", "--scene", "experts-solid-5", "--size", "40x16", "--engine", "pysim", "--json"]




def test_waves_written_on_request_only(tmp_path, capsys):
    vcd = tmp_path / "run.vcd"
    assert run_cli([*ARGS, "-o", str(tmp_path / "a.png"), "--waves", str(vcd)]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["waves"] == [str(vcd)] and res["mismatches"] == 0
    text = vcd.read_text()
    assert "$enddefinitions" in text and "$var" in text
    assert run_cli([*ARGS, "-o", str(tmp_path / "b.png")]) == 0
    res = json.loads(capsys.readouterr().out)
    assert "waves" not in res
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "b.png", "run.gtkw", "run.vcd"]


def test_pysim_waves_must_be_vcd(tmp_path, capsys):
    assert run_cli([*ARGS, "--waves", str(tmp_path / "run.fst")]) == 2
    assert "writes VCD" in capsys.readouterr().err


COUNTER = counter_verilog("tb_wave_count", 19)


@pytest.mark.cocotb
def test_plain_verilator_run_writes_a_trace_on_request_only(tmp_path):
    """A plain-Verilator model (the scene runs' path) built and run inside ``recording`` writes a
    VCD through the shared C++ main, numbered per run; outside it, the untraced model runs."""
    from rasterhw.sim.engines.runner import build_plain_verilator, run_plain_verilator
    from rasterhw.sim.engines.waves import recording

    src = tmp_path / "tb_wave_count.v"
    src.write_text(COUNTER + f"// {tmp_path}\n")   # a fresh build folder per test run
    vcd = tmp_path / "w" / "run.vcd"
    with recording(vcd, "verilator") as traces:
        for _ in range(2):
            exe, _s = build_plain_verilator("waves-test", "tb_wave_count", [src], params={})
            meta = run_plain_verilator(exe, [], run_dir=tmp_path, maxcyc=100)
            assert meta["done"] == 1 and meta["sim_cycles"] == 20
    assert traces == [vcd, vcd.with_suffix(".1.vcd")]
    text = vcd.read_text()
    assert "$var wire 8" in text and "cycles" in text and "$enddefinitions" in text
    # two time steps per clock: 20 rising edges -> steps 0..40 in the trace
    assert "\n#40\n" in text and "\n#41\n" not in text
    assert "-trace-vcd" in exe.parent.parent.name
    plain, _s = build_plain_verilator("waves-test", "tb_wave_count", [src], params={})
    assert plain != exe and "-trace-" not in plain.parent.parent.name
    assert run_plain_verilator(plain, [], run_dir=tmp_path, maxcyc=100)["sim_cycles"] == 20
    assert sorted(p.name for p in (tmp_path / "w").iterdir()) == ["run.1.gtkw", "run.1.vcd", "run.gtkw", "run.vcd"]


@pytest.mark.cocotb
def test_sim_on_plain_verilator_writes_one_trace_per_processor(tmp_path, capsys):
    vcd = tmp_path / "sp.vcd"
    args = ["sim", "sparse", "--scene", "c50", "--size", "32x32", "--matrix", "2x2", "--engine", "verilator",
            "--no-coupled", "--json", "--waves", str(vcd)]   # no -o: sim sparse gives no frame image (issue 33)
    assert run_cli(args) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["mismatches"] == 0 and len(res["waves"]) == 4
    for w in res["waves"]:
        assert "rasterhw_bench" in Path(w).read_text()[:4000]   # the engine's bench top (ProcessorBench)


def test_fst_without_the_writer_headers_is_one_clear_error(tmp_path, capsys, monkeypatch):
    from rasterhw.sim.engines import waves

    monkeypatch.setattr(waves, "fst_writer_available", lambda: False)
    args = ["sim", "sparse", "--scene", "c50", "--size", "32x32", "--matrix", "2x2", "--engine", "verilator",
            "--waves", str(tmp_path / "sp.fst"), "-o", str(tmp_path / "sp.png")]
    assert run_cli(args) == 2
    err = capsys.readouterr().err
    assert "lz4.h" in err and ".vcd" in err
    assert list(tmp_path.iterdir()) == []
