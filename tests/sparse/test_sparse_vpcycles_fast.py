"""The video processor's cycle model: the numba fast path (golden_model/sparse/vpcycles_fast.py)
against the Python specification (golden_model/sparse/vpcycles.py), every returned key, on small
seeded random frames."""

from __future__ import annotations

import numpy as np
import pytest
from numba_blocked import run_without_numba
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse import vpcycles as V
from rasterhw.golden_model.sparse.search import sparse_render

pytest.importorskip("numba")

_KEYS = {"frame_cycles", "stall_cycles", "fifo_peak", "fifo_peak_max", "busy", "idle", "depth", "issue_interval",
         "accept", "broadcast", "tests", "stalls"}


def _frame(size, matrix, ntri, area, seed):
    return sparse_render(random_triangles(size, size, ntri, mean_area=area, seed=seed), matrix, depth="fixed",
                         trace=True)


def _same(a: dict, b: dict) -> None:
    assert set(a) == set(b) == _KEYS
    for k in _KEYS:
        if isinstance(a[k], np.ndarray):
            assert a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k]), k
        else:
            assert type(a[k]) is type(b[k]) and a[k] == b[k], k


# (size, matrix, triangles, mean area, scene seed): big triangles fill the inner FIFOs; small ones
# make the broadcast wait on the slowest processor
_FRAMES = [(32, (2, 2), 24, 60.0, 1), (32, (2, 2), 40, 12.0, 2), (64, (4, 4), 30, 40.0, 3),
           (64, (4, 4), 50, 200.0, 4)]


@pytest.mark.parametrize("frame", _FRAMES, ids=lambda f: f"{f[1][0]}x{f[1][1]}-{f[0]}-s{f[4]}")
def test_coupled_fast_path_equals_the_specification(frame):
    f = _frame(*frame)
    stalled = inner = 0
    frames = {}
    for depth in (1, 2, 64):
        for kp in (0, 4):
            for vp_depth in (2, 8):
                kw = dict(fifo_depth=vp_depth, kp=kp)
                want = V.coupled_matrix_vp(f, depth, engine="python", **kw)
                got = V.coupled_matrix_vp(f, depth, engine="numba", **kw)
                _same(want, got)
                stalled += want["stall_cycles"] > 0
                inner += sum(map(sum, want["stalls"])) > 0
                frames[depth, kp, vp_depth] = want["frame_cycles"]
    # the cases exercise what they claim: broadcast waits, full inner FIFOs, parameter cycles
    assert stalled > 0 and inner > 0
    assert all(frames[d, 4, v] > frames[d, 0, v] for d in (1, 2, 64) for v in (2, 8))


def test_coupled_fast_path_with_the_other_options():
    """A slower broadcast (issue interval 3), a shallower set-up FIFO, other ``ke``."""
    f = _frame(32, (2, 2), 30, 30.0, 11)
    for kw in (dict(issue_interval=3), dict(setup_fifo_depth=2, fifo_depth=4), dict(kp=5, ke=2, fifo_depth=3)):
        _same(V.coupled_matrix_vp(f, 2, engine="python", **kw), V.coupled_matrix_vp(f, 2, engine="numba", **kw))


@pytest.mark.parametrize("frame", _FRAMES[::2], ids=lambda f: f"{f[1][0]}x{f[1][1]}-{f[0]}-s{f[4]}")
def test_standalone_fast_path_equals_the_specification(frame):
    f = _frame(*frame)
    for k in range(f.p * f.q):
        for kw in (dict(), dict(fifo_depth=2), dict(fifo_depth=3, kp=4)):
            want = V.vp_standalone(*V.vp_streams(f, k), f.triangles, engine="python", **kw)
            got = V.vp_standalone(*V.vp_streams(f, k), f.triangles, engine="numba", **kw)
            assert want == got and len(got["accept"]) == f.triangles


def test_runaway_and_bad_input_are_refused_alike():
    f = _frame(32, (2, 2), 10, 30.0, 5)
    for engine in ("python", "numba"):
        with pytest.raises(RasterhwError, match="runaway coupled frame"):
            V.coupled_matrix_vp(f, 2, max_cycles=50, engine=engine)
        with pytest.raises(RasterhwError, match="runaway feed"):
            V.vp_standalone(*V.vp_streams(f, 0), f.triangles, max_cycles=5, engine=engine)
        with pytest.raises(RasterhwError, match="fifo_depth"):
            V.coupled_matrix_vp(f, 2, fifo_depth=1, engine=engine)
        with pytest.raises(RasterhwError, match="kp"):
            V.vp_standalone(*V.vp_streams(f, 0), f.triangles, kp=-1, engine=engine)


def test_engine_switch(monkeypatch):
    """RASTERHW_VPCYCLES=python runs the specification (the fast module is never entered), the
    default the fast path; a bad value is an error that names the variable."""
    f = _frame(32, (2, 2), 10, 30.0, 6)

    class Boom:
        def __getattr__(self, name):
            raise AssertionError("fast path entered")

    monkeypatch.setattr(V._FAST, "module", lambda: Boom())
    monkeypatch.setenv(V.ENGINE_ENV, "python")
    assert V.choose_engine() == "python"
    V.coupled_matrix_vp(f, 2)
    V.vp_standalone(*V.vp_streams(f, 0), f.triangles)
    monkeypatch.delenv(V.ENGINE_ENV)
    assert V.choose_engine() == "numba"
    with pytest.raises(AssertionError, match="fast path"):
        V.coupled_matrix_vp(f, 2)
    monkeypatch.setenv(V.ENGINE_ENV, "numpy")
    with pytest.raises(RasterhwError, match=V.ENGINE_ENV):
        V.coupled_matrix_vp(f, 2)
    with pytest.raises(RasterhwError, match="engine"):
        V.coupled_matrix_vp(f, 2, engine="fast")


def test_without_numba_the_specification_runs_with_one_line_saying_so():
    code = """
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse import vpcycles as V
from rasterhw.golden_model.sparse.search import sparse_render
f = sparse_render(random_triangles(32, 32, 10, mean_area=30.0, seed=6), (2, 2), depth="fixed", trace=True)
a = V.coupled_matrix_vp(f, 2)
b = V.coupled_matrix_vp(f, 1)
print(V.choose_engine(), a["frame_cycles"], b["stall_cycles"])
try:
    V.coupled_matrix_vp(f, 2, engine="numba")
except V.RasterhwError as e:
    print("refused:", e)
"""
    out, line = run_without_numba(code, V.ENGINE_ENV)
    assert "Python specification" in line
    f = _frame(32, (2, 2), 10, 30.0, 6)
    want = V.coupled_matrix_vp(f, 2, engine="python")["frame_cycles"], V.coupled_matrix_vp(f, 1)["stall_cycles"]
    assert out[0] == f"python {want[0]} {want[1]}"
    assert out[1].startswith("refused:") and "numba" in out[1]
