"""Soak rounds for tests/test_cluster.py: stand-ins for a machine's round (``round(rng, k)``,
sim/flow/soak.py) that take a known time and log when they start and end, so a test can kill a
worker in the middle of one. Imported by the test and, by name, by Dask workers (the tests
folder on their PYTHONPATH)."""

from __future__ import annotations

import os
import time


def _log(what: str) -> None:
    path = os.environ.get("RASTERHW_TEST_ROUND_LOG")
    if path:
        with open(path, "a") as fh:
            fh.write(f"{what} {os.getpid()}\n")


def slow_round(rng, k: int) -> dict:
    """``RASTERHW_TEST_ROUND_SLEEP`` seconds (the workers': 0.4; none in the test's process); a
    seeded number of pixels (50..149), no mismatch."""
    _log(f"start {k}")
    time.sleep(float(os.environ.get("RASTERHW_TEST_ROUND_SLEEP", "0")))
    px = int(rng.integers(50, 150))
    _log(f"end {k}")
    return {"pixels": px, "mismatches": 0, "run_s": 0.4, "settings": f"x={int(rng.integers(1 << 20))}"}


def failing_round(rng, k: int) -> dict:
    """100 pixels; round 3 mismatches."""
    return {"pixels": 100, "mismatches": int(k == 3), "run_s": 0.0, "settings": f"x={int(rng.integers(1 << 20))}"}
