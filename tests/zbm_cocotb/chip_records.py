"""Committed fixed-seed records of the cocotb ZB/M chip bench at its clock ratios
(``chip_ratio_records.json``): per case the chip's segment-clock cycle count, its line count and a
digest of the merged frame, so the fast suite runs each case on the generic Verilator engine with
the bench's clocks, idle gaps and back-pressure and compares with cocotb's run without running
cocotb (the cocotb chip build, ~30 s cold, and 3-5 s per cocotb run against ~0.1 s on the engine).
``tests/zbm/test_zbm_chip_engine.py::test_cocotb_chip_runs_equal_their_records`` (slow) runs every
case on the cocotb bench again, with its protocol checkers and in-bench golden compare, and holds
the records equal to it; with ``RASTERHW_WRITE_RECORDS=1`` it writes them instead.

A case is ``test_zbm_cocotb.py``'s chip run (:func:`chip_case`): a 64 x 16 frame of 40 random
triangles and random upstream pixels, interleave 4, chip 1, at segment : merge half periods
``ratio`` (the merge clock 1 ns behind), back-pressure ``stall``, idle gaps seeded ``seed``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm.stimulus import random_doublez, random_triangles
from rasterhw.golden_model.zbm.words import merge_words

from zbm_cocotb.records import frame_digest

RECORDS = Path(__file__).parent / "chip_ratio_records.json"
W, H, ILV, CHIP = 64, 16, 4, 1

#: name -> (ratio, stall, seed): test_zbm_cocotb.py's test_chip_verilator_ratios (seed 7 s + m) and
#: test_chip_sims[verilator]
CASES = {
    "ratio-5-5-s80": ((5, 5), 80, 40),
    "ratio-2-3-s80": ((2, 3), 80, 17),
    "ratio-3-2-s80": ((3, 2), 80, 23),
    "ratio-5-5-s40": ((5, 5), 40, 3),
}


def chip_case(seed: int, *, interleave: int = ILV, chip: int = CHIP):
    """(segment words, upstream words, golden (s0, s1)) of the chip run seeded ``seed``."""
    from zbm_cocotb.chip_bench import chip_stimulus

    tris = random_triangles(np.random.default_rng(seed), 40, W, H, size=10)
    segs = G.segment_generator(G.edge_pairs(tris), H, width=W)
    npx = -(-(W - chip) // interleave)
    up = random_doublez(np.random.default_rng(seed), H * npx)
    up = G.DoubleZ(up.z.reshape(H, npx, 2), up.a.reshape(H, npx, 2), up.c.reshape(H, npx, 2, 4),
                   up.tag.reshape(H, npx, 2))
    return chip_stimulus(segs, H, up, chip=chip, interleave=interleave, width=W)


def record(name: str) -> dict:
    """The committed record of case ``name``: ``{"cycles", "lines", "frame"}``."""
    return json.loads(RECORDS.read_text())[name]


def engine_run(name: str):
    """Case ``name`` on the generic Verilator engine: the cocotb bench's clocks (``bench_clocks``),
    its idle gaps (``random_gaps`` over the segment words, then the upstream words) and its sink's
    back-pressure (the bench seeds its xorshift ``0x9E3779B9 ^ (7919 seed + 1)``; the engine's
    ``zbm-chip`` sink starts from the run's seed, so that value is the seed given)."""
    from rasterhw.sim.engines import run
    from rasterhw.sim.testbench import Stimulus, find_testbench
    from rasterhw.sim.zbm.testbench import bench_clocks, random_gaps

    ratio, stall, seed = CASES[name]
    seg_w, up_w, exp = chip_case(seed)
    g = random_gaps(len(seg_w) + len(up_w), seed).tolist()
    tb = find_testbench("zbm-chip")
    p = tb.params(interleave=ILV, chip=CHIP, width=W)
    stim = Stimulus({"i_seg": seg_w, "i_merge": up_w}, gaps={"i_seg": g[:len(seg_w)], "i_merge": g[len(seg_w):]})
    return run(tb, p, stim, engine="verilator", stall=stall, seed=0x9E3779B9 ^ ((seed * 7919 + 1) & 0xFFFF_FFFF),
               expect_words={"o_merge": len(merge_words(*exp))}, build={"opt": "-O1"}, clocks=bench_clocks(ratio))


def cocotb_run(name: str) -> dict:
    """Case ``name`` on the cocotb chip bench (Verilator), protocol checked, compared in the bench."""
    from zbm_cocotb.chip_bench import run_chip_bench

    ratio, stall, seed = CASES[name]
    seg_w, up_w, exp = chip_case(seed)
    return run_chip_bench(seg_w, up_w, lines=H, chip=CHIP, interleave=ILV, width=W, sim="verilator", ratio=ratio,
                          stall=stall, seed=seed, gap_seed=seed, expect=exp, check_protocol=True)


def as_record(r: dict) -> dict:
    return {"cycles": int(r["cycles"]), "lines": int(r["lines"]), "frame": frame_digest(r["s0"], r["s1"])}


def check_engine(name: str):
    """Case ``name`` on the engine: the golden merged words, no protocol error, every line, and
    cocotb's recorded cycle count."""
    _, _, exp = chip_case(CASES[name][2])
    got = engine_run(name)
    assert got.words["o_merge"] == merge_words(*exp)
    assert got.protocol_errors == 0 and got.status["lines"] == H
    rec = record(name)
    assert rec["frame"] == frame_digest(*exp) and rec["lines"] == H
    assert got.cycles == rec["cycles"] > H
    return got
