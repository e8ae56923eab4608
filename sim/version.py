"""The version of this copy of rasterhw, with the commit it was made from where that is known.

* In a git checkout (the package folder is a work tree: ``.git`` beside ``pyproject.toml``): the
  release (``rasterhw.__version__``) with the commit as a PEP 440 local label, asked of git once
  per process: ``0.1.0+g0d10752`` (``.dirty`` added when tracked files differ from the commit);
* in an installed wheel: what ``setup.py`` recorded when it built the wheel (``_version.py``
  written into the wheel beside ``__init__.py``: the same string, from the checkout it was built in);
* anywhere else (a wheel built from a tarball without ``.git``, git not installed): the release alone.

Never the installed distribution's metadata: the package imported may not be the one installed
(a checkout on ``PYTHONPATH`` beside an older install). :func:`version` is what ``rasterhw
--version`` prints, every ``--json`` document carries (``sim/cli/jsonout.py``) and the header of
every generated Verilog file names.
"""

from __future__ import annotations

import functools
import re
import subprocess
from pathlib import Path

__all__ = ["commit", "git_version", "version"]

_ROOT = Path(__file__).resolve().parents[1]


def _release() -> str:
    from rasterhw import __version__

    return __version__


def git_version(root: str | Path, release: str) -> str | None:
    """``RELEASE+gHASH[.dirty]`` of the git work tree at ``root``, None if it is none (or git is
    missing). ``setup.py`` calls it too (with its own copy of this file's logic: it runs before
    the package is importable)."""
    root = Path(root)
    if not (root / ".git").exists():
        return None
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short=10", "HEAD"], capture_output=True,
                              text=True, timeout=20)
        if head.returncode or not re.fullmatch(r"[0-9a-f]{7,40}", head.stdout.strip()):
            return None
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    local = f"g{head.stdout.strip()}" + (".dirty" if dirty.returncode == 0 and dirty.stdout.strip() else "")
    return f"{release}+{local}"


@functools.cache
def version() -> str:
    """This copy's version (see the module docstring)."""
    got = git_version(_ROOT, _release())
    if got is not None:
        return got
    try:
        from rasterhw._version import VERSION  # written into the wheel by setup.py
    except ImportError:
        return _release()
    return VERSION


def commit() -> str | None:
    """The commit of :func:`version` (short hash), None where it is not known."""
    m = re.search(r"\+g([0-9a-f]+)", version())
    return m.group(1) if m else None
