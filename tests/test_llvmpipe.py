"""sim/report/llvmpipe.py: Mesa llvmpipe draws the reference's screen triangles (coverage and
visible triangle compared with ours), and the bench keeps its llvmpipe rows, with no value
and the reason, where moderngl or EGL is missing."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.sim.report import bench, llvmpipe


def _gl(width: int, height: int) -> llvmpipe.Llvmpipe:
    try:
        return llvmpipe.Llvmpipe(width, height)
    except llvmpipe.Unavailable as e:
        pytest.skip(str(e))


def fill_rule_scene(seed: int, width: int = 40, height: int = 30) -> ScreenTriangles:
    """A mesh of triangles on a grid whose vertices sit on pixel centres and corners (edges
    through pixel centres everywhere: the fill rule decides), plus loose triangles over it;
    one flat depth per triangle, all distinct and far apart (so float32 depth cannot change
    a winner)."""
    rng = np.random.default_rng(seed)
    xs = np.arange(0, width + 1, 4, dtype=float)
    ys = np.arange(0, height + 1, 3, dtype=float)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx, gy], axis=-1) + rng.choice([0.0, 0.5], gx.shape + (2,))
    tris = []
    for r in range(len(ys) - 1):
        for c in range(len(xs) - 1):
            a, b, d, e = pts[r, c], pts[r, c + 1], pts[r + 1, c], pts[r + 1, c + 1]
            tris += [(a, b, d), (b, e, d)] if (r + c) % 2 else [(a, b, e), (a, e, d)]
    loose = rng.integers(0, [width, height], (12, 3, 2)) + rng.choice([0.0, 0.5], (12, 3, 2))
    xy = np.concatenate([np.array(tris), loose])
    n = xy.shape[0]
    z = np.repeat(rng.permutation(n)[:, None] / n * 0.9 + 0.05, 3, axis=1)
    return ScreenTriangles(width=width, height=height, xy=xy, z=z, zq=np.zeros((n, 3), np.int64),
                           colour=rng.random((n, 3, 3)), poly_id=np.arange(n, dtype=np.int64))


@pytest.mark.parametrize("seed", range(3))
def test_llvmpipe_coverage_and_winners_equal_ours(seed):
    tris = fill_rule_scene(seed)
    ours = rasterise(tris)
    gl = _gl(tris.width, tris.height)
    try:
        rgba, ids = gl.draw(gl.load(tris))
    finally:
        gl.close()
    assert (ours.tri_id >= 0).sum() > 0.8 * tris.width * tris.height
    np.testing.assert_array_equal(ids >= 0, ours.tri_id >= 0)
    np.testing.assert_array_equal(ids, ours.tri_id)
    # Gouraud colour agrees to 8 bits (llvmpipe interpolates in float32 and rounds its own way)
    diff = np.abs(rgba[..., :3].astype(int) - ours.to_rgb8().astype(int))
    assert diff.max() <= 2


def test_compare_reports_times_and_diffs():
    tris = fill_rule_scene(5)
    _gl(tris.width, tris.height).close()
    r = llvmpipe.compare(tris, 3, lambda: rasterise(tris))
    assert r["coverage_diff"] == 0 and r["winner_diff"] == 0
    assert r["ours_s"] > 0 and r["llvmpipe_s"] > 0
    assert r["ratio"] == pytest.approx(r["ours_s"] / r["llvmpipe_s"])
    assert r["repeat"] == 3 and "llvmpipe" in r["renderer"]


def test_bench_rows_say_why_when_llvmpipe_is_missing(monkeypatch):
    def missing(*a, **k):
        raise llvmpipe.Unavailable("moderngl not installed (test)")

    monkeypatch.setattr(llvmpipe, "Llvmpipe", missing)
    tris = fill_rule_scene(1)
    rows = bench._raster_rows("mesh", tris, 2)
    assert [r["unit"] for r in rows] == ["ms", "ms", "ms", "x"]
    assert rows[0]["value"] > 0 and 0 < rows[1]["value"] <= rows[0]["value"]
    for r in rows[2:]:
        assert r["value"] is None
        assert "moderngl not installed (test)" in r["note"]
