"""Random differential runs of every HDL block against its golden model, on Verilator
(sim/flow/soak.py): at least 10**6 output pixels per block in every CI run, a fresh seed each
time (printed; ``RASTERHW_SEED=n`` reruns it). ``make soak`` runs 10**8 per block."""

from __future__ import annotations

import json
import os
import secrets

import pytest
from rasterhw.sim.flow.soak import run_soak, soak_blocks

pytestmark = pytest.mark.cocotb

PIXELS = int(float(os.environ.get("SOAK_PIXELS", "1e6")))


@pytest.mark.parametrize("block", list(soak_blocks()))
@pytest.mark.heavy(2)
def test_random_differential_rounds_match_golden(block):
    seed = int(os.environ.get("RASTERHW_SEED") or secrets.randbelow(1 << 31))
    print(f"soak {block}: seed {seed} (rerun: RASTERHW_SEED={seed} or rasterhw soak --seed {seed} --block {block})")
    (row,) = run_soak(pixels=PIXELS, seed=seed, blocks=[block], progress=False)
    if os.environ.get("SOAK_REPORT"):  # a folder: one JSON row per block (pixels, rounds, seconds)
        os.makedirs(os.environ["SOAK_REPORT"], exist_ok=True)
        with open(os.path.join(os.environ["SOAK_REPORT"], f"{block}.json"), "w") as fh:
            json.dump(row, fh)
    assert row["pixels_compared"] >= PIXELS
    assert row["mismatches"] == 0, f"seed {seed}: {row['failures']}"
