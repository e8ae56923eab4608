"""Issue 33, high 1: a Verilator build is all or nothing. An interrupted build (Ctrl-C, SIGTERM,
a kill mid-compile) leaves no folder the next build would trust, and the next build succeeds;
the build folder of an installed (non-editable) package is not inside site-packages."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from rasterhw.sim.engines import runner
from rasterhw.sim.engines.vlruntime import cache_dir

PY = sys.executable
COUNTER = """module tb_rel_count (input clk, output reg done, output reg [31:0] cycles);
  initial begin done = 0; cycles = 0; end
  always @(posedge clk) begin
    cycles <= cycles + 1;
    if (cycles >= 40) done <= 1;
  end
endmodule
// {tag}
"""


def _counter(tmp_path: Path) -> Path:
    src = tmp_path / "tb_rel_count.v"
    src.write_text(COUNTER.format(tag=tmp_path))   # a build folder of its own per test run
    return src


def _runs(exe: Path) -> None:
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["done"] == 1 and out["cycles"] >= 40


def test_a_folder_without_a_finished_build_is_rebuilt_not_trusted(tmp_path, monkeypatch):
    """What an interrupted link leaves: a half-written binary and no build record. It is
    removed and built again (before the fix the half-written binary was returned)."""
    monkeypatch.setattr(runner, "BUILD_ROOT", tmp_path / "build")
    src = _counter(tmp_path)
    exe, secs = runner.build_plain_verilator("rel-count", "tb_rel_count", [src], params={},
                                             defines={"RASTERHW_CYCLES": 1}, opt="-O0")
    _runs(exe)
    bdir = exe.parent.parent
    (bdir / "build.json").unlink()
    exe.write_bytes(b"\x7fELF half a binary")
    (exe.parent / "Vtb_rel_count__pch.h.fast.gch").write_bytes(b"garbage")
    exe2, secs2 = runner.build_plain_verilator("rel-count", "tb_rel_count", [src], params={},
                                               defines={"RASTERHW_CYCLES": 1}, opt="-O0")
    assert exe2 == exe and secs2 > 0
    _runs(exe2)
    assert sorted(p.name for p in bdir.parent.iterdir()) == [bdir.name, f"{bdir.name}.lock"]


SCRIPT = """
import signal, sys
from pathlib import Path
from rasterhw.sim.cli import main as cli
from rasterhw.sim.engines import runner
signal.signal(signal.SIGTERM, cli._terminate)
exe, s = runner.build_plain_verilator("rel-count", "tb_rel_count", [Path({src!r})], params={{}},
                                      defines={{"RASTERHW_CYCLES": 1}}, opt="-O0")
print(exe, flush=True)
"""


def _descendants(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    kids = [int(k) for k in out]
    return kids + [g for k in kids for g in _descendants(k)]


def _interrupt_in_compile(cmd: list[str], env: dict, build: Path, work_glob: str, sig, delay: float,
                          wait_s: float) -> tuple[subprocess.Popen, str]:
    """Start ``cmd``, wait until its compiler runs (a work folder matching ``work_glob`` under
    ``build`` with an ``obj_dir/*.mk``), wait ``delay`` seconds more, send ``sig``; then check
    that none of its processes survived. Gives the process and its stderr."""
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while not list(build.glob(f"{work_glob}/obj_dir/*.mk")) and time.time() - t0 < wait_s and p.poll() is None:
        time.sleep(0.05)
    time.sleep(delay)
    kids = _descendants(p.pid)
    p.send_signal(sig)
    _out, err = p.communicate(timeout=120)
    time.sleep(0.3)
    left = [k for k in kids if os.path.exists(f"/proc/{k}") and open(f"/proc/{k}/stat").read().split()[2] != "Z"]
    assert not left, f"processes survived {sig.name}: {left}"
    return p, err


@pytest.mark.cocotb
@pytest.mark.heavy
def test_interrupted_cold_build_then_the_same_build_succeeds(tmp_path):
    """SIGINT and SIGTERM at seeded random points of a cold build; nothing is left behind
    (no work folder, no process), and the same build then succeeds. The runtime objects are
    not shared (a cold build compiles the whole Verilator runtime: ~10 s to interrupt in)."""
    src = _counter(tmp_path)
    build = tmp_path / "build"
    env = dict(os.environ, RASTERHW_BUILD=str(build), RASTERHW_VL_RUNTIME="0")
    script = textwrap.dedent(SCRIPT.format(src=str(src)))
    rng = random.Random(33)
    for sig in (signal.SIGINT, signal.SIGTERM):
        # the compiler runs (a work folder with an obj_dir), then a random moment more
        p, _err = _interrupt_in_compile([PY, "-c", script], env, build, ".rel-count-*.tmp-*", sig,
                                        rng.uniform(0.5, 4.0), 120)
        assert p.returncode != 0, "the build finished before the signal: nothing was interrupted"
        assert not list(build.glob(".rel-count-*")), f"a work folder was left by {sig.name}"
        assert not [d for d in build.glob("rel-count-*") if d.is_dir()], "an unfinished build folder was left"
    r = subprocess.run([PY, "-c", script], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    _runs(Path(r.stdout.strip().splitlines()[-1]))


def test_build_root_is_the_checkout_or_a_user_cache(monkeypatch, tmp_path):
    from rasterhw.sim import paths

    monkeypatch.delenv("RASTERHW_BUILD", raising=False)
    monkeypatch.delenv("RASTERHW_CACHE", raising=False)
    assert paths.build_root() == paths.REPO_ROOT / "build"        # this checkout (editable)
    monkeypatch.setenv("RASTERHW_BUILD", str(tmp_path / "b"))
    assert paths.build_root() == (tmp_path / "b").resolve()
    monkeypatch.setenv("RASTERHW_CACHE", str(tmp_path / "c"))      # the name issue 30 asks for wins
    assert paths.build_root() == (tmp_path / "c").resolve()
    monkeypatch.delenv("RASTERHW_CACHE")
    # an installed package: no pyproject.toml beside it -> the user's cache folder, never site-packages
    monkeypatch.delenv("RASTERHW_BUILD")
    fake = tmp_path / "site-packages" / "rasterhw"
    fake.mkdir(parents=True)
    monkeypatch.setattr(paths, "REPO_ROOT", fake)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    root = paths.build_root()
    assert fake not in (root, *root.parents)
    assert root == tmp_path / "cache" / "rasterhw"


def test_every_cache_goes_under_the_build_root():
    from rasterhw.sim.paths import BUILD_ROOT

    d = runner.build_dir_for("pixelbus", "verilator", width=4)
    assert d.parent == BUILD_ROOT
    assert BUILD_ROOT in cache_dir("plain", []).parents or "RASTERHW_VL_RUNTIME_DIR" in os.environ


def test_interrupted_cocotb_build_restarts_without_its_outputs(tmp_path, monkeypatch):
    """cocotb builds go into a folder that also holds the generated source and run folders: an
    interrupted build's outputs (objects, precompiled headers) are removed before the next
    build, the source and run folders are kept."""
    import cocotb_tools.runner as ct
    from rasterhw.golden_model.errors import RasterhwError

    bdir = tmp_path / "b"
    bdir.mkdir()
    src = bdir / "top.v"
    src.write_text("module top; endmodule\n")
    (bdir / "run-x").mkdir()
    seen = []

    class Fake:
        def build(self, build_dir, **kw):
            seen.append(sorted(p.name for p in Path(build_dir).iterdir()))
            if len(seen) == 1:
                (Path(build_dir) / "Vtop__pch.h.fast.gch").write_bytes(b"half")
                raise KeyboardInterrupt
            raise RuntimeError("Command failed with return code: 2")

    monkeypatch.setattr(ct, "get_runner", lambda sim: Fake())
    with pytest.raises(KeyboardInterrupt):
        runner.run_cocotb(sources=[src], toplevel="top", test_module="x", build_dir=bdir, sim="verilator")
    with pytest.raises(RasterhwError, match="build failed"):
        runner.run_cocotb(sources=[src], toplevel="top", test_module="x", build_dir=bdir, sim="verilator")
    assert "Vtop__pch.h.fast.gch" not in seen[1]
    assert {"top.v", "run-x"} <= set(seen[1])


@pytest.mark.cocotb
@pytest.mark.heavy(2)
def test_interrupted_cold_sim_then_the_same_command_passes(tmp_path):
    """The probe's case: ``rasterhw sim zbm ... --engine verilator`` interrupted (SIGINT, then
    SIGTERM) during its cold build, then run again: it builds, passes (0 mismatches), and the
    build folder holds only finished builds. Generated Verilog and the Verilator runtime come
    from the shared caches (the interruption is in the model's own compile)."""
    build = tmp_path / "build"
    # RASTERHW_PGO=0: the -O1 build alone, as before sim zbm trained a gcc profile with a design's
    # first build (that path, and what it says: tests/zbm/test_zbm_build_speed.py)
    env = dict(os.environ, RASTERHW_BUILD=str(build), RASTERHW_PGO="0",
               RASTERHW_VL_RUNTIME_DIR=str(cache_dir("plain", []).parent))
    # interleave 1: the smallest unit (its model compiles in ~3.5 s here, interleave 2's in ~10 s;
    # the signal comes 0.1-1.5 s into the compile)
    cmd = [PY, "-m", "rasterhw.sim.cli.main", "sim", "zbm", "--scene", "c50", "--size", "48x40",
           "--interleave", "1", "--engine", "verilator", "-o", str(tmp_path / "z.png"), "--json"]
    rng = random.Random(1033)
    for sig in (signal.SIGINT, signal.SIGTERM):
        p, err = _interrupt_in_compile(cmd, env, build, ".*.tmp-*", sig, rng.uniform(0.1, 1.5), 300)
        assert p.returncode != 0 and "Traceback" not in err, err
        assert not list(build.glob(".*.tmp-*")) and not (tmp_path / "z.png").exists()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert res["mismatches"] == 0 and res["pixels_compared"] == 48 * 40
    models = [d.parent for d in build.glob("*/obj_dir")]
    assert models and all((d / "build.json").exists() for d in models)
