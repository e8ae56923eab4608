"""Committed fixed-seed records of the cocotb ZB/M unit bench (``unit_records.json``): per case its
segment-clock cycle count, per-line log and a digest of its frame, so the fast suite compares the
generic engine's run of that case with cocotb's without running cocotb (the bench costs ~40x the
engine's CPU per frame). ``tests/zbm/test_zbm_unit_records.py`` (slow) runs every case on the
cocotb bench again and holds the record equal to it (and to the golden frame); with
``RASTERHW_WRITE_RECORDS=1`` it writes the records instead (then ``git diff`` shows what changed).

A case is ``(units, interleave, stall, gap_seed, seed, ratio)`` on a 64 x 16 frame of 30 random
triangles (``random_triangles(default_rng(scene_seed), 30, 64, 16, size=10)``)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import doublez_words

RECORDS = Path(__file__).parent / "unit_records.json"
W, H = 64, 16

#: name -> case. "eq-*": equal clocks in phase (test_zbm_unit_engine.py); "ratio-*": the cocotb
#: bench's clocks at a segment:merge ratio, the merge clock 1 ns behind (test_engine_clocks.py,
#: test_zbm_unit_engine.py)
CASES = {
    "eq-s0-11": {"scene_seed": 11, "stall": 0, "gap_seed": None, "seed": 11, "ratio": None},
    "eq-s90-g7-101": {"scene_seed": 101, "stall": 90, "gap_seed": 7, "seed": 101, "ratio": None},
    "eq-s0-3": {"scene_seed": 3, "stall": 0, "gap_seed": None, "seed": 3, "ratio": None},
    "eq-s120-3": {"scene_seed": 3, "stall": 120, "gap_seed": None, "seed": 3, "ratio": None},
    "ratio-2-3": {"scene_seed": 5, "stall": 80, "gap_seed": 5, "seed": 8, "ratio": (2, 3)},
    "ratio-3-2": {"scene_seed": 5, "stall": 0, "gap_seed": None, "seed": 8, "ratio": (3, 2)},
    "ratio-7-2": {"scene_seed": 9, "stall": 60, "gap_seed": 9, "seed": 12, "ratio": (7, 2)},
    # the runs of test_zbm_cocotb.py's unit tests, now slow (test_unit_verilator_ratios[ratio0],
    # test_unit_no_gaps_full_rate[verilator]), and of the watchdog test (was a cocotb run):
    # test_zbm_unit_engine.py
    "ratio-5-5-s80-g10": {"scene_seed": 10, "stall": 80, "gap_seed": 10, "seed": 10, "ratio": (5, 5)},
    "ratio-5-5-s0-g11": {"scene_seed": 11, "stall": 0, "gap_seed": 11, "seed": 11, "ratio": (5, 5)},
    "ratio-2-7-s254": {"scene_seed": 5, "stall": 254, "gap_seed": None, "seed": 3, "ratio": (2, 7)},
}


def scene(name: str):
    """(edge pairs per unit, golden (s0, s1)) of case ``name``."""
    tris = random_triangles(np.random.default_rng(CASES[name]["scene_seed"]), 30, W, H, size=10)
    return [G.edge_pairs(tris)], doublez_words(G.render_zbm(tris, interleave=2).pixels)


def frame_digest(s0: np.ndarray, s1: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(s0, "<u8").tobytes() + np.ascontiguousarray(s1, "<u8").tobytes()
                          ).hexdigest()[:16]


def record(name: str) -> dict:
    """The committed record of case ``name``: ``{"cycles", "line_cycles", "frame"}``."""
    return json.loads(RECORDS.read_text())[name]


def engine_run(name: str) -> dict:
    """Case ``name`` on the generic Verilator engine (``run_scene``, the speed Verilog at -O1)."""
    from rasterhw.sim.zbm.scene import run_scene
    from rasterhw.sim.zbm.testbench import bench_clocks
    c = CASES[name]
    eps, _ = scene(name)
    return run_scene(eps, width=W, height=H, interleave=2, stall=c["stall"], seed=c["seed"], gap_seed=c["gap_seed"],
                     line_log=True, build={"speed": True, "opt": "-O1"},
                     clocks=bench_clocks(c["ratio"]) if c["ratio"] else None)


def cocotb_run(name: str) -> dict:
    """Case ``name`` on the cocotb unit bench (Verilator): equal clocks in phase, or its ratio."""
    from zbm_cocotb.unit_bench import run_unit_bench
    c = CASES[name]
    eps, _ = scene(name)
    kw = {"ratio": (5, 5), "phase": 0} if c["ratio"] is None else {"ratio": c["ratio"]}
    return run_unit_bench(eps, width=W, height=H, interleave=2, sim="verilator", stall=c["stall"], seed=c["seed"],
                          gap_seed=c["gap_seed"], speed_run=True, line_log=True, **kw)


def as_record(r: dict) -> dict:
    return {"cycles": int(r["cycles"]), "line_cycles": [int(x) for x in r["line_cycles"]],
            "frame": frame_digest(r["s0"], r["s1"])}


def check_engine(name: str) -> dict:
    """Case ``name`` on the engine against the golden frame and cocotb's committed record."""
    _, gold = scene(name)
    r = engine_run(name)
    assert np.array_equal(r["s0"], gold[0]) and np.array_equal(r["s1"], gold[1])
    assert r["proto_errors"] == 0 and r["frames_ok"] == 1 and r["overflow"] == 0
    rec = record(name)
    assert rec["frame"] == frame_digest(*gold)
    assert as_record(r) == rec and rec["cycles"] > H
    return r


def hold_records(path: Path, got: dict) -> None:
    """The committed records at ``path`` must equal ``got`` (case -> record, from the cocotb runs);
    with ``RASTERHW_WRITE_RECORDS=1`` they are written from ``got`` first (one case a line)."""
    if os.environ.get("RASTERHW_WRITE_RECORDS") == "1":
        path.write_text("{\n" + ",\n".join(f" {json.dumps(k)}: {json.dumps(v)}" for k, v in got.items()) + "\n}\n")
    assert json.loads(path.read_text()) == got
