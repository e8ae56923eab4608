"""The ``zbm-chip`` testbench on the generic Verilator engine (what the ZB/M chip-rate bench row runs;
was the plain bench ``sim/zbm/fast.py`` + ``cocotb_tests/zbm/fast/tb_zbm_fast.v``): one 64x16 chip
(interleave 4, chip 1, random triangles and random upstream pixels) must produce the golden merged
scan lines bit for bit, in the same number of segment-clock cycles as the cocotb chip bench
(``run_chip_bench`` with equal in-phase clocks, no gaps, no back-pressure), and count every line.
The fast test compares the engine's cycles with that bench's committed record
(``tests/zbm_cocotb/chip_record.json``: cycles and frame digest); the slow test runs the cocotb
bench again and holds the record equal to it (``RASTERHW_WRITE_RECORDS=1`` writes it instead). The
chip is the one ``tests/zbm/test_zbm_cocotb.py`` runs under cocotb. That file's chip runs at clock
ratios, gaps and back-pressure are slow; here the engine runs each at the bench's clocks against
the bench's recorded run (``tests/zbm_cocotb/chip_records.py``, one separate-clock engine build),
and the slow test holds those records equal to cocotb. The fast suite builds no cocotb chip."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm.stimulus import random_doublez, random_triangles
from rasterhw.golden_model.zbm.words import merge_words
from rasterhw.sim.engines import run
from rasterhw.sim.testbench import Stimulus, find_testbench
from zbm_cocotb import chip_records as CR
from zbm_cocotb.chip_bench import chip_stimulus, run_chip_bench
from zbm_cocotb.records import frame_digest, hold_records

pytestmark = pytest.mark.cocotb

W, H, ILV, CHIP = 64, 16, 4, 1   # test_zbm_cocotb.py's chip (W, H, _chip_run's defaults)
#: the cocotb chip bench's run of :func:`_stimulus`: ``{"cycles", "frame"}`` (segment clocks, frame digest)
RECORD = Path(__file__).parents[1] / "zbm_cocotb" / "chip_record.json"


def _stimulus(seed: int = 5):
    tris = random_triangles(np.random.default_rng(seed), 40, W, H, size=10)
    segs = G.segment_generator(G.edge_pairs(tris), H, width=W)
    npx = -(-(W - CHIP) // ILV)
    up = random_doublez(np.random.default_rng(seed + 1), H * npx)
    up = G.DoubleZ(up.z.reshape(H, npx, 2), up.a.reshape(H, npx, 2), up.c.reshape(H, npx, 2, 4),
                   up.tag.reshape(H, npx, 2))
    return chip_stimulus(segs, H, up, chip=CHIP, interleave=ILV, width=W)


@pytest.mark.heavy(2)
def test_engine_chip_matches_golden_and_the_cocotb_record():
    """Was a cocotb chip run beside the engine run (``..._and_cocotb_cycles``): the cocotb bench's
    cycles now come from its committed record, held equal to cocotb by the slow test below."""
    seg_w, up_w, exp = _stimulus()
    assert len(seg_w) > H   # some segments, not only end-of-line records
    tb = find_testbench("zbm-chip")
    p = tb.params(interleave=ILV, chip=CHIP, width=W)
    want = merge_words(*exp)
    got = run(tb, p, Stimulus({"i_seg": seg_w, "i_merge": up_w}), engine="verilator",
              expect_words={"o_merge": len(want)}, build={"opt": "-O1"})
    assert got.words["o_merge"] == want
    assert got.status["lines"] == H and got.cycles > 0 and got.protocol_errors == 0
    rec = json.loads(RECORD.read_text())
    assert rec["frame"] == frame_digest(*exp)          # the record is of this stimulus's golden frame
    assert got.cycles == rec["cycles"]


@pytest.mark.slow
def test_cocotb_chip_bench_equals_its_record():
    seg_w, up_w, exp = _stimulus()
    ref = run_chip_bench(seg_w, up_w, lines=H, chip=CHIP, interleave=ILV, width=W, sim="verilator",
                         ratio=(5, 5), stall=0, repeat=1, phase=0, expect=exp)
    assert np.array_equal(ref["s0"], exp[0]) and np.array_equal(ref["s1"], exp[1])
    got = {"cycles": int(ref["cycles"]), "frame": frame_digest(ref["s0"], ref["s1"])}
    if os.environ.get("RASTERHW_WRITE_RECORDS") == "1":
        RECORD.write_text(json.dumps(got) + "\n")
    assert json.loads(RECORD.read_text()) == got


@pytest.mark.parametrize("case", list(CR.CASES))
def test_engine_chip_at_the_cocotb_benchs_clocks_equals_its_record(case):
    """The chip on the engine at the cocotb chip bench's segment : merge clocks, idle gaps and
    back-pressure (``tests/zbm_cocotb/chip_records.py``): the golden merged words, no protocol error,
    every line, and the cocotb bench's segment-clock count as recorded
    (``tests/zbm_cocotb/chip_ratio_records.json``, held equal to cocotb by the slow test below).
    Was a cocotb run each: test_zbm_cocotb.py's test_chip_verilator_ratios and
    test_chip_sims[verilator], now slow."""
    CR.check_engine(case)


@pytest.mark.slow
def test_cocotb_chip_runs_equal_their_records():
    got = {}
    for name in CR.CASES:
        r = CR.cocotb_run(name)
        _, _, exp = CR.chip_case(CR.CASES[name][2])
        assert np.array_equal(r["s0"], exp[0]) and np.array_equal(r["s1"], exp[1]), name
        assert r["proto_errors"] == 0 and r["lines"] == H, name
        got[name] = CR.as_record(r)
    hold_records(CR.RECORDS, got)


def test_every_chip_case_is_recorded():
    """One record per case, no stale ones (fast: reads the file)."""
    assert set(json.loads(CR.RECORDS.read_text())) == set(CR.CASES)
