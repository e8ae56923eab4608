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
