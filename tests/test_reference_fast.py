"""The reference rasteriser's numba fast path (golden_model/reference_fast.py) against the NumPy
specification (golden_model/reference.py), bit for bit: on c300, sp27 and c300 at 1280x1024, on
hypothesis-generated scenes, in row bands and tiles; the output contract (render into a Target);
the engine switch (RASTERHW_REFERENCE); the fallback without numba; numba's cache location.
(The brute-force tests of tests/test_reference*.py run on both engines.)"""

from __future__ import annotations

import hashlib
import itertools
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numba_blocked import run_without_numba
from rasterhw.golden_model import reference as R
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles

pytest.importorskip("numba")

FIELDS = ("colour", "depth", "tri_id", "poly_id")


def assert_same(a: R.Frame, b: R.Frame) -> None:
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name  # bits: -0.0 != 0.0, NaN payloads, ...
    assert (a.fragments, a.pixels_written, a.pixels_covered) == (b.fragments, b.pixels_written, b.pixels_covered)


def both(tris, **kw) -> tuple[R.Frame, R.Frame]:
    return R.rasterise(tris, engine="numpy", **kw), R.rasterise(tris, engine="numba", **kw)


def assert_target_is_frame(t: R.Target, f: R.Frame) -> None:
    if t.rgb8 is not None:
        np.testing.assert_array_equal(t.rgb8, f.to_rgb8())
    for name in FIELDS:
        arr = getattr(t, name)
        if arr is not None:
            ref = getattr(f, name)
            assert arr.tobytes() == ref.astype(arr.dtype).tobytes(), name
            np.testing.assert_array_equal(arr, ref)  # the narrower ids hold the same values
    assert t.counts == {"fragments": f.fragments, "pixels_written": f.pixels_written,
                        "pixels_covered": f.pixels_covered}


@pytest.fixture(scope="module")
def scenes():
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene

    c300 = build_scene("c300")
    return {"c300 512x512": run_geometry(c300, 512, 512),
            "sp27 512x512": run_geometry(build_scene("sp27"), 512, 512),
            "c300 1280x1024": run_geometry(c300, 1280, 1024)}


@pytest.mark.parametrize("name", ["c300 512x512", "sp27 512x512", "c300 1280x1024"])
def test_scenes_bit_identical(scenes, name):
    tris = scenes[name]
    spec, fast = both(tris)
    assert spec.fragments > 100_000 and spec.pixels_written > spec.pixels_covered  # overdraw happens
    assert_same(spec, fast)
    t = R.render(tris, R.Target(tris.width, tris.height, rgb8=True, tri_id=True, poly_id=np.int64, depth=True))
    assert_target_is_frame(t, spec)


# Random scenes: vertices on pixel centres, on corners, anywhere and off screen, shared between
# triangles; flat depths from a few levels (exact ties) or sloped; duplicates; any background.
_coord = st.one_of(st.integers(-6, 60).map(lambda v: v + 0.5), st.integers(-6, 60).map(float),
                   st.floats(-8, 64, allow_nan=False), st.integers(-2000, 2000).map(lambda v: v / 7.0))
_level = st.sampled_from([0.0, 0.25, 0.5, 0.5, 1.0, -0.0, 1e-300, 3.5e9])


@st.composite
def scenes_(draw):
    w = draw(st.integers(1, 48))
    h = draw(st.integers(1, 40))
    nv = draw(st.integers(3, 14))
    pts = np.array([[draw(_coord), draw(_coord)] for _ in range(nv)])
    n = draw(st.integers(0, 30))
    idx = np.array([[draw(st.integers(0, nv - 1)) for _ in range(3)] for _ in range(n)], dtype=np.int64).reshape(n, 3)
    if n > 2 and draw(st.booleans()):
        idx[-1] = idx[0]  # an exact duplicate
    xy = pts[idx].reshape(n, 3, 2)
    flat = draw(st.booleans())
    z = np.array([[draw(_level)] * 3 if flat else [draw(st.floats(-2, 2)) for _ in range(3)] for _ in range(n)])
    z = z.reshape(n, 3)
    colour = np.array([draw(st.floats(-0.2, 1.2)) for _ in range(9 * n)]).reshape(n, 3, 3)
    pid = np.array([draw(st.integers(-5, 2**40)) for _ in range(n)], dtype=np.int64)
    bg = draw(st.sampled_from([(0.0, 0.0, 0.0), (-0.0, 0.0, 1.0), (0.2, 0.4, 0.6), (1.5, -0.3, 0.5 / 255)]))
    return ScreenTriangles(width=w, height=h, xy=xy, z=z, zq=np.zeros((n, 3), np.int64), colour=colour,
                           poly_id=pid), bg


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes_())
def test_random_scenes_bit_identical(scene):
    tris, bg = scene
    spec, fast = both(tris, background=bg)
    assert_same(spec, fast)
    t = R.render(tris, R.Target(tris.width, tris.height, rgb8=True, colour=True, depth=True,
                                tri_id=True, poly_id=np.int64), background=bg)
    assert_target_is_frame(t, spec)
    rgb8, counts = R.rasterise_rgb8(tris, background=bg, engine="numba")
    np.testing.assert_array_equal(rgb8, spec.to_rgb8())
    assert counts == t.counts


def test_random_scenes_reach_the_cases():
    """The generator really produces covered pixels and overdraw. ``find`` without its shrink
    phase: the first example found is proof enough, and shrinking it cost minutes."""
    from hypothesis import Phase, find

    quick = settings(phases=[Phase.generate], database=None, max_examples=500)
    find(scenes_(), lambda s: R.rasterise(s[0], engine="numpy").pixels_covered > 200, settings=quick)
    find(scenes_(), lambda s: (lambda f: f.pixels_written > f.pixels_covered + 20)(R.rasterise(s[0], engine="numpy")),
         settings=quick)


@pytest.mark.parametrize("threads, per_thread", [(2, 1), (2, 3), (3, 5)])
def test_bands_and_tiles_are_bit_identical(threads, per_thread, monkeypatch):
    """Row bands in threads (each thread taking bands in turn) and tiles of rows on the fast
    path: the whole frame, bit for bit."""
    tris = R.random_triangles(200, 150, 700, mean_area=120, seed=5)
    spec = R.rasterise(tris, engine="numpy")
    monkeypatch.setattr(R, "THREADS", threads)
    monkeypatch.setattr(R, "FAST_BANDS_PER_THREAD", per_thread)
    monkeypatch.setattr(R, "_exec", None)
    monkeypatch.setattr(R, "THREAD_MIN_PIXELS", 1)
    assert len(R._bands(200, 150, tris.n_triangles)) == threads
    assert_same(spec, R.rasterise(tris, engine="numba"))
    monkeypatch.setattr(R, "TILE_PIXELS", 200 * 7)  # tiles of 7 rows, each in bands
    rgb8, counts = R.rasterise_rgb8(tris, engine="numba")
    np.testing.assert_array_equal(rgb8, spec.to_rgb8())
    assert counts == {"fragments": spec.fragments, "pixels_written": spec.pixels_written,
                      "pixels_covered": spec.pixels_covered}
    monkeypatch.setattr(R, "_exec", None)


@pytest.mark.parametrize("size, n, area", [((700, 48), 30, 9000.0), ((300, 260), 6, 60000.0)])
def test_big_triangles_and_long_rows(size, n, area):
    """Spans of hundreds of pixels, triangles bigger than the frame, clipped on every side, drawn
    in row bands: the same bits as the specification."""
    w, h = size
    tris = R.random_triangles(w, h, n, mean_area=area, seed=11)
    spec, fast = both(tris, background=(0.25, 0.5, 1.0))
    assert_same(spec, fast)
    assert spec.fragments > 10 * w and spec.pixels_written > spec.pixels_covered
    t = R.render(tris, R.Target(w, h, rgb8=True, tri_id=True), background=(0.25, 0.5, 1.0))
    assert_target_is_frame(t, spec)


_SNAP = st.one_of(st.floats(-65536, 65536, allow_nan=False), st.integers(-2**24, 2**24).map(lambda v: v / 512.0))


@settings(max_examples=60, deadline=None)
@given(st.lists(_SNAP, min_size=6, max_size=60).filter(lambda v: len(v) % 6 == 0), st.integers(1, 7))
def test_prepare_snaps_like_screen_snap_and_cuts_in_order(coords, n):
    """``prepare`` snaps exactly as ``screen.snap`` (ties of half a sub-pixel included), and its
    cuts run from the first row to the last, never decreasing."""
    from rasterhw.golden_model import reference_fast as F
    from rasterhw.golden_model.screen import snap

    xy = np.array(coords).reshape(-1, 3, 2)
    X, Y, cuts = F.prepare(xy, 64, 48, 5, 40, n)
    assert X.tobytes() == snap(xy[:, :, 0]).tobytes() and Y.tobytes() == snap(xy[:, :, 1]).tobytes()
    assert len(cuts) == n + 1 and cuts[0] == 5 and cuts[-1] == 40
    assert all(a <= b for a, b in itertools.pairwise(cuts))


@pytest.mark.parametrize("engine", ["numpy", "numba"])
def test_render_writes_only_what_is_asked_into_reused_buffers(engine):
    a = R.random_triangles(96, 64, 300, mean_area=60, seed=3)
    b = R.random_triangles(96, 64, 200, mean_area=90, seed=4)
    t = R.Target(96, 64, rgb8=True, tri_id=True)
    assert t.colour is None and t.depth is None and t.poly_id is None
    assert t.rgb8.dtype == np.uint8 and t.tri_id.dtype == np.int32
    bufs = (t.rgb8, t.tri_id)
    assert R.render(a, t, engine=engine) is t
    assert_target_is_frame(t, R.rasterise(a, engine="numpy"))
    R.render(b, t, background=(0.1, 0.2, 0.3), engine=engine)  # overwrites every pixel
    assert t.rgb8 is bufs[0] and t.tri_id is bufs[1]
    assert_target_is_frame(t, R.rasterise(b, background=(0.1, 0.2, 0.3), engine="numpy"))
    for combo in ({"depth": True}, {"poly_id": True}, {"colour": True, "tri_id": np.int64}):
        t = R.Target(96, 64, **combo)
        assert_target_is_frame(R.render(a, t, engine=engine), R.rasterise(a, engine="numpy"))


def test_render_refuses_ids_that_do_not_fit_and_wrong_targets():
    tris = R.random_triangles(32, 32, 20, seed=1)
    tris.poly_id = tris.poly_id + 2**31
    with pytest.raises(RasterhwError, match="poly_id.*int64"):
        R.render(tris, R.Target(32, 32, poly_id=True))
    R.render(tris, R.Target(32, 32, poly_id=np.int64))
    with pytest.raises(RasterhwError, match="32x32"):
        R.render(tris, R.Target(32, 16, rgb8=True))
    with pytest.raises(RasterhwError, match="int32 or int64"):
        R.Target(32, 32, tri_id=np.int16)


def test_engine_switch(monkeypatch):
    """RASTERHW_REFERENCE=numpy runs the NumPy code (the fast path is never entered), the
    default runs the fast path; a bad value is an error that names the variable."""
    tris = R.random_triangles(64, 48, 60, seed=2)

    def boom(*a, **k):
        raise AssertionError("fast path entered")

    monkeypatch.setattr(R, "_fast_draw", boom)
    monkeypatch.setenv(R.ENGINE_ENV, "numpy")
    assert R.choose_engine() == "numpy"
    R.rasterise(tris)
    R.render(tris, R.Target(64, 48, rgb8=True))
    R.rasterise_rgb8(tris)
    monkeypatch.delenv(R.ENGINE_ENV)
    assert R.choose_engine() == "numba"
    with pytest.raises(AssertionError, match="fast path"):
        R.rasterise(tris)
    with pytest.raises(AssertionError, match="fast path"):
        R.rasterise(tris, engine="numba")
    monkeypatch.setenv(R.ENGINE_ENV, "fast")
    with pytest.raises(RasterhwError, match=R.ENGINE_ENV):
        R.rasterise(tris)


_BLOCKED = """
import hashlib
from rasterhw.golden_model import reference as R
tris = R.random_triangles(64, 48, 80, seed=9)
a = R.rasterise(tris)
b = R.rasterise(tris)
print(R.choose_engine(), hashlib.sha256(a.colour.tobytes() + a.tri_id.tobytes() + a.depth.tobytes()).hexdigest())
try:
    R.rasterise(tris, engine="numba")
except R.RasterhwError as e:
    print("refused:", e)
"""


def test_without_numba_the_numpy_code_runs_with_one_line_saying_so():
    out, line = run_without_numba(_BLOCKED, R.ENGINE_ENV)
    assert "NumPy" in line
    a = R.rasterise(R.random_triangles(64, 48, 80, seed=9), engine="numpy")
    digest = hashlib.sha256(a.colour.tobytes() + a.tri_id.tobytes() + a.depth.tobytes()).hexdigest()
    assert out[0] == f"numpy {digest}"
    assert out[1].startswith("refused:") and "numba" in out[1]


_LOCATE = """
import numba.core.caching as c
c.CacheImpl._locator_classes = {classes}  # as if the package and the user cache were read-only
from rasterhw.golden_model import reference_fast as F
print(type(F._band._cache).__name__, getattr(F._band._cache, "cache_path", "-"))
"""


@pytest.mark.parametrize("classes, expect", [("[c.UserProvidedCacheLocator]", "tmp"), ("[]", "none")])
def test_cache_falls_back_where_numba_finds_no_writable_place(tmp_path, classes, expect):
    """No writable __pycache__ and no user cache directory: the kernel is cached under
    $TMPDIR/rasterhw-numba-UID; with no place at all it is compiled without a cache."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["TMPDIR"] = str(tmp_path)
    p = subprocess.run([sys.executable, "-c", _LOCATE.format(classes=classes)], capture_output=True,
                       text=True, env=env, timeout=120)
    assert p.returncode == 0, p.stderr
    kind, path = p.stdout.split()
    if expect == "tmp":
        assert kind == "FunctionCache"
        assert path.startswith(str(tmp_path / f"rasterhw-numba-{os.getuid()}")), path
    else:
        assert kind == "NullCache"


def test_default_cache_is_beside_the_module():
    from rasterhw.golden_model import reference_fast as F

    if os.environ.get("NUMBA_CACHE_DIR"):
        pytest.skip("NUMBA_CACHE_DIR is set")
    assert F._band._cache.cache_path == os.path.join(os.path.dirname(F.__file__), "__pycache__")
