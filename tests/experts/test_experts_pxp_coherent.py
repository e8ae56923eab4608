# amaranth: UnusedElaboratable=no
"""The coherent span PXP (``experts-pxp-coherent``, ours: span cull once per segment, depth search
only where the visible segment can change) against its golden cycle model
(``golden_model/experts/coherent.py``): the per-pixel search's visible segment on every pixel,
pixels and per-line cycles equal in pysim through the registered testbench, and less work than
the span PXP on the same words."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.experts.coherent import STEPS, TERMS, resolve, resolve_counts
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.experts.span_cycles import resolve as span_resolve
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim import registry
from rasterhw.sim.experts.scene import jobs, simulate_scene


def _frame(name, w, h, aj="c", seed=0):
    return render_frame(run_geometry(build_scene(name, seed=seed), w, h, z_bits=16), model="bit", aj=aj)


@pytest.mark.parametrize("name,seed", [("experts-tilt-1000", 0), ("experts-1000", 0), ("c100", 0),
                                       ("experts-solids", 0), ("sp5", 0), ("experts-tilt-2000", 7),
                                       ("experts-uneven", 3)])
@pytest.mark.parametrize("aj", ["none", "c"])
def test_coherent_pxp_sees_the_per_pixel_visible_segment(name, seed, aj):
    """Every pixel of every range: the coherent PXP's visible record is the per-pixel search's
    (and so the span PXP's and the line Z-buffer's: the same image); scenes and seeds the PXP was
    not developed on included (sp5, experts-uneven, other seeds)."""
    fr = _frame(name, 160, 64, aj, seed)
    W, H, pn = fr.width, fr.height, 4
    b = equal_bounds(W, pn)
    jb = jobs(fr, 1, pn, pxp="coherent")
    win = fr.win.reshape(H, W)
    got = np.concatenate(jb["visible"])     # frame order: every line's ranges left to right
    assert np.array_equal(got, np.concatenate([win[y, b[p]:b[p + 1]] for y in range(H) for p in range(pn)]))
    assert (got >= 0).sum() > W * H // 20
    span = jobs(fr, 1, pn, pxp="span")
    assert np.array_equal(np.concatenate(jb["visible"]), np.concatenate(span["visible"]))
    assert np.array_equal(jb["pixels"], span["pixels"])


def _seg(zl, dz, addr, x0=0, x1=16):
    return {"xl": x0 << 6, "xr": x1 << 6, "zl": zl, "il": 0, "dzdx": dz << 4, "didx": 0, "addr": addr}


def test_search_only_where_the_visible_segment_can_change():
    """By hand: a near segment over the line and three behind it entering one by one: one depth
    search at the first pixel, none at the entries; a segment entering nearer asks for a search
    at its start; two crossing segments halve (the crossing rule) and the image follows the
    per-pixel keys."""
    near = _seg(100, 0, 0)
    behind = [_seg(500 + 10 * q, 0, q + 1, 2 + 3 * q, 16) for q in range(3)]
    cyc, vis, cnt = resolve_counts([near, *behind], [], 0, 0, 16)
    assert vis == [0] * 16 and cnt["searches_all"] == 1 and cyc["pass_a"] == 1 and cyc["pass_b"] == 0
    assert cyc["enter"] == 4 + 4 and cyc["write"] == 16          # 4 entering + one right end per span
    span_cyc, span_vis = span_resolve([near, *behind], [], 0, 0, 16)
    assert span_vis == vis and sum(span_cyc.values()) > sum(cyc.values())
    front = _seg(50, 0, 9, 8, 12)
    _, vis2, cnt2 = resolve_counts([near, front], [], 0, 0, 16)
    assert vis2 == [0] * 8 + [1] * 4 + [0] * 4 and cnt2["searches_all"] == 3   # at 0, at 8, after 11
    a, b = _seg(100, 10, 0), _seg(200, -10, 1)
    cyc3, vis3, cnt3 = resolve_counts([a, b], [], 0, 0, 16)
    z0 = [100 + 10 * x + 5 for x in range(16)]
    z1 = [200 - 10 * x - 5 for x in range(16)]
    assert vis3 == [0 if p <= q else 1 for p, q in zip(z0, z1, strict=True)]
    assert cnt3["halvings"] >= 2 and set(cyc3) == set(STEPS)
    assert resolve([a, b], [], 0, 0, 16) == (cyc3, vis3)
    assert set(TERMS["span_cull"]) | set(TERMS["depth_search"]) < set(STEPS)


def test_span_cull_once_per_segment_per_line():
    """Every segment is read once when it enters and dropped at most once: the span cull term is
    at most twice the segments plus one right end per span, and the coherent PXP searches less
    than the span PXP on the same words."""
    fr = _frame("experts-tilt-1000", 256, 64, "none")
    co, sp = jobs(fr, 1, 1, pxp="coherent"), jobs(fr, 1, 1, pxp="span")
    segs = int(np.sum([np.count_nonzero(fr.records.row == y) for y in range(fr.height)]))
    st = {k: sum(s[k] for s in co["steps"]) for k in co["steps"][0]}
    assert st["drop"] <= segs and st["enter"] <= 2 * segs + fr.height + st["pass_a"]
    sst = {k: sum(s[k] for s in sp["steps"]) for k in sp["steps"][0]}
    assert st["pass_a"] + st["pass_b"] < sst["pass_a"] + sst["pass_b"]
    assert st["enter"] + st["drop"] < sst["enter"] + sst["cull"]
    assert int(co["cycles"].sum()) < int(sp["cycles"].sum())


@pytest.mark.parametrize("aj", ["none", "c"])
def test_small_frame_coherent_pxp_pysim_pixel_and_cycle_exact(aj):
    r = simulate_scene(build_scene("experts-tilt-1000"), 64, 16, engine="pysim", sn=2, pn=4, aj=aj, pxp="coherent")
    assert r["pixels_compared"] == 64 * 16 and r["mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert r["last_pixel_mismatch"] == 0 and r["pxp"] == "coherent" and "ours" in r["pxp_is"]
    assert r["span_steps"]["write"] == 16 * (64 + (2 * 3 if aj == "c" else 0))
    assert r["span_steps"]["drop"] > 0 and r["span_steps"]["pass_a"] > 0


def test_crossing_faces_through_the_hdl_halve():
    """A frame where faces cross inside spans (experts-tilt at 128 x 24): the HDL halves as the
    model does, pixel and cycle for cycle."""
    r = simulate_scene(build_scene("experts-tilt-2000"), 128, 24, engine="pysim", sn=1, pn=2, aj="none",
                       pxp="coherent")
    assert r["mismatches"] == 0 and r["cycle_mismatches"] == 0 and r["last_pixel_mismatch"] == 0
    assert r["span_steps"]["pass_b"] > 0


def test_balanced_ranges_through_the_coherent_hdl():
    r = simulate_scene(build_scene("experts-uneven"), 128, 32, engine="pysim", sn=1, pn=4, aj="c", ranges="ii",
                       pxp="coherent")
    assert r["mismatches"] == 0 and r["cycle_mismatches"] == 0 and r["last_pixel_mismatch"] == 0


def test_registered_testbench_runs_the_block():
    """The block and its testbench are in the registry: random frames through pysim, pixels and
    cycles against the cycle model (the engines' generic check)."""
    from rasterhw.sim.engines import run
    from rasterhw.sim.testbench import compare, find_testbench
    assert registry.blocks()["experts-pxp-coherent"].endswith(":ExpertsPxpCoherent")
    tb = find_testbench("experts-pxp-coherent")
    p = tb.params(width=64, aj="c")
    for seed in (1, 2):
        stim = tb.stimulus(p, seed)
        exp = tb.expect(p, stim)
        got = run(tb, p, stim, engine="pysim", expect_words={"o": len(exp.words["o"])})
        c = compare(exp, got)
        assert c["mismatches"] == 0 and c["cycle_mismatches"] == 0, c


@pytest.mark.parametrize(("name", "aj"), [("experts-1000", "c"), ("experts-tilt-1000", "none")])
def test_paper_coherent_pxp_pysim_word_and_cycle_exact(name, aj):
    """experts-pxp-coherent at datapath "paper" (the span PXP's one 16 x 16 multiplier and 16-bit adder,
    z and i in two words) on a 64 x 16 frame of 4 ranges: every pixel and every line's finish-time
    counter equal the golden side's (span_cycles.paper_jobs with coherent.paper_resolve; with A.J. (c)
    the drain's blend holding the multiplier); the rule adds cycles for each of its terms, and the
    elaborated design has one multiplier of 16 x 16."""
    from rasterhw.golden_model.experts.pxp_cycles import guarded
    from rasterhw.golden_model.experts.span_cycles import dmm_line, paper_jobs, schedule
    from rasterhw.hdl.experts.census import multipliers
    from rasterhw.hdl.experts.pxp_coherent import ExpertsPxpCoherent
    from rasterhw.sim.experts.scene import check_jobs
    fr = _frame(name, 64, 16, aj)
    jb = jobs(fr, 1, 4, pxp="coherent")
    pj = paper_jobs(jb)
    assert pj["datapath"] == "paper" and np.array_equal(pj["pixels"], jb["pixels"])
    # each term of the rule is exercised: pass A and B, entering tests, drawn pixels
    cnt = {"pass_a": 0, "pass_b": 0, "tests_enter": 0}
    b = equal_bounds(64, 4)
    for y, p in ((y, p) for y in range(16) for p in range(4)):
        segs, lead, buckets = dmm_line(fr, y, b)
        glo, ghi = guarded(int(b[p]), int(b[p + 1]), 64, aj)
        cyc, _, c = resolve_counts(segs, buckets[p], lead[p], glo, ghi)
        cnt["pass_a"] += cyc["pass_a"]
        cnt["pass_b"] += cyc["pass_b"]
        cnt["tests_enter"] += c["tests_enter"]
    assert min(cnt.values()) > 10
    assert sum(pj["paper_extra"]) == cnt["pass_a"] + 5 * cnt["pass_b"] + 7 * cnt["tests_enter"] + sum(jb["drawn"])
    if aj == "c":       # the drain's blend holds the multiplier: the schedule without the holds is shorter
        assert sum(schedule(pj["timing"])["line_cycles"]) < int(pj["cycles"].sum())
    r = check_jobs(pj, width=64, engine="pysim")
    assert r["pixel_mismatches"] == 0 and r["line_mismatches"] == 0
    assert r["pixels"].size == 64 * 16 and np.array_equal(r["pixels"], pj["pixels"])
    assert r["last_pixel"] == pj["last_pixel"] + 1 > jb["last_pixel"] + 1
    assert multipliers(ExpertsPxpCoherent(width=64, aj=aj, datapath="paper")) == [(16, 16)]
