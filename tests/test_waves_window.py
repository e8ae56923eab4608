"""Waves people can open (issue 30 item 4): a GTKWave save file beside every VCD with the block's
stream ports grouped, and a trace window (``--trace-start`` / ``--trace-end``) on pysim and on
plain Verilator (the hook on Amaranth's simulator: tests/test_library_hooks.py)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from rasterhw.sim.engines import waves
from wave_helpers import counter_verilog, run_cli

ARGS = ["sim", "pixelbus", "--scene", "snu-100px", "--size", "16x16", "--engine", "pysim", "--json"]




def _gtkw_traces(gtkw: Path, *, ports_only: bool = False) -> list[str]:
    """The signal names a GTKWave save file shows (not its groups, comments, settings or the
    fields it combines from a payload's bits, ``#{...}``); ``ports_only``: those in a group."""
    out, group = [], 0
    for ln in gtkw.read_text().splitlines():
        ln = ln.strip()
        if ln.startswith("-"):
            group ^= 1
        elif ln and ln[0] not in "[@*#" and (group or not ports_only):
            out.append(ln)
    return out


def _vcd_names(vcd: Path) -> set[str]:
    """Every variable of a VCD as GTKWave names it: ``scope.name`` (without a bit range)."""
    return {".".join((*s, n.lstrip("\\"))) for s, n, *_ in waves.vcd_header(vcd)}


def _check_gtkw(vcd: Path, ports: set[str]) -> list[str]:
    gtkw = vcd.with_suffix(".gtkw")
    assert gtkw.exists(), "no .gtkw beside the VCD"
    text = gtkw.read_text()
    # the dump path relative to the save file (GTKWave reads it so beside a relative [savefile])
    assert f'[dumpfile] "{vcd.name}"' in text and f'[savefile] "{gtkw.name}"' in text
    names = _gtkw_traces(gtkw)
    have = _vcd_names(vcd)
    for n in names:   # every signal the save file names is in the trace
        assert re.sub(r"\[\d+:\d+\]$", "", n).replace(".\\", ".") in have, n
    for p in ports:   # every stream port is a group with its valid, ready and payload
        assert f"-{p}\n" in text, p
        for m in ("valid", "ready", "payload"):
            assert any(re.search(rf"\.{p}__{m}(\$\d+)?(\[|$)", n) for n in names), (p, m)
    return names


def _times(vcd: Path) -> list[int]:
    return [int(ln[1:]) for ln in vcd.read_text().splitlines() if ln.startswith("#")]


def _rising_edges(vcd: Path) -> list[int]:
    """Times of the rising edges of the trace's first ``clk``."""
    head = vcd.read_text().split("$enddefinitions", 1)[0]
    clk = re.search(r"\$var\s+\S+\s+1\s+(\S+)\s+\\?clk\s", head).group(1)   # the VCD's id code
    t, last, out = 0, "0", []
    body = vcd.read_text().split("$enddefinitions", 1)[1]
    for ln in body.splitlines():
        if ln.startswith("#"):
            t = int(ln[1:])
        elif ln[1:] == clk and ln[0] in "01":
            if ln[0] == "1" and last != "1":
                out.append(t)
            last = ln[0]
    return out


def test_pysim_gtkw_groups_the_stream_ports_and_names_only_signals_of_the_vcd(tmp_path, capsys):
    vcd = tmp_path / "run.vcd"
    assert run_cli([*ARGS, "-o", str(tmp_path / "a.png"), "--waves", str(vcd)]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["gtkw"] == [str(vcd.with_suffix(".gtkw"))]
    # Amaranth's own save file (the generic engine declared the testbench's ports)
    _check_gtkw(vcd, {"i_pipe0", "i_pipe1", "o"})
    # and ours, read from the VCD header alone, names the same ports
    own = waves.write_gtkw(vcd, tmp_path / "own.gtkw")
    _check_gtkw(vcd, set())
    text = own.read_text()
    for p in ("i_pipe0", "i_pipe1", "o"):
        assert f"-{p}\n" in text


def test_pysim_window_keeps_only_the_cycles_asked_for(tmp_path, capsys):
    full, cut = tmp_path / "full.vcd", tmp_path / "cut.vcd"
    assert run_cli([*ARGS, "-o", str(tmp_path / "a.png"), "--waves", str(full)]) == 0
    assert run_cli([*ARGS, "-o", str(tmp_path / "b.png"), "--waves", str(cut), "--trace-start", "20",
                 "--trace-end", "40"]) == 0
    capsys.readouterr()
    edges = _rising_edges(full)
    assert len(edges) > 100
    times = _times(cut)
    assert times[0] == edges[20] and max(times) < edges[40] and min(times) >= edges[20]
    assert len(_rising_edges(cut)) == 20      # edges 20..39, no more
    body = lambda p: p.stat().st_size - len(p.read_text().split("$enddefinitions")[0])   # noqa: E731
    assert body(cut) < body(full) / 4
    _check_gtkw(cut, {"i_pipe0", "i_pipe1", "o"})


def test_window_filter_on_a_small_vcd():
    import io

    head = "$timescale 1 ns $end\n$scope module top $end\n$var wire 1 ! clk $end\n$var wire 4 \" n $end\n" \
           "$upscope $end\n$enddefinitions $end\n"
    body = "#0\n$dumpvars\n0!\nb0 \"\n$end\n" + "".join(
        f"#{10 * k + 5}\n1!\nb{k + 1:b} \"\n#{10 * k + 10}\n0!\n" for k in range(10))
    out = io.StringIO()
    out.close = lambda: None
    w = waves.VcdWindow(out, 3, 6)
    text = head + body
    for i in range(0, len(text), 7):      # written in pieces, as pyvcd does
        w.write(text[i:i + 7])
    w.close()
    got = out.getvalue()
    assert got.startswith(head)
    rest = got[len(head):]
    # edge 3 at t=35: every value at once, then the changes up to t=60 (falling edge of edge 5)
    assert rest.startswith("#35\n$dumpvars\n1!\nb100 \"\n$end\n")
    assert [int(t) for t in re.findall(r"^#(\d+)$", rest, re.M)] == [35, 40, 45, 50, 55, 60]
    assert w.edges == 10 and w.opened


@pytest.mark.parametrize("extra, says", [
    (["--trace-start", "-1"], "--trace-start must be a cycle number 0 or more"),
    (["--trace-end", "-3"], "--trace-end must be a cycle number 0 or more"),
    (["--trace-start", "10", "--trace-end", "10"], "--trace-end 10 must be after --trace-start 10"),
    (["--trace-start", "10", "--trace-end", "4"], "must be after"),
    (["--trace-end", "0"], "must be after --trace-start 0"),
    (["--trace-start", "3", "--no-waves"], "need --waves"),
])
def test_bad_window_is_one_line_exit_2(tmp_path, extra, says):
    args = [*ARGS, "-o", str(tmp_path / "a.png")]
    if "--no-waves" in extra:
        extra = [e for e in extra if e != "--no-waves"]
    else:
        args += ["--waves", str(tmp_path / "w.vcd")]
    r = subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", *args, *extra], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and says in lines[0], r.stderr
    assert list(tmp_path.iterdir()) == []   # refused before any work


def test_window_past_the_end_of_the_run_is_one_clear_error(tmp_path, capsys):
    assert run_cli([*ARGS, "-o", str(tmp_path / "a.png"), "--waves", str(tmp_path / "w.vcd"),
                 "--trace-start", "100000"]) == 2
    assert "the run ended after" in capsys.readouterr().err


COUNTER = counter_verilog("tb_wave_window", 39)


@pytest.mark.cocotb
def test_plain_verilator_main_opens_and_closes_the_trace_at_the_window(tmp_path):
    """The shared C++ main dumps only edges start .. end-1 (steps 2k+1, 2k+2) when given the window."""
    from rasterhw.sim.engines.runner import build_plain_verilator, run_plain_verilator
    from rasterhw.sim.engines.waves import recording

    src = tmp_path / "tb_wave_window.v"
    src.write_text(COUNTER)
    full, cut = tmp_path / "full.vcd", tmp_path / "cut.vcd"
    for path, window in ((full, {}), (cut, {"start": 10, "end": 25})):
        with recording(path, "verilator", **window):
            exe, _s = build_plain_verilator("waves-window-test", "tb_wave_window", [src], params={})
            assert run_plain_verilator(exe, [], run_dir=tmp_path, maxcyc=1000)["sim_cycles"] == 40
    assert _times(full)[0] == 0 and max(_times(full)) == 80
    t = _times(cut)
    assert min(t) == 21 and max(t) == 50          # edge 10's rising step .. edge 24's falling step
    assert cut.stat().st_size < full.stat().st_size
    assert cut.with_suffix(".gtkw").exists()      # a VCD always gets its save file
    # the first step in the window carries every value: the counter stands at 10 after edge 10
    first = cut.read_text().split("#21\n", 1)[1].split("#22", 1)[0]
    assert "b00001011 " in first or "b1011 " in first


@pytest.mark.cocotb
def test_verilator_engine_gtkw_names_the_bench_blocks_stream_ports(tmp_path):
    """The generic Verilator engine on ``pixelbus-bank``: the save file groups the block's ``i`` and
    ``o`` (and nothing the block only names like a stream inside), every signal is in the VCD."""
    from rasterhw.sim import engines
    from rasterhw.sim.engines.waves import recording
    from rasterhw.sim.testbench import compare, find_testbench

    tb = find_testbench("pixelbus-bank")
    p = tb.params(depth=16)
    stim = tb.stimulus(p, seed=3)
    exp = tb.expect(p, stim)
    vcd = tmp_path / "bank.vcd"
    with recording(vcd, "verilator", start=5, end=30) as traces:
        got = engines.run(tb, p, stim, engine="verilator", expect_words={k: len(v) for k, v in exp.words.items()})
    assert compare(exp, got)["mismatches"] == 0
    assert traces == [vcd]
    _check_gtkw(vcd, {"i", "o"})
    names = _gtkw_traces(vcd.with_suffix(".gtkw"), ports_only=True)
    # the bench's nets named like the block's ports are the block's ports: the same VCD nets
    ids = {".".join((*s, n)): i for s, n, w, r, i in waves.vcd_header(vcd)}
    dut_ids = {i for s, n, w, r, i in waves.vcd_header(vcd) if s[-1:] == ("dut",)}
    assert names and all(ids[re.sub(r"\[\d+:\d+\]$", "", n)] in dut_ids for n in names)
    assert min(_times(vcd)) == 11 and max(_times(vcd)) <= 60


@pytest.mark.cocotb
def test_plain_verilator_trace_named_relative_lands_in_the_current_folder(tmp_path, monkeypatch):
    """The binary runs in its own run folder: ``--waves run.vcd`` still means ./run.vcd (it used to
    be written into the run folder and removed with it)."""
    from rasterhw.sim.engines.runner import build_plain_verilator, run_plain_verilator
    from rasterhw.sim.engines.waves import recording

    src = tmp_path / "tb_wave_window.v"
    src.write_text(COUNTER)
    (tmp_path / "here").mkdir()
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "here")
    with recording("run.vcd", "verilator") as traces:
        exe, _s = build_plain_verilator("waves-window-test", "tb_wave_window", [src], params={})
        run_plain_verilator(exe, [], run_dir=tmp_path / "elsewhere", maxcyc=1000)
    assert traces == [Path("run.vcd")]
    assert (tmp_path / "here" / "run.vcd").exists() and (tmp_path / "here" / "run.gtkw").exists()
    assert not list((tmp_path / "elsewhere").iterdir())
