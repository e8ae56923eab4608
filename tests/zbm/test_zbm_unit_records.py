"""The committed records of the cocotb ZB/M unit bench (``tests/zbm_cocotb/unit_records.json``, which
the fast suite compares the generic engine with: test_zbm_unit_engine.py, test_engine_clocks.py)
held equal to the cocotb bench itself: every case run on it again, its frame the golden model's.
``RASTERHW_WRITE_RECORDS=1`` writes the records from these runs instead. Slow: seven cocotb runs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from zbm_cocotb import records as R


@pytest.mark.cocotb
@pytest.mark.slow
def test_records_are_the_cocotb_bench_runs():
    got = {}
    for name in R.CASES:
        r = R.cocotb_run(name)
        _, gold = R.scene(name)
        assert np.array_equal(r["s0"], gold[0]) and np.array_equal(r["s1"], gold[1]), name
        got[name] = R.as_record(r)
    R.hold_records(R.RECORDS, got)


def test_every_case_is_recorded():
    """One record per case, no stale ones (fast: reads the file)."""
    assert set(json.loads(R.RECORDS.read_text())) == set(R.CASES)
