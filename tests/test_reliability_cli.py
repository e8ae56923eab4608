"""Issue 33: command-line checks (high 4: prove --depth; medium and low: tracebacks and values
that changed nothing), each one line ``error: ...`` with exit status 2, no traceback, no stray
process."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

PY = sys.executable


def run(*args, cwd=None, timeout=300):
    return subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


def one_line_error(r, contains=""):
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert contains in lines[0], lines[0]
    return lines[0]


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
    time.sleep(0.5)
    assert not [k for k in kids if _alive(k)]
