"""The vectorised Z resolve of the reference rasteriser (one comparison for fragments alone at
their pixel, sorted runs for the rest) against a per-pixel serial Z-buffer by brute force
(tests/brute.py, plain Python, no shared code), on scenes built for deep overdraw and
depth ties, with chunk boundaries anywhere."""

from __future__ import annotations

import brute
import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model.screen import ScreenTriangles

W, H = 24, 16


def stacked_scene(seed: int) -> ScreenTriangles:
    """30-50 triangles over a 24x16 frame, most of them over its middle (runs of 10 and
    more fragments per pixel), vertices on pixel centres or corners half the time, depths
    from a set of four values (ties everywhere, also with earlier chunks), exact duplicates
    and shared edges."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(30, 51))
    centre = rng.random((n, 1, 2)) * [8, 6] + [8, 5]
    off = (rng.random((n, 3, 2)) - 0.5) * rng.choice([6.0, 12.0, 30.0], (n, 1, 1))
    xy = centre + off
    on_grid = rng.random(n) < 0.5
    xy[on_grid] = np.floor(xy[on_grid] * 2) / 2  # pixel centres and corners
    for t in range(1, n):
        r = rng.random()
        if r < 0.15:  # exact duplicate of an earlier triangle: a tie at every pixel
            xy[t] = xy[int(rng.integers(t))]
        elif r < 0.3:  # shares an edge with an earlier one (on the other side of it)
            s = int(rng.integers(t))
            xy[t, 0], xy[t, 1] = xy[s, 1], xy[s, 0]
    levels = np.array([0.2, 0.4, 0.4, 0.7])
    z = np.where(rng.random((n, 1)) < 0.7, levels[rng.integers(0, 4, (n, 1))],
                 rng.random((n, 3)))  # mostly flat at a shared level, some sloped
    z = np.broadcast_to(z, (n, 3)).copy()
    colour = rng.random((n, 3, 3))
    return ScreenTriangles(width=W, height=H, xy=xy, z=z, zq=np.zeros((n, 3), np.int64),
                           colour=colour, poly_id=np.arange(n, dtype=np.int64) * 7)


def brute_colour(tris: ScreenTriangles, tri_id: np.ndarray) -> np.ndarray:
    """Gouraud colour of the brute-force winner at each pixel (the documented formula,
    brute.py's integer edge functions), background 0."""
    pts = brute._snapped(tris)
    out = np.zeros((tris.height, tris.width, 3))
    for row in range(tris.height):
        for col in range(tris.width):
            t = int(tri_id[row, col])
            if t < 0:
                continue
            p = pts[t]
            cx, cy = brute.GRID * col + brute.GRID // 2, brute.GRID * row + brute.GRID // 2
            area = float(brute._cross(*p[0], *p[1], *p[2]))
            w1 = float(brute._cross(*p[2], *p[0], cx, cy)) / area
            w2 = float(brute._cross(*p[0], *p[1], cx, cy)) / area
            w0 = (1.0 - w1) - w2
            c = tris.colour[t]
            out[row, col] = w0 * c[0] + w1 * c[1] + w2 * c[2]
    return out


@pytest.mark.parametrize("engine, chunk", [("numpy", 1 << 18), ("numpy", 64), ("numpy", 7), ("numba", None)])
@pytest.mark.parametrize("seed", range(4))
def test_equals_serial_zbuffer_with_ties(seed, engine, chunk, monkeypatch):
    """The NumPy code with chunk boundaries anywhere, and the numba fast path (no chunks)."""
    if engine == "numba":
        pytest.importorskip("numba")
    monkeypatch.setenv(ref.ENGINE_ENV, engine)
    if chunk is not None:
        monkeypatch.setattr(ref, "CHUNK_CANDIDATES", chunk)
    tris = stacked_scene(seed)
    frame = ref.rasterise(tris)
    tri_id, depth, written = brute.brute_visible(tris)
    cov = brute.brute_coverage(tris)
    depth_of_run = cov.sum(axis=0).max()
    assert depth_of_run >= 8, "no deep overdraw: the sorted-run path would go untested"
    assert written > int((tri_id >= 0).sum()), "no pixel written twice: the test proves little"
    np.testing.assert_array_equal(frame.tri_id, tri_id)
    np.testing.assert_array_equal(frame.depth, depth)
    np.testing.assert_array_equal(frame.poly_id, np.where(tri_id >= 0, tri_id * 7, -1))
    assert frame.pixels_written == written
    assert frame.fragments == int(cov.sum())
    assert frame.pixels_covered == int((tri_id >= 0).sum())
    np.testing.assert_array_equal(frame.colour, brute_colour(tris, tri_id))


@pytest.mark.parametrize("engine", ["numpy", "numba"])
def test_tiles_equal_whole_frame(engine, monkeypatch):
    """rasterise_rgb8 renders in tiles of rows: same image and counts as rasterise."""
    monkeypatch.setenv(ref.ENGINE_ENV, engine)
    tris = stacked_scene(11)
    frame = ref.rasterise(tris)
    old = ref.TILE_PIXELS
    try:
        ref.TILE_PIXELS = 3 * W  # three rows per tile
        rgb8, counts = ref.rasterise_rgb8(tris)
    finally:
        ref.TILE_PIXELS = old
    np.testing.assert_array_equal(rgb8, frame.to_rgb8())
    assert counts == {"fragments": frame.fragments, "pixels_written": frame.pixels_written,
                      "pixels_covered": frame.pixels_covered}
