"""Random differential runs of every HDL block against its golden model, on Verilator
(sim/flow/soak.py): at least 10**6 output pixels per block in every CI run, a fresh seed each
time (printed; ``RASTERHW_SEED=n`` reruns it). ``make soak`` runs 10**8 per block.

A block may run its CI rounds on smaller designs that other tests build anyway (``CI_ROUNDS``: the
sparse matrix's whole-matrix and cocotb rounds, ``sim/sparse/soak.py``); its registered rounds, at
full size, run in the ``slow`` test below and in ``make soak``."""

from __future__ import annotations

import json
import os
import secrets

import pytest
from rasterhw.sim.flow.soak import run_soak, soak_blocks

pytestmark = pytest.mark.cocotb

PIXELS = int(float(os.environ.get("SOAK_PIXELS", "1e6")))
#: block -> the round the test suite runs in place of the registered one (the same kinds of round
#: on smaller designs)
CI_ROUNDS = {"sparse": "rasterhw.sim.sparse.soak:sparse_round_ci"}


def _soak(block: str, ref: str) -> None:
    seed = int(os.environ.get("RASTERHW_SEED") or secrets.randbelow(1 << 31))
    print(f"soak {block} ({ref}): seed {seed} (rerun: RASTERHW_SEED={seed}; the registered rounds: "
          f"rasterhw soak --seed {seed} --block {block})")
    (row,) = run_soak(pixels=PIXELS, seed=seed, blocks=[block], progress=False, rounds={block: ref})
    if os.environ.get("SOAK_REPORT"):  # a folder: one JSON row per block (pixels, rounds, seconds)
        os.makedirs(os.environ["SOAK_REPORT"], exist_ok=True)
        with open(os.path.join(os.environ["SOAK_REPORT"], f"{block}.json"), "w") as fh:
            json.dump(row, fh)
    assert row["pixels_compared"] >= PIXELS
    assert row["mismatches"] == 0, f"seed {seed}: {row['failures']}"


@pytest.mark.parametrize("block", list(soak_blocks()))
@pytest.mark.heavy(2)
def test_random_differential_rounds_match_golden(block):
    _soak(block, CI_ROUNDS.get(block, soak_blocks()[block]))


@pytest.mark.parametrize("block", list(CI_ROUNDS))
@pytest.mark.slow
def test_registered_full_size_rounds_match_golden(block):
    """The rounds ``CI_ROUNDS`` stands in for, at their full size (``make soak``'s)."""
    _soak(block, soak_blocks()[block])
