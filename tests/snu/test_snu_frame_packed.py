"""``sim/snu/scene.py: frame_job`` gives the frame's expected words as packed rows (no Python int
per pixel): they are ``FrameBench.expect``'s words, and ``frame_words`` reads the display from
packed rows (Verilator) as from ints (the other engines)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.snu.gouraud import scan_convert
from rasterhw.sim.engines.scene import Done
from rasterhw.sim.packed import as_bytes, as_ints
from rasterhw.sim.snu import scene as F
from rasterhw.sim.testbench import Run, compare


def test_frame_job_rows_are_the_testbench_s_words_and_read_back():
    tris = run_geometry(build_scene("sp27"), 24, 16, z_bits=24, z_far_is_zero=True)
    s = scan_convert(tris)
    p = F.producer_gaps(tris, s)
    sch = F.golden_schedule(s, p["gaps"], p["first_work"], ratio=p["ratio"])
    job = F.frame_job(s, p["gaps"], sch)
    want = job.tb.expect(job.params, job.stim).words
    rows = job.expect.words["o"]
    assert isinstance(rows, np.ndarray) and len(rows) == 24 * 16
    assert np.array_equal(rows, as_bytes(want["o"], rows.shape[1] * 8)) and as_ints(rows) == want["o"]
    assert job.expect.words["o_sched"] == want["o_sched"] and job.run["packed"]
    assert len(set(want["o"])) > 2                                    # a frame with pixels drawn
    for got in ({"o": rows, "o_sched": np.array([[v] for v in want["o_sched"]], np.uint8)} if max(want["o_sched"]) < 256
                else {"o": rows, "o_sched": want["o_sched"]}, want):   # packed (Verilator) and ints (pysim)
        run = Run("x", got, {})
        r = F.frame_words(Done(job, run, compare(replace(job.expect, cycles=None), run)))   # words only
        assert r["mismatches"] == 0 and [r[k] for k in F.SCHEDULE] == want["o_sched"]
        assert np.array_equal((r["rgb"].ravel() << 24) | r["z"].ravel(), want["o"])
