"""Issue 47, item 5: early, clear refusals. Each case is one line ``error: ...``, exit 2, no
traceback, before the work it would have wasted (or, for ``--sn`` up to the frame's lines, a
frame instead of an IndexError)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_reliability import one_line_error

PY = sys.executable


def run(*args, cwd=None, env=None, timeout=300, **kw):
    t0 = time.monotonic()
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True, cwd=cwd,
                       env=dict(os.environ, **(env or {})), timeout=timeout, **kw)
    r.secs = time.monotonic() - t0
    return r


@pytest.mark.parametrize("sn", [420, 450, 512])
def test_experts_sn_up_to_the_frames_lines_renders(tmp_path, sn):
    """``render c50 --arch experts --sn 420 --size 512x512`` ended in an IndexError
    (golden_model/experts/parallel.py:163: the load-balanced bands' last bound was pushed past the
    frame's last line)."""
    r = run("render", "c50", "--arch", "experts", "--sn", str(sn), "--size", "512x512", "-o", "e.png", cwd=tmp_path)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0, 1e6), min_size=1, max_size=80), st.data())
def test_load_balanced_bands_always_cover_the_frame(load, data):
    from rasterhw.golden_model.experts.parallel import _bands_from_load

    sn = data.draw(st.integers(1, len(load)))
    b = _bands_from_load(np.asarray(load), sn)
    assert b[0] == 0 and b[-1] == len(load) and len(b) == sn + 1 and np.all(np.diff(b) > 0)


def test_verilog_size_is_estimated_before_elaboration(tmp_path):
    """Grew to 15.6 GB (85 % of the available memory) before a MemoryError."""
    r = run("verilog", "pixelbus", "-p", "width=100000", "-p", "height=100000", "-p", "ram=memory", "-o", "pb.v",
            cwd=tmp_path, timeout=120)
    one_line_error(r, contains="its memories hold")
    assert r.secs < 60 and not (tmp_path / "pb.v").exists()


def test_output_to_dev_stdout_that_is_a_pipe(tmp_path):
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", "verilog", "zbm-merger", "-o", "/dev/stdout"],
                       capture_output=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert b"module zbm_merger" in r.stdout and len(r.stdout) > 10_000


@pytest.mark.skipif(shutil.which("iverilog") is not None, reason="Icarus is installed here")
@pytest.mark.parametrize("args", [("sim", "zbm", "--scene", "c50", "--size", "32x32", "--engine", "icarus"),
                                  ("demo", "--engine", "icarus", "--out", "d"),
                                  ("report", "zbm", "--fast", "--engine", "icarus", "--out", "r")])
def test_an_engine_that_is_not_installed_is_said_first(tmp_path, args):
    r = run(*args, cwd=tmp_path)
    one_line_error(r, contains="--engine icarus")
    assert r.secs < 30 and not (tmp_path / "d").exists() and not (tmp_path / "r").exists()


@pytest.mark.parametrize("args", [("sim", "zbm", "--scene", "c50", "--size", "32x32"),
                                  ("verilog", "zbm-merger", "-o", "x.v"), ("prove", "zbm-merger"),
                                  ("synth", "zbm-merger")])
def test_an_unwritable_cache_is_said_before_any_work(tmp_path, args):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = run(*args, cwd=tmp_path, env={"RASTERHW_CACHE": str(blocker / "cache")})
    one_line_error(r, contains="cannot be written")
    assert r.secs < 30


@pytest.mark.parametrize("args,contains", [
    (("verilog", "zbm-merger", "-p", "z_bits=\u0662\u0664", "-o", "y.v"), "integer in ASCII digits"),
    (("verilog", "pixelbus", "-p", "width=0x40", "-o", "y.v"), "integer in ASCII digits"),
    (("sim", "sparse", "--matrix", "\uff12x\uff12", "--scene", "c50", "--size", "32x32", "--engine", "pysim"),
     "digits as ASCII"),
    (("prove", "zbm-merger", "--depth", "99999999999999999999"), "from 1 to 10000"),
    (("fpga", "zbm-merger", "--device", ""), "--device for ecp5 must be one of"),
    (("synth", "zbm-merger", "--store", "s"), "--store applies only with --all"),
])
def test_values_that_did_nothing_or_ran_forever_are_refused(tmp_path, args, contains):
    r = run(*args, cwd=tmp_path)
    one_line_error(r, contains=contains)
    assert r.secs < 30
