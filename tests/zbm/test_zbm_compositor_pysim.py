"""Pysim tests of the last stage's alpha-composite (hdl/zbm/compositor.py) against the golden
``composite`` (golden_model/zbm/composite.py), on random and on c300 stimulus."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.composite import composite
from rasterhw.golden_model.zbm.words import pixel2_words
from rasterhw.hdl.zbm.compositor import ZbmCompositor
from rasterhw.sim.engines.harness import run_stream

pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")

C300_WIDTH = 512  # a c300 frame's line (rasterhw sim zbm --scene c300: 512 x 512)


def random_pixels(rng: np.random.Generator, shape) -> G.DoubleZ:
    """Random double-Z pixels with every case: both empty, s1 empty, opaque, translucent,
    alpha 0 and 255 fronts (z sorted, s0 nearer)."""
    d = G.DoubleZ.empty(shape)
    z = np.sort(rng.integers(0, F.Z_MAX_SAMPLE + 1, shape + (2,)), axis=-1)
    z[rng.random(shape + (2,)) < 0.25] = F.Z_EMPTY
    d.z[:] = np.sort(z, axis=-1)
    a = rng.integers(0, 256, shape + (2,))
    pick = rng.random(shape + (2,))
    a[pick < 0.2] = 255
    a[(pick >= 0.2) & (pick < 0.3)] = 0
    d.a[:] = a
    d.c[:] = rng.integers(0, 256, shape + (2, 4))
    d.c[..., 3] = 0
    return d


def run_compositor(words, *, background=(0, 0, 0), seed=0, p_stall=0.3, p_gap=0.3):
    return run_stream(ZbmCompositor(background=background), words, seed=seed, p_stall=p_stall, p_gap=p_gap)


def rgb_words(img: np.ndarray) -> list[int]:
    """(..., 3) uint8 -> r | g << 8 | b << 16 per pixel, row-major."""
    f = np.asarray(img, np.int64).reshape(-1, 3)
    return [int(v) for v in f[:, 0] | f[:, 1] << 8 | f[:, 2] << 16]


def mismatches(got: list[int], want: list[int]) -> int:
    if len(got) != len(want):
        return max(len(got), len(want))
    return sum(g != w for g, w in zip(got, want, strict=True))


def test_compositor_matches_golden_random_c300_lines():
    """Four 512-px lines (c300's line length) of random double-Z pixels, random gaps and stalls,
    a non-black background; and a corrupted expected value must be caught."""
    rng = np.random.default_rng(11)
    px = random_pixels(rng, (4, C300_WIDTH))
    bg = (17, 200, 99)
    want = rgb_words(composite(px, background=bg))
    got = run_compositor(pixel2_words(px), background=bg, seed=5)
    assert mismatches(got, want) == 0
    # the comparison can fail: one corrupted expected pixel is one mismatch
    bad = list(want)
    bad[1234] ^= 1 << 9
    assert mismatches(got, bad) == 1
    # the stimulus covers every case of the formula
    v0, v1 = px.z[..., 0] != F.Z_EMPTY, px.z[..., 1] != F.Z_EMPTY
    a0 = px.a[..., 0]
    assert (~v0).any() and (v0 & ~v1).any() and (v0 & v1 & (a0 < 255) & (a0 > 0)).any()
    assert (v0 & (a0 == 255)).any() and (v0 & (a0 == 0)).any()


def test_compositor_on_c300_frame_lines():
    """Lines of the golden c300 frame (colour mode, interleave 8) through the HDL: = composite."""
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.pipeline import run_geometry

    tris = run_geometry(load_scene("c300"), C300_WIDTH, C300_WIDTH)
    res = G.render_zbm(tris, interleave=8)
    rows = slice(250, 253)
    sub = G.DoubleZ(res.pixels.z[rows], res.pixels.a[rows], res.pixels.c[rows], res.pixels.tag[rows])
    assert (sub.z[..., 0] != F.Z_EMPTY).sum() > 100
    got = run_compositor(pixel2_words(sub), seed=1, p_stall=0.0, p_gap=0.0)
    assert mismatches(got, rgb_words(composite(sub))) == 0
    assert mismatches(got, rgb_words(res.rgb8[rows])) == 0


def test_compositor_exhaustive_alpha_one_channel():
    """Every (alpha, colour) of a translucent front over an opaque back, checked against the
    formula written out here (independent of the golden module)."""
    a, c = np.meshgrid(np.arange(256), np.arange(0, 256, 15))
    a, c = a.ravel(), c.ravel()
    n = a.size
    px = G.DoubleZ.empty((n,))
    px.z[:, 0], px.z[:, 1] = 5, 9
    px.a[:, 0], px.a[:, 1] = a, 255
    px.c[:, 0, :3] = c[:, None]
    px.c[:, 1, :3] = 77
    got = run_compositor(pixel2_words(px), p_stall=0.0, p_gap=0.0)
    r = (a * c + (255 - a) * 77 + 127) // 255
    assert [g & 0xFF for g in got] == [int(v) for v in r]


def test_compositor_bad_background():
    with pytest.raises(ValueError, match="background"):
        ZbmCompositor(background=(0, 0, 256))
    with pytest.raises(ValueError, match="background"):
        ZbmCompositor(background=(0, 0))


@pytest.mark.slow
def test_compositor_matches_golden_random_c300_frame():
    """A whole c300-sized frame (512 x 512) of random pixels (~3.5 min in pysim on this machine)."""
    px = random_pixels(np.random.default_rng(12), (C300_WIDTH, C300_WIDTH))
    want = rgb_words(composite(px, background=(40, 40, 40)))
    got = run_compositor(pixel2_words(px), background=(40, 40, 40), p_stall=0.1, p_gap=0.1)
    assert mismatches(got, want) == 0
