"""Every ``--json`` output of the command line, in one style (``docs/architecture.md``, "JSON
output"): one line on stdout, keys in snake_case with the unit last (``_s``, ``_ms``, ``_hz``,
``_per_s``), a golden model's value of a measured key ``K`` named ``K_golden``, NumPy numbers
as JSON numbers and paths as strings. ``tests/test_json_style.py`` walks every command's output."""

from __future__ import annotations

import json
from pathlib import Path

import click

__all__ = ["RENAMED", "emit_json", "normalise"]

#: keys some drivers still return under an older name -> ``(the name in the JSON, keep the old
#: name too)``; the old one is kept only where a committed document names it in a command's output
RENAMED: dict[str, tuple[str, bool]] = {
    "golden_cycles": ("cycles_golden", False),   # sim pixelbus: every other golden value is K_golden
    "sim_s": ("run_s", True),                    # sim zbm: the clock loop, run_s everywhere else (docs/zbm.md names sim_s)
}


def normalise(res: dict) -> dict:
    """``res`` with the keys of :data:`RENAMED` under their names (top level; order kept)."""
    out = {}
    for k, v in res.items():
        new, keep = RENAMED.get(k, (k, False))
        out[new] = v
        if keep and new != k:
            out[k] = v
    return out


def _default(o):
    import numpy as np

    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    return str(o)


def emit_json(obj) -> None:
    """Print ``obj`` as one line of JSON on stdout."""
    click.echo(json.dumps(obj, indent=None, sort_keys=False, default=_default))
