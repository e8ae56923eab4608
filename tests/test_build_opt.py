"""The test suite's optimisation level for Verilator builds (sim/engines/runner.py: effective_opt,
set by tests/conftest.py): it replaces only the default -O2, never a profile-guided build's level,
is part of every build's key, and a bad value is one clear error."""

from __future__ import annotations

from pathlib import Path

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import runner

SRC = Path(__file__).parent / "wave_helpers.py"   # any file: only the key is computed here


def test_the_level_replaces_only_the_default(monkeypatch):
    monkeypatch.delenv(runner.OPT_ENV, raising=False)
    assert runner.effective_opt("-O2") == "-O2" and runner.effective_opt("-O0") == "-O0"
    monkeypatch.setenv(runner.OPT_ENV, "-O1")
    assert runner.effective_opt("-O2") == "-O1" and runner.effective_opt("-O0") == "-O0"
    monkeypatch.setenv(runner.OPT_ENV, "-O9")
    with pytest.raises(RasterhwError, match="RASTERHW_VERILATOR_OPT must be one of"):
        runner.effective_opt("-O2")


def test_the_level_is_in_the_build_key(monkeypatch):
    kw = dict(params={}, opt="-O2")
    monkeypatch.delenv(runner.OPT_ENV, raising=False)
    plain_o2 = runner.plain_build_dir("t", "tb_t", [SRC], **kw)
    cocotb_o2 = runner.build_dir_for("t", "verilator", sources=[SRC])
    monkeypatch.setenv(runner.OPT_ENV, "-O1")
    assert runner.plain_build_dir("t", "tb_t", [SRC], **kw) != plain_o2
    assert runner.plain_build_dir("t", "tb_t", [SRC], params={}, opt="-O1") == \
        runner.plain_build_dir("t", "tb_t", [SRC], **kw)          # -O1 asked or given: one build
    assert runner.build_dir_for("t", "verilator", sources=[SRC]) != cocotb_o2


def test_speed_builds_carry_their_flags_and_the_host_cpu_in_their_key(monkeypatch, tmp_path):
    """A profile-guided build (instrumented or optimised) gets SPEED_CFLAGS (-march=native where the
    compiler takes it, -flto, gcc-ar); a plain build does not; what -march=native means on this host
    is part of the key (a build cache shared with another CPU builds its own), and a compiler
    without -march=native gets the rest of the flags."""
    (tmp_path / "x.gcda").write_bytes(b"profile")

    def plan(pgo):
        return runner._plain_plan("t", "tb_t", [SRC], params={}, opt="-O2", defines=None, generated=None, pgo=pgo)

    native = bool(runner.native_target())
    for pgo in ("generate", tmp_path):
        make = plan(pgo)[2]
        assert ("-march=native" in make) == native and "-flto=2" in make and "AR=gcc-ar" in make
    plain = plan(None)[2]
    assert "-march" not in plain and "-flto" not in plain and "AR=" not in plain
    gen, use = plan("generate")[1], plan(tmp_path)[1]
    monkeypatch.setattr(runner, "native_target", lambda: "another cpu")
    assert plan("generate")[1] != gen and plan(tmp_path)[1] != use
    monkeypatch.setattr(runner, "native_target", lambda: "")
    make = plan("generate")[2]
    assert "-march=native" not in make and "-flto=2" in make
