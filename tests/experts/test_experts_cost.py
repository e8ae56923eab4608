"""EXPERTS cost model: the paper's formulas, and the measured counts behaving as the formulas say."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rasterhw.golden_model.experts import cost
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene


@pytest.mark.parametrize("fr,pn", [(1000, 7.06), (2000, 3.95)])
def test_balance_pn_is_where_q_s_meets_q_p(fr, pn):
    lo, hi = 1.0, 64.0
    for _ in range(60):  # bisection on the formulas, independent of the closed form
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cost.q_p(fr, 1, mid) > cost.q_s(fr, 1) else (lo, mid)
    assert cost.balance_pn(fr) == pytest.approx(lo, rel=1e-9)
    assert cost.balance_pn(fr) == pytest.approx(pn, abs=0.01)
    # the totals are the sums the paper prints: 893 + 31607 = 32500
    assert cost.q_s(fr, 1) + cost.q_p(fr, 1, 1) == pytest.approx(cost.q_seq(fr))


def test_measured_q_par_falls_with_pn_until_the_slp_binds():
    f = render_frame(run_geometry(build_scene("experts-tilt-1000"), 512, 512))
    q = [cost.measured_q(f, 1, pn) for pn in (1, 2, 4, 8, 16, 32)]
    par = [d["q_par"] for d in q]
    assert all(a >= b for a, b in zip(par, par[1:], strict=False))
    assert q[0]["q_p"] > q[0]["q_s"] and q[-1]["q_s"] >= q[-1]["q_p"]     # PXP-bound, then SLP-bound
    assert q[-1]["q_par"] == q[-1]["q_s"]
    # the measured Q_seq is the sum of the stages, whatever the partition
    assert all(d["q_seq"] == q[0]["q_seq"] for d in q)


def test_alpha_error_curves():
    e = cost.alpha_error()
    a = e["angle"]
    assert e["c_max"][a == 90.0][0] < 1e-12 and e["b_max"][a == 90.0][0] < 1e-12   # vertical edge: exact
    # (c) is worst at the 45-degree switch; (b) is never worse than (c) there
    k45 = int(np.argmin(np.abs(a - 45)))
    assert e["c_max"][k45] == pytest.approx(e["c_max"].max())
    assert e["b_max"][k45] <= e["c_max"][k45]


def test_line_segments_scene():
    ls = cost.line_segments(8)
    assert ls.n_triangles == 16 and len(set(ls.poly_id.tolist())) == 8
    f = render_frame(ls, aj="c")
    assert f.aj_pixels > 8 * 2 * 100   # both long sides of every segment are blended
    assert math.isfinite(cost.total_ops(f))


def test_aj_cost_is_per_crossing_and_rises_with_edges_when_only_edges_vary():
    """Table 2.1 analysis (docs/reproduction/experts.md): the extra work per A.J. pixel is one
    constant on every solid, and in the pyramid family (one size, 6 to 20 edges) the increase rises."""
    from rasterhw.golden_model.experts import cost
    from rasterhw.golden_model.experts.model import render_frame
    from rasterhw.golden_model.experts.scenes import build_pyramid
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene

    def overhead(sc):
        tris = run_geometry(sc, 512, 512, z_bits=16)
        a = cost.total_ops(render_frame(tris))
        fc = render_frame(tris, aj="c")
        extra = cost.total_ops(fc) - a
        return extra / a, extra / fc.aj_pixels

    # the extra work per A.J. pixel comes from the routine each pixel executed (aj_ops) plus the
    # edge tests and the SLP's slopes; it varies with the edges' slopes, within 10 % here
    per_pixel = [overhead(build_scene(f"experts-solid-{k}"))[1] for k in (5, 9, 15, 20)]
    assert max(per_pixel) / min(per_pixel) < 1.1, per_pixel
    assert len({round(p, 6) for p in per_pixel}) == 4
    lo, hi = overhead(build_pyramid(3)(21))[0], overhead(build_pyramid(10)(21))[0]
    assert hi > 1.2 * lo, (lo, hi)


def test_aj_per_pixel_cost_is_the_work_the_routine_executed(monkeypatch):
    """Table 2.1 / 2.2 count what the A.J. routine executes per blended pixel: make every one of
    its operations count twice and the blended pixels' share of the A.J. work doubles exactly."""
    from rasterhw.golden_model.experts import aj_ops
    tris = run_geometry(build_scene("experts-solid-15"), 512, 512, z_bits=16)
    f1 = render_frame(tris, aj="c")
    w = f1.win.reshape(f1.height, f1.width)
    edge_tests = int(np.count_nonzero(w[:, 1:] != w[:, :-1]))     # 1 per run boundary
    per_pixel = int(f1.costs["anti_jagging"].sum()) - edge_tests
    assert per_pixel >= 23 * f1.aj_pixels          # float model: 23 on a steep edge
    tick = aj_ops.Tally.tick
    monkeypatch.setattr(aj_ops.Tally, "tick", lambda self, k=1: tick(self, 2 * k))
    f2 = render_frame(tris, aj="c")
    assert int(f2.costs["anti_jagging"].sum()) - edge_tests == 2 * per_pixel
    assert np.array_equal(f2.rgb8, f1.rgb8)


def test_aj_routine_counts_by_path_and_computes_the_image_alpha():
    """Method (c), bit model: 33 operations on a steep edge, 35 on a shallow one (|dy/dx| and the
    multiply instead of a shift); (b) one path, (a) four (which pieces of the area integral)."""
    from rasterhw.golden_model.experts import aj_ops
    # 3 (pixel: shift, clamp) + 3 (delta) + 2 (|s|, compare) + 2 or 4 (alpha) + 2 (clamp) + 21 (blend)
    xe = np.array([100 * 64 + 10, 100 * 64 + 10])
    fl = np.array([[7, 0, 0, 100], [7, 0, 0, 100]])
    fr = np.array([[0, 7, 0, 20], [0, 7, 0, 20]])
    al, blend, ops = aj_ops.aj_pixel_ops("c", True, xe, np.array([100, 100]), np.array([128, 512]),
                                         np.array([512, 128]), None, fl, fr)
    assert list(ops) == [33, 35]
    assert list(al) == [128 + ((10 - 32) << 2), 128 + (((10 - 32) * 128) >> 6)]
    assert np.array_equal(blend[0], (al[0] * fl[0] + (256 - al[0]) * fr[0] + 128) >> 8)
    for m, paths in (("b", 1), ("a", 4)):
        rng = np.random.default_rng(1)
        x = rng.uniform(10, 11, 400)
        s = rng.uniform(-3, 3, 400)
        a, _, ops = aj_ops.aj_pixel_ops(m, False, x, np.full(400, 11), s, 1 / s, 1 / np.sqrt(1 + s * s))
        assert len(set(ops.tolist())) == paths
        from rasterhw.golden_model.experts.alpha import ALPHA
        assert np.allclose(a, ALPHA[m](x - (np.clip(np.floor(x), 10, 11) + 0.5), s), atol=1e-12)


@pytest.mark.parametrize("model", ["float", "bit"])
@pytest.mark.parametrize("m", ["a", "b", "c"])
def test_counted_aj_routine_computes_the_image_alpha(model, m):
    """The counted routine is the work behind the image: its alpha (and in the bit model with (c),
    the machine's, its blend) is the one anti_jagging puts in the frame."""
    from rasterhw.golden_model.experts import pxp
    f = render_frame(run_geometry(build_scene("experts-solids"), 512, 512, z_bits=16), model=model)
    fields = pxp.pixel_fields(f.setup, f.records, f.win, pxp.smooth_shading(f.setup, f.records, f.win, 512))
    _, info = pxp.anti_jagging(f.setup, f.records, f.win, fields, 512, 512, m)
    assert info["pixels"] > 1000 and info["ops"].size == info["pixels"]
    if model == "bit" and m == "c":
        assert np.array_equal(info["alpha"], info["alpha_counted"])
    else:
        assert np.abs(info["alpha"] - info["alpha_counted"]).max() <= (1e-12 if model == "float" else 1)


def test_measured_q_run_comes_from_the_sorts_run_and_the_span_pxp():
    from rasterhw.golden_model.experts import slp_run, span
    from rasterhw.golden_model.experts.model import equal_bounds
    f = render_frame(run_geometry(build_scene("experts-tilt-1000"), 512, 512))
    cache: dict = {}
    one = cost.measured_q_run(f, 1, 1, cache)
    (run,) = slp_run.run_bands(f, equal_bounds(512, 1))
    sp = span.span_pxp(f.setup, f.records, 512, 512)
    assert one["q_s"] == run.ops["y_sort"] + run.ops["x_merge"] + run.ops["l_sort"]
    assert one["q_p"] == sp.total(("span_cull", "depth_search"))
    q = [cost.measured_q_run(f, sn, pn, cache) for sn, pn in ((2, 4), (8, 8), (8, 16))]
    assert all(d["q_seq"] == one["q_seq"] and d["q_par"] == max(d["q_s"], d["q_p"]) for d in q)
    assert one["q_p"] / 32 < q[1]["q_p"] < one["q_p"] / 8      # 64 PXPs: not a perfect split, not none


def test_realtime_clocks_from_golden_counts():
    """The busiest SLP's operations and the busiest span PXP's cycles, times 30 frames/s; the span
    PXP needs more on the tilted scene than on the flat one with the same screen triangles."""
    from rasterhw.golden_model.experts import span
    from rasterhw.golden_model.experts.model import equal_bounds, slp_band_ops
    tilt = render_frame(run_geometry(build_scene("experts-tilt-1000"), 512, 512, z_bits=16), model="bit", aj="c")
    r = cost.realtime(tilt, 8, 8)
    bands = equal_bounds(512, 8)
    runs, counted = r["slp_detail"], slp_band_ops(tilt, bands, 8)
    per_band = [sum(x.ops.values()) + sum(v for k, v in c.items() if k not in x.ops) for x, c in zip(runs, counted, strict=True)]
    assert r["slp_ops"] == max(per_band) and r["slp_clock_for_30fps_hz"] == 30 * max(per_band)
    cyc = span.span_cycles(tilt, r["span"])
    assert r["pxp_cycles"] == max(int(cyc[bands[s]:bands[s + 1]].sum(axis=0).max()) for s in range(8))
    assert r["pxp_clock_for_30fps_hz"] == 30 * r["pxp_cycles"]
    flat = render_frame(run_geometry(build_scene("experts-1000"), 512, 512, z_bits=16), model="bit", aj="c")
    assert cost.realtime(flat, 8, 8)["pxp_cycles"] < r["pxp_cycles"]
