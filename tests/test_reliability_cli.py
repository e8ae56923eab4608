"""Issue 33: command-line checks (high 4: prove --depth; medium and low: tracebacks and values
that changed nothing), each one line ``error: ...`` with exit status 2, no traceback, no stray
process."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from test_reliability import (
    one_line_error,  # the one check of a one-line error (tests/ is on the path)
)

PY = sys.executable


def run(*args, cwd=None, timeout=300):
    return subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


@pytest.mark.parametrize("depth", ["-3", "0"])
def test_prove_depth_below_one_is_refused(depth):
    r = run("prove", "zbm-merger", "--depth", depth)
    one_line_error(r, contains="--depth must be")
    assert "PASS" not in r.stdout


def _descendants(pid):
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [int(k) for k in out] + [g for k in out for g in _descendants(int(k))]


def _cmd(pid):
    try:
        return open(f"/proc/{pid}/cmdline").read()
    except OSError:
        return ""


def _alive(pid):
    try:
        return open(f"/proc/{pid}/stat").read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.heavy
def test_sigterm_during_prove_leaves_no_solver_running(tmp_path):
    env = dict(os.environ, RASTERHW_BUILD=str(tmp_path / "build"))
    p = subprocess.Popen([PY, "-m", "rasterhw.sim.cli.main", "prove", "zbm-merger", "--fresh"], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    kids, t0 = [], time.time()
    while time.time() - t0 < 120 and p.poll() is None:   # until SymbiYosys has started its solvers
        kids = _descendants(p.pid)
        if any("yices" in _cmd(k) for k in kids):
            break
        time.sleep(0.1)
    assert p.poll() is None and kids, "the proof ended before it could be interrupted"
    time.sleep(0.5)
    kids = set(kids) | set(_descendants(p.pid))
    p.send_signal(signal.SIGTERM)
    p.communicate(timeout=60)
    deadline = time.time() + 15          # a loaded machine: the children's SIGTERM/SIGKILL take a moment
    while [k for k in kids if _alive(k)] and time.time() < deadline:
        time.sleep(0.2)
    assert not [(k, _cmd(k)) for k in kids if _alive(k)]


@pytest.mark.parametrize("args,contains", [
    (("soak", "--seed", "-1", "--pixels", "10"), "--seed must be"),
    (("soak", "--pixels", "0"), "--pixels must be"),
    (("bench", "--repeat", "0", "--no-hdl"), "--repeat must be"),
    (("verilog", "pixelbus", "-p", "width=99999999999999999999999", "-o", "w.v"), "too large"),
    (("sim", "pixelbus", "--size", "1x1", "--engine", "pysim", "-o", "a.png"), "smaller than"),
    (("render", "c50", "--z-bits", "1", "--size", "16x16", "-o", "z.png"), "--z-bits changes no image"),
    (("render", "c50", "--arch", "vz1", "--z-bits", "24", "--size", "16x16", "-o", "z.png"), "--z-bits"),
    (("synth", "--small", "zbm-merger"), "--small applies only with --all"),
    (("render", "c50", "-o", "x.xbm", "--size", "16x16"), "cannot hold an RGB image"),
    (("render", "c50", "-o", "x.ico", "--size", "300x300"), "at most 256x256"),
    (("render", "c50", "--arch", "experts", "--sn", "0", "--size", "32x32", "-o", "e.png"), "--sn must be"),
    (("render", "c50", "--arch", "experts", "--sn", "-1", "--size", "32x32", "-o", "e.png"), "--sn must be"),
    (("render", "c50", "--arch", "experts", "--sn", "33", "--size", "32x32", "-o", "e.png"), "32 lines"),
    (("render", "c50", "--arch", "experts", "--pn", "0", "--size", "32x32", "-o", "e.png"), "--pn must be"),
    (("sim", "pxp", "--scene", "c50", "--sn", "0", "--size", "32x16", "--engine", "pysim"), "parts must be"),
    (("render", "c50", "--arch", "experts", "--size", "1024x1024", "-o", "e.png"), "at most 1023 px a side"),
    (("render", "c50", "--arch", "vz2", "--eps", "0.01", "--size", "16x16", "-o", "v.png"), "shadow map's"),
    (("render", "c50", "--arch", "vz2", "--shadows", "map", "--eps", "1e300", "--size", "16x16", "-o", "v.png"),
     "number in (0, 1)"),
])
def test_bad_values_are_one_line_errors(tmp_path, args, contains):
    r = run(*args, cwd=tmp_path)
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert "Traceback" not in r.stderr and "Warning" not in r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith("error: ") and contains in r.stderr
    assert not [p for p in tmp_path.iterdir() if p.suffix in (".png", ".v", ".xbm", ".ico")]


BACK = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\n"   # clockwise as the framing camera sees it


@pytest.mark.parametrize("args", [
    ("render", "--arch", "vz1"), ("render", "--arch", "vz2"), ("render", "--arch", "experts"),
    ("sim", "pxp", "--engine", "pysim", "--scene"),
])
def test_scene_with_nothing_facing_the_camera_gives_a_blank_frame_everywhere(tmp_path, args):
    from PIL import Image

    (tmp_path / "back.obj").write_text(BACK)
    cmd = [args[0], "back.obj", *args[1:]] if args[0] == "render" else [*args, "back.obj"]
    r = run(*cmd, "--size", "24x24", "-o", "b.png", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr and "warning: nothing drawn" in r.stderr
    assert not np.asarray(Image.open(tmp_path / "b.png")).any()


def test_sim_output_of_a_block_without_a_frame_is_refused_not_silently_skipped(monkeypatch, tmp_path):
    from click.testing import CliRunner
    from rasterhw.sim import registry
    from rasterhw.sim.cli import main as cli

    real = registry.load

    def fake_load(ref):
        if ref == registry.sim_blocks()["pxp"][1].simulate:
            return lambda *a, **k: {"mismatches": 0}     # a run that gives no frame_rgb
        return real(ref)

    monkeypatch.setattr(registry, "load", fake_load)
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(cli.cli, ["sim", "pxp", "--engine", "pysim", "--size", "24x24", "-o", "x.png"])
    assert isinstance(r.exception, cli.RasterhwError) and "gives no frame image" in str(r.exception)


def test_sim_output_refused_before_any_run_where_the_options_give_no_frame(monkeypatch, tmp_path):
    """sim sparse --no-coupled gives no frame image: -o is refused before anything is simulated
    (it simulated for 19 s, then exited 2, before)."""
    from click.testing import CliRunner
    from rasterhw.sim import registry
    from rasterhw.sim.cli import main as cli

    real = registry.load

    def fake_load(ref):
        if ref == registry.sim_blocks()["sparse"][1].simulate:
            raise AssertionError("simulated before the -o check")
        return real(ref)

    monkeypatch.setattr(registry, "load", fake_load)
    r = CliRunner().invoke(cli.cli, ["sim", "sparse", "--no-coupled", "-o", str(tmp_path / "no" / "x.png"),
                                     "--json"])
    assert isinstance(r.exception, cli.RasterhwError), r.exception
    assert "--no-coupled gives no frame image" in str(r.exception)
    assert not (tmp_path / "no").exists()


def test_failed_demo_leaves_no_empty_folder(tmp_path):
    r = run("demo", "--out", "newout", "--scene", "no-such-scene", cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert not (tmp_path / "newout").exists()


def test_ctrl_c_during_a_pysim_run_prints_one_line(tmp_path):
    """Ctrl-C mid-simulation: "aborted" and nothing after it (the simulation's coroutines,
    closed at exit, printed "Exception ignored ... RuntimeError" tracebacks)."""
    p = subprocess.Popen([PY, "-m", "rasterhw.sim.cli.main", "sim", "pxp", "--size", "32x32", "--engine", "pysim",
                          "-o", "q.png"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = ""                              # the progress bar redraws with \r: read until the HDL step starts
    while "HDL simulation" not in seen:
        ch = p.stderr.read(1)
        assert ch, seen                    # the run ended before it simulated
        seen += ch
    time.sleep(2.0)
    p.send_signal(signal.SIGINT)
    _out, err = p.communicate(timeout=120)
    assert p.returncode == 130, (p.returncode, err)
    lines = [ln for ln in re.split(r"[\r\n]", seen + err) if ln.strip()]
    assert lines[-1] == "aborted", err                 # nothing after it: no "Exception ignored" tracebacks
    assert all(ln.startswith("pxp pysim:") for ln in lines[:-1]), err   # before it, only the progress bar
    assert not (tmp_path / "q.png").exists()


def test_report_fpga_runs_place_and_route_only_when_asked(monkeypatch, tmp_path):
    from click.testing import CliRunner
    from rasterhw.sim.cli import main as cli
    from rasterhw.sim.report import rows

    calls = []
    monkeypatch.setattr(rows, "run_report", lambda name, **kw: calls.append((name, kw)) or [])
    monkeypatch.setattr(rows, "format_table", lambda r: "")
    for args in (["fpga"], ["fpga", "--rerun"], ["all"]):
        r = CliRunner().invoke(cli.cli, ["report", *args, "--out", str(tmp_path)])
        assert r.exit_code == 0, r.output
    fpga = [kw for name, kw in calls if name == "fpga"]
    # without --rerun the rows are the record's alone (issue 53: no Verilog, no tool runs)
    assert [kw.get("records_only") for kw in fpga] == [True, False, True]
    assert all("records_only" not in kw and "cached_only" not in kw for name, kw in calls if name != "fpga")
    r = CliRunner().invoke(cli.cli, ["report", "snu", "--rerun", "--out", str(tmp_path)])
    assert isinstance(r.exception, cli.RasterhwError)


def test_verilog_too_big_for_memory_is_one_line_not_an_oom_kill(tmp_path):
    env = dict(os.environ, RASTERHW_MEMORY_LIMIT="1200M")
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "verilog", "pixelbus", "-p", "width=100000",
                        "-p", "height=100000", "-p", "ram=memory", "-o", "pb.v"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    one_line_error(r, contains="more memory than there is")
    assert not (tmp_path / "pb.v").exists()
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "verilog", "zbm-merger", "-o", "m.v"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "module" in (tmp_path / "m.v").read_text()


def test_a_big_mesh_says_what_is_going_on_before_the_silence(tmp_path):
    """On a terminal, loading a big mesh and rendering a big scene print a line first (the
    thresholds are lowered here so a small file stands for a big one)."""
    import pty

    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    script = ("import sys\nfrom rasterhw.sim.cli import main as m\nm._BIG_MESH_BYTES = 10\n"
              "m._BIG_SCENE_POLYGONS = 0\nsys.argv = ['rasterhw', 'render', 'm.obj', '--size', '16x16', '-o', 'm.png']\n"
              "m.main()\n")
    master, slave = pty.openpty()
    p = subprocess.Popen([PY, "-c", script], cwd=tmp_path, stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    p.wait(timeout=300)
    err = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        err += chunk
    os.close(master)
    text = err.decode(errors="replace")
    assert p.returncode == 0, text
    assert "loading m.obj" in text and "1 polygons; transforming and rendering" in text


@pytest.mark.heavy
def test_synth_memory_map_says_when_there_is_nothing_to_map(tmp_path):
    """Issue 33 (low): `synth --memory map` on a block with no memories used to give the keep
    netlist without a word; it says so, and counts what it maps where there is something."""
    r = run("synth", "pixelbus-bank", "-p", "depth=64", "-p", "ram=verilog", "--memory", "map", cwd=tmp_path,
            timeout=900)
    assert r.returncode == 0, r.stderr
    assert "nothing to map: the block has no memories" in r.stdout
    r = run("synth", "zbm-merger", "-p", "fifo_depth=4", "--memory", "map", "--json", cwd=tmp_path, timeout=900)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["memories_mapped"] >= 1
