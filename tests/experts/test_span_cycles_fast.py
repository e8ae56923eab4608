"""The span PXP's cycle model: the numba fast path (golden_model/experts/span_cycles_fast.py and
span_cycles_kernel.py) against the Python specification (golden_model/experts/span_cycles.py),
every job of whole frames: step counts, drain, words and visible positions; and the scene run's
job list (what ``rasterhw sim pxp`` checks the HDL against) the same with either engine."""

from __future__ import annotations

import numpy as np
import pytest
from numba_blocked import run_without_numba
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts import span_cycles as spec
from rasterhw.golden_model.experts import span_cycles_fast as fast
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene

pytest.importorskip("numba")


def _frame(name, w, h, aj, seed=0):
    return render_frame(run_geometry(build_scene(name, seed=seed), w, h, z_bits=16), model="bit", aj=aj)


@pytest.mark.parametrize("name", ["experts-tilt-1000", "experts-1000", "c100"])
@pytest.mark.parametrize("aj", ["none", "c"])
def test_fast_line_jobs_equal_the_specification(name, aj):
    fr = _frame(name, 128, 64, aj)
    W, pn = fr.width, 4
    b = equal_bounds(W, pn).tolist()
    searched = 0
    for y in range(fr.height):
        segs, ids = spec.line_asl(fr, y)
        fsegs, fids = fast.line_asl(fr, y)
        assert fsegs == segs and fids.tolist() == ids.tolist()
        assert all(type(v) is int for s in fsegs for v in s.values())
        assert fast.dmm_line(fr, y, b, engine="numba") == spec.dmm_line(fr, y, b)      # every range at once
        for p in range(pn):
            lo, hi = b[p], b[p + 1]
            segs, lead, buckets = spec.dmm_line(fr, y, [lo, hi])
            fsegs, flead, fbuckets = fast.dmm_line(fr, y, [lo, hi], engine="numba")
            assert (fsegs, flead, fbuckets) == (segs, lead, buckets)
            want = spec.line_job(segs, buckets[0], lead[0], lo, hi, aj=aj, width=W)
            got = fast.line_job(fsegs, fbuckets[0], flead[0], lo, hi, aj=aj, width=W, engine="numba")
            assert got == want, (y, p)
            assert type(got["visible"]) is list and all(type(v) is int for v in got["visible"])
            searched += want["steps"]["pass_b"] > 0
    # every frame exercises the depth search, not only single-segment spans (the halving: below)
    assert searched > 0


def test_fast_resolve_edge_cases_equal_the_specification():
    """An empty range, no segments, and two segments crossing inside one span (halved)."""
    s0 = {"xl": 0, "xr": 16 << 6, "zl": 100, "il": 0, "dzdx": 10 << 4, "didx": 0, "addr": 0}
    s1 = {"xl": 0, "xr": 16 << 6, "zl": 180, "il": 0, "dzdx": 0, "didx": 0, "addr": 1}
    for segs, bucket, lead, glo, ghi in [([s0, s1], [], 0, 0, 16), ([s0, s1], [], 0, 4, 4), ([], [], spec.NO_PTR, 0, 8),
                                         ([s1, s0], [0, 1], spec.NO_PTR, 3, 12)]:
        want = spec.resolve(segs, bucket, lead, glo, ghi)
        assert fast.resolve(segs, bucket, lead, glo, ghi, engine="numba") == want
        assert fast.resolve(segs, bucket, lead, glo, ghi, engine="python") == want
    assert spec.resolve([s0, s1], [], 0, 0, 16)[0]["pass_a"] > 2        # the crossing was halved
    segs = [dict(s0), dict(s1)]                  # a list changed between calls is read again
    fast.resolve(segs, [], 0, 0, 16, engine="numba")
    segs[1]["zl"] = 20
    assert fast.resolve(segs, [], 0, 0, 16, engine="numba") == spec.resolve(segs, [], 0, 0, 16)


def test_scene_job_list_is_the_same_on_either_engine(monkeypatch):
    from rasterhw.sim.experts.scene import jobs
    fr = _frame("experts-1000", 96, 48, "c")
    monkeypatch.setenv(fast.ENGINE_ENV, "python")
    want = jobs(fr, 1, 4, pxp="span")
    monkeypatch.setenv(fast.ENGINE_ENV, "numba")
    got = jobs(fr, 1, 4, pxp="span")
    assert want.keys() == got.keys()
    for k in want:
        if k == "visible":
            assert all(np.array_equal(a, b) for a, b in zip(want[k], got[k], strict=True))
        elif isinstance(want[k], np.ndarray):
            assert np.array_equal(want[k], got[k]), k
        else:
            assert want[k] == got[k], k


def test_bad_engine_is_one_line_error(monkeypatch):
    monkeypatch.setenv(fast.ENGINE_ENV, "fortran")
    with pytest.raises(RasterhwError, match="RASTERHW_SPANCYCLES must be one of"):
        fast.choose_engine()


def test_without_numba_the_specification_runs_with_one_line():
    code = ("from rasterhw.golden_model.experts import span_cycles_fast as f\n"
            "s = {'xl': 0, 'xr': 1024, 'zl': 100, 'dzdx': 160, 'addr': 0}\n"
            "print(f.choose_engine(), f.resolve([s], [], 0, 0, 16)[0]['write'])\n")
    out, err = run_without_numba(code, fast.ENGINE_ENV)
    assert out == ["python 16"] and "Python specification" in err
