"""Run code in a fresh Python where ``import numba`` fails (the golden models' fast paths fall back
to their specification): shared by the fast-path tests of the reference rasteriser and the sparse
VP cycle model."""

from __future__ import annotations

import os
import subprocess
import sys

_BLOCK = 'import sys\nsys.modules["numba"] = None  # import numba -> ImportError\n'


def run_without_numba(code: str, engine_env: str) -> tuple[list[str], str]:
    """``code`` run with numba unimportable and ``engine_env`` unset: (its stdout lines, the one
    line it wrote to stderr, which must name numba)."""
    env = {k: v for k, v in os.environ.items() if k != engine_env}
    p = subprocess.run([sys.executable, "-c", _BLOCK + code], capture_output=True, text=True, env=env, timeout=120)
    assert p.returncode == 0, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "numba" in lines[0], p.stderr
    return p.stdout.splitlines(), lines[0]
