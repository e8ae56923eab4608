"""EXPERTS parallel model: pipeline bounds, both balancing methods, both levels."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import pxp_range_ops, render_frame
from rasterhw.golden_model.experts.parallel import Balance, rebalance, run_parallel
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene


@cache
def _frame(name: str):
    return render_frame(run_geometry(build_scene(name), 512, 512), model="bit", aj="c")


def test_rebalance_methods():
    w = np.array([64, 64, 64, 64])
    t = np.array([100.0, 200.0, 100.0, 400.0])
    wi = rebalance(w, t, "i")
    assert wi.sum() == 256 and wi[3] < wi[1] < wi[0]
    # method i: widths proportional to width / time (pixels per op time)
    assert np.allclose(wi / wi.sum(), (w / t) / (w / t).sum(), atol=2 / 256)
    wii = rebalance(w, t, "ii", Balance(theta_shift=3, shrink_shift=3))
    # mean 200, threshold 225: only PXP 3 is late; it gives 64 >> 3 = 8 to the earliest (PXP 0)
    assert list(wii) == [72, 64, 64, 56]
    assert list(rebalance(w, t, "static")) == list(w)
    with pytest.raises(RasterhwError, match="balancing method"):
        rebalance(w, t, "iii")


def test_pipeline_time_bounds():
    f = _frame("experts-tilt-1000")
    r = run_parallel(f, 2, 4)
    for s in range(2):
        y0, y1 = r.bands[s], r.bands[s + 1]
        slp = r.slp_busy[s]
        pxp = r.pxp_busy[s].max()
        drain = Balance().fb_cost * 512 * (y1 - y0)
        # overlap: never faster than the busiest stage, never slower than running them one after another
        assert r.group_time[s] >= max(slp, pxp, drain) - 1e-6
        assert r.group_time[s] <= slp + r.pxp_time[y0:y1].max(axis=1).sum() + drain + 1e-6
    # static ranges: PXP times are exactly the range op counts of the golden model
    assert np.allclose(r.pxp_time, pxp_range_ops(f, np.arange(5) * 128))


def test_dynamic_ranges_beat_static_on_the_uneven_scene():
    f = _frame("experts-uneven")
    st = run_parallel(f, 1, 8, range_method="static").imbalance()
    m1 = run_parallel(f, 1, 8, range_method="i").imbalance()
    m2 = run_parallel(f, 1, 8, range_method="ii").imbalance()
    assert m2 < m1 < st
    assert st > 1.5 and m2 < 1.3


def test_host_bands_beat_equal_bands_on_the_uneven_scene():
    f = _frame("experts-uneven")
    eq = run_parallel(f, 8, 8, band_method="equal")
    pl = run_parallel(f, 8, 8, band_method="pl")
    assert pl.frame_time < 0.7 * eq.frame_time
    assert pl.group_time.max() / pl.group_time.mean() < eq.group_time.max() / eq.group_time.mean()
    fi = run_parallel(f, 8, 8, band_method="i", frames=4)
    assert fi.frame_time < eq.frame_time


def test_bad_parameters():
    f = _frame("experts-tilt-1000")
    with pytest.raises(RasterhwError, match="range method"):
        run_parallel(f, 1, 2, range_method="x")
    with pytest.raises(RasterhwError, match="band method"):
        run_parallel(f, 1, 2, band_method="x")
    with pytest.raises(RasterhwError, match="parts"):
        run_parallel(f, 1, 1000)


@pytest.mark.parametrize("aj", ["none", "c"])
def test_range_cycles_equal_the_hdl_cycle_model(aj):
    """The parallel model's PXP times in HDL cycles (from per-pixel counts) equal the cycle model
    run on each range's clipped ASL (the one the HDL matches)."""
    from rasterhw.golden_model.experts.model import pxp_range_cycles
    from rasterhw.golden_model.experts.pxp_cycles import line_segments, resolve_cycles
    f = render_frame(run_geometry(build_scene("experts-tilt-1000"), 512, 512, z_bits=16), model="bit", aj=aj)
    bounds = np.array([0, 1, 64, 100, 255, 256, 400, 511, 512])
    cyc = pxp_range_cycles(f, bounds)
    for y in (0, 57, 200, 389, 511):
        for p in range(len(bounds) - 1):
            lo, hi = int(bounds[p]), int(bounds[p + 1])
            want = resolve_cycles(line_segments(f, y, lo, hi, aj=aj), lo, hi, aj=aj) + 1
            assert cyc[y, p] == want, (y, lo, hi)


def test_parallel_in_pxp_cycles_are_the_hdl_finish_time_counters():
    """PXP times in cycles = what each PXP's counter reads line by line (its DSLB drain waits
    included): the cycle model's schedule of that PXP's own lines, which the HDL matches."""
    from rasterhw.golden_model.experts.model import pxp_range_cycles
    from rasterhw.golden_model.experts.pxp_cycles import line_segments, schedule
    f = _frame("experts-uneven")
    r = run_parallel(f, 8, 8, range_method="static", pxp_unit="cycles")
    assert (r.pxp_time >= pxp_range_cycles(f, np.arange(9) * 64)).all()
    for p in (0, 5):
        own = [(line_segments(f, y, 64 * p, 64 * p + 64, aj="c"), 64 * p, 64 * p + 64) for y in range(64, 128)]
        assert r.pxp_time[64:128, p].tolist() == schedule(own, aj="c")["line_cycles"]
    st = run_parallel(f, 1, 8, range_method="static", pxp_unit="cycles")
    ii = run_parallel(f, 1, 8, range_method="ii", pxp_unit="cycles")
    assert ii.imbalance() < st.imbalance()
    with pytest.raises(RasterhwError, match="pxp_unit"):
        run_parallel(f, 1, 8, pxp_unit="s")
