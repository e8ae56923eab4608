"""The version names its commit (issue 53 item 5, sim/version.py): ``rasterhw --version`` in a
checkout, every ``--json`` document (tests/test_json_style.py), the header of generated Verilog
(tests/test_verilog_header.py); the wheel carries the version it was built as (tests/test_wheel.py)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from rasterhw import __version__
from rasterhw.sim.version import commit, git_version, version

ROOT = Path(__file__).resolve().parents[1]


def _head() -> str | None:
    if not (ROOT / ".git").exists():
        return None
    r = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short=10", "HEAD"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else None


def test_version_in_a_checkout_names_the_commit():
    head = _head()
    if head is None:
        pytest.skip("not a git checkout")
    r = subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", "--version"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    m = re.fullmatch(r"rasterhw, version (\S+)\n", r.stdout)
    assert m and m.group(1) == version(), r.stdout
    assert re.fullmatch(rf"{re.escape(__version__)}\+g{head}(\.dirty)?", version())
    assert commit() == head


def test_no_git_no_commit(tmp_path):
    """A tarball without .git (and a folder that is no work tree) gives the release alone."""
    assert git_version(tmp_path, "1.2.3") is None
    (tmp_path / ".git").write_text("gitdir: /nonexistent\n")   # a broken work tree: still no commit, no error
    assert git_version(tmp_path, "1.2.3") is None
