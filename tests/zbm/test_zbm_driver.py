"""ZbmScene (sim/zbm/scene.py) on a tiny scene in Amaranth pysim, and its input checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scenes import SCENES, build_scene
from rasterhw.golden_model.zbm import words as W
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.sim.zbm.edge_check import check_edge_pairs
from rasterhw.sim.zbm.scene import simulate
from zbm_cocotb.chip_bench import run_chip_bench
from zbm_cocotb.unit_bench import run_unit_bench


def _scene():
    from rasterhw.golden_model.meshio import load_scene

    name = "c300" if "c300" in SCENES else sorted(SCENES)[0]
    return load_scene(name)


def test_simulate_zbm_pysim_tiny_frame():
    # 32 x 8 (not 16): pysim runs ~1,000 clocks per line of c300 here; Verilator runs the bigger frames
    r = simulate(_scene(), 32, 8, interleave=2, engine="pysim")
    assert r["block"] == "zbm" and r["engine"] == "pysim" and r["units"] == 1
    assert r["pixels_compared"] == 32 * 8 and r["mismatches"] == 0
    # every line's cycle = the exact cycle model's (issue 46)
    assert r["cycle_mismatches"] == 0 and r["lines_compared"] == 8 and r["cycles"] == r["cycles_golden"]
    assert r["edge_pairs"] > 0 and r["cycles"] > 0 and r["frame_rgb"].shape == (8, 32, 3)
    assert r["frame_rgb"].dtype == np.uint8 and r["frame_rgb"].any()
    assert r["float_tolerance"]["ok"], r["float_tolerance"]


def test_bad_arguments():
    sc = _scene()
    with pytest.raises(RasterhwError, match="engine"):
        simulate(sc, 32, 16, engine="modelsim")
    with pytest.raises(RasterhwError, match="interleave"):
        simulate(sc, 32, 16, interleave=3, engine="pysim")
    with pytest.raises(RasterhwError, match="units"):
        simulate(sc, 32, 16, units=0, engine="pysim")
    with pytest.raises(RasterhwError, match="width"):
        simulate(sc, 1024, 16, engine="pysim")


def _eps():
    return G.edge_pairs(random_triangles(np.random.default_rng(0), 12, 32, 16, size=8))


def test_edge_pair_checks():
    eps = _eps()
    assert check_edge_pairs(eps, 32, 16) >= 1
    bad = eps.take(np.arange(len(eps)))
    bad.len[2] = -1
    with pytest.raises(RasterhwError, match="len -1 < 0"):
        check_edge_pairs(bad, 32, 16)
    bad = eps.take(np.arange(len(eps)))
    bad.h[-1] = 40
    with pytest.raises(RasterhwError, match="outside 0..15"):
        check_edge_pairs(bad, 32, 16)
    with pytest.raises(RasterhwError, match="active-edge-pair memory"):
        check_edge_pairs(eps, 32, 16, capacity=2)
    # dealing to more units lowers each unit's peak
    assert check_edge_pairs(eps, 32, 16, units=3) <= check_edge_pairs(eps, 32, 16)
    # the frame must fit the chips' line memories (width was once ignored)
    for w, h, msg in ((513, 16, "width must be an integer in 1..512, not 513"), (0, 16, "width"),
                      (32, 0, "height must be"), (32.0, 16, "width")):
        with pytest.raises(RasterhwError, match=msg):
            check_edge_pairs(eps, w, h)


def test_words_round_trip():
    gold = G.render_zbm(random_triangles(np.random.default_rng(1), 10, 32, 16), interleave=2)
    s0, s1 = W.doublez_words(gold.pixels)
    px = W.words_to_doublez(s0, s1)
    assert np.array_equal(px.z, gold.pixels.z) and np.array_equal(px.c, gold.pixels.c)
    assert np.array_equal(G.composite(px), gold.rgb8)


def test_float_tolerance_when_last_triangles_cover_no_pixel():
    """Issue 14 row 1: the highest-numbered triangles of c50 at 16x16 cover no pixel; the
    float-tolerance check must still size its per-triangle table by every edge-pair tag."""
    res = simulate(build_scene("c50"), 16, 16, interleave=1, engine="pysim")
    assert res["mismatches"] == 0 and res["pixels_compared"] == 256


def test_bench_without_golden_frame_must_say_speed_run():
    """A cocotb bench run with nothing to compare against is refused unless it is an explicit
    speed run whose caller compares the dump itself."""
    with pytest.raises(RasterhwError, match="speed_run"):
        run_chip_bench([0], [0], lines=1, chip=0, interleave=1, width=8, sim="verilator")
    with pytest.raises(RasterhwError, match="speed_run"):
        run_unit_bench([G.edge_pairs(random_triangles(np.random.default_rng(0), 2, 8, 8))], width=8,
                         height=8, interleave=1, sim="verilator")


@pytest.mark.parametrize("interleave,seed,schedule", [(1, 0, "overlap"), (2, 1, "paper"), (8, 2, "overlap"),
                                                      (4, 3, "paper")])
def test_line_log_equals_cycle_model(interleave, seed, schedule):
    """The unit's per-line log on the engine (``UnitBench.line_cycles``: the clock after every chip
    slot's last merge word of line y) == the exact cycle model's ``hdl_cycles(...)["line_cycles"]``
    (its swaps + chip pixels + ``MERGE_OUT_LATENCY``) line for line, on random streams (empty and
    clipped segments, several pairs per line), both schedules: what ``sim zbm``'s
    ``cycle_mismatches`` compares."""
    from rasterhw.golden_model.zbm import cycles as C
    from rasterhw.sim.zbm.scene import run_scene

    w, h = 8 * interleave if interleave > 1 else 24, 10
    eps = G.edge_pairs(random_triangles(np.random.default_rng(seed), 6, w, h, size=10))
    model = C.hdl_cycles(eps, h, width=w, interleave=interleave, schedule=schedule)
    r = run_scene([eps], width=w, height=h, interleave=interleave, schedule=schedule, engine="pysim", line_log=True)
    assert r["mismatches"] == 0 and len(eps) >= 5
    assert r["line_cycles"] == model["line_cycles"].tolist() and r["cycles"] == model["line_cycles"][-1]


def test_cycle_mismatches_counts_perturbed_lines(monkeypatch):
    """``cycle_mismatches`` can fail: the same run with the HDL's stamps of the last line one clock
    late (every chip slot) counts that line; one clock early everywhere, every line."""
    from rasterhw.sim.engines import scene as S

    real = S.run_job

    def shifted(by, last_only):
        def run(job, engine):
            d = real(job, engine)
            npx = {p: len(range(c, 32, 2)) for c, p in enumerate(job.tb.outputs_of(job.params))}
            st = {p: [s + by if (not last_only or k >= len(v) - npx[p]) else s for k, s in enumerate(v)]
                  for p, v in d.got.stamps.items()}
            return S.Done(d.job, dataclasses.replace(d.got, stamps=st), d.cmp)
        return run

    for by, last_only, want in ((1, True, 1), (-1, False, 8)):
        monkeypatch.setattr(S, "run_job", shifted(by, last_only))
        r = simulate(_scene(), 32, 8, interleave=2, engine="pysim")
        assert r["mismatches"] == 0 and r["cycle_mismatches"] == want, (by, r["cycle_mismatches"])
        assert r["cycles"] != r["cycles_golden"]


def test_scene_golden_is_the_golden_models_and_cached(monkeypatch):
    """``scene_golden`` (what ``sim zbm`` compares with): every slot's rows = the ``zbm-unit``
    testbench's expected words, ``lines`` = ``hdl_cycles``' line log, the float arrays =
    ``float_reference``; a second call is served from the build cache (no golden model runs)."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.zbm import cycles as C
    from rasterhw.sim.testbench import find_testbench
    from rasterhw.sim.zbm import scene as S

    tris = run_geometry(build_scene("c50"), 32, 16)
    eps = G.edge_pairs(tris)
    g = S.scene_golden(tris, eps, width=32, height=16, interleave=2, units=1, schedule="paper")
    tb = find_testbench("zbm-unit")
    p = tb.params(interleave=2, width=32, height=16)
    exp = tb.expect(p, tb.scene_stimulus(p, [eps]))
    assert np.array_equal(g["rows"], np.concatenate([exp.words[o] for o in tb.outputs_of(p)]))
    assert g["counts"].tolist() == [len(exp.words[o]) for o in tb.outputs_of(p)]
    assert g["lines"].tolist() == C.hdl_cycles(eps, 16, width=32, interleave=2, schedule="paper")["line_cycles"].tolist()
    ref = S.float_reference(tris, exp.golden.tag[..., 0])
    assert all(np.array_equal(g[k], v) for k, v in ref.items())

    def no(*a, **k):
        raise AssertionError("computed again")

    monkeypatch.setattr(G, "render_zbm_float", no)
    monkeypatch.setattr(C, "hdl_cycles", no)
    again = S.scene_golden(tris, eps, width=32, height=16, interleave=2, units=1, schedule="paper")
    assert all(np.array_equal(again[k], v) for k, v in g.items())
