"""Docs that run: every ```python and ```sh block of docs/*.md is executed (issue 25, item 6).

A block's fence says how it is checked (the words after the language):

- ```` ```python ```` / ```` ```sh ````: run, must exit 0, in an empty folder (``.venv/bin/`` means
  this interpreter's ``bin``);
- ``root``: run from the checkout's root (a block that names files in it: ``cd tests``);
- ``slow``: run only with ``-m slow`` (minutes: synthesis, a 100 K-polygon frame, a benchmark);
- ``norun``: commands that write committed files (``rasterhw report``) or need a shell the test
  does not have; each ``rasterhw SUBCOMMAND`` line's subcommand is checked to exist
  (``--help``).

A fence with no language is text (diagrams, output) and is not run. Generated pages
(docs/reproduction/) are not scanned.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
FENCE = re.compile(r"^```(\w+)([^\n]*)\n(.*?)^```", re.M | re.S)


def blocks():
    out = []
    for doc in sorted((ROOT / "docs").glob("*.md")):
        text = doc.read_text()
        for m in FENCE.finditer(text):
            lang, flags, body = m.group(1), set(m.group(2).split()), m.group(3)
            if lang not in ("python", "sh"):
                continue
            line = text[:m.start()].count("\n") + 1
            out.append(pytest.param(doc.name, line, lang, flags, body, id=f"{doc.name}:{line}",
                                    marks=[pytest.mark.slow] if "slow" in flags else []))
    return out


def _env():
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env.setdefault("MPLBACKEND", "Agg")
    return env


@pytest.mark.parametrize("doc,line,lang,flags,body", blocks())
def test_doc_block_runs(doc, line, lang, flags, body, tmp_path):
    where = f"docs/{doc}:{line}"
    if "norun" in flags:
        subs = [ln.split()[1] for ln in body.splitlines() if ln.strip().startswith("rasterhw ")]
        assert subs, f"{where}: a norun block with no rasterhw command to check"
        for sub in subs:
            r = subprocess.run([str(BIN / "rasterhw"), sub, "--help"], capture_output=True, text=True,
                               env=_env(), timeout=120)
            assert r.returncode == 0, f"{where}: `rasterhw {sub}` is not a command: {r.stderr[-500:]}"
        return
    if lang == "python":
        cmd, cwd = [sys.executable, "-c", body], tmp_path
    else:
        script = re.sub(r"(?:\.\./)*\.venv/bin/", f"{BIN}/", body)
        cmd, cwd = ["bash", "-euo", "pipefail", "-c", script], ROOT if "root" in flags else tmp_path
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=_env(), timeout=1800)
    assert r.returncode == 0, f"{where} failed (exit {r.returncode}):\n{r.stderr[-2000:]}"


def test_every_doc_has_its_runnable_blocks_found():
    """The scanner sees the blocks the docs hold (a fence typo would hide one)."""
    found = {p.values[0] for p in blocks()}
    assert {"reference.md", "scenes.md", "zbm.md", "snu.md", "snu_geometry.md"} <= found
