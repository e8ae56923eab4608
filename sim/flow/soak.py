"""Random differential runs: every HDL block against its golden model, on Verilator.

``rasterhw soak --pixels N --seed S`` runs rounds of random stimulus through each block until
``N`` output pixels of that block have been compared bit for bit with the golden model (the
last round may overshoot). Every round draws its own settings from ``numpy.random`` seeded by
``(S, block, round)``: the same seed gives the same rounds, so a failure printed as
``seed S`` reproduces with ``--seed S --block NAME``.

A machine declares its rounds in its registry entry (``Machine.soak``: block name ->
``"module:round"``, a ``round(rng, k) -> {"pixels", "mismatches", "run_s", "settings"}`` for
round number ``k``); each round's module says what it randomises (e.g. ``sim/zbm/soak.py``).
This module knows no machine. A machine without HDL (the vector Z-buffer) declares no round.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry

__all__ = ["run_soak", "soak_blocks"]


def _rng(seed: int, block: str, k: int) -> np.random.Generator:
    return np.random.default_rng([seed, sum(block.encode()) * 7919 + len(block), k])


def soak_blocks() -> dict[str, str]:
    """Every block with a soak round -> its ``"module:round"``, in block-name order."""
    return dict(sorted(registry.entries("soak").items()))


def run_soak(*, pixels: int, seed: int, blocks: list[str] | None = None, progress: bool = True,
             max_rounds: int = 100_000) -> list[dict]:
    """Random rounds per block until ``pixels`` output pixels were compared; one row per block:
    ``block, rounds, pixels_compared, mismatches, wall_s, failures`` (the first few failing
    rounds: round number and settings)."""
    rounds = soak_blocks()
    names = list(rounds) if not blocks else blocks
    for b in names:
        if b not in rounds:
            raise RasterhwError(f"no soak for block {b!r}; blocks: {', '.join(rounds)}")
    if not isinstance(pixels, int) or pixels < 1:
        raise RasterhwError(f"--pixels must be a positive integer, not {pixels!r}")
    rows = []
    for b in names:
        fn = registry.load(rounds[b])
        t0 = time.perf_counter()
        done = bad = k = 0
        failures = []
        while done < pixels and k < max_rounds:
            r = fn(_rng(seed, b, k), k)
            done += r["pixels"]
            bad += r["mismatches"]
            if r["mismatches"] and len(failures) < 5:
                failures.append({"round": k, "mismatches": r["mismatches"], "settings": r["settings"]})
            if progress:
                print(f"soak {b} round {k}: {r['pixels']} pixels, {r['mismatches']} mismatches ({r['settings']})",
                      file=sys.stderr, flush=True)
            k += 1
        rows.append({"block": b, "seed": seed, "rounds": k, "pixels_compared": done, "mismatches": bad,
                     "wall_s": round(time.perf_counter() - t0, 1), "failures": failures})
    return rows
