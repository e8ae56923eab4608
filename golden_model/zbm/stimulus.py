"""Seeded random ZB/M stimulus for the benches: segments, upstream pixels, screen triangles."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.zbm import formats as F

__all__ = ["first_triangles", "multi_line_segments", "random_doublez", "random_segments", "random_triangles"]


def random_segments(rng: np.random.Generator, n: int, width: int, mode: int = F.MODE_COLOUR,
                    y: int = 0) -> G.Segments:
    """``n`` random segments on line ``y`` with overlapping depths (Z ties included)."""
    C = len(F.CHANNELS[mode])
    x = rng.integers(0, width, n)
    ln = np.minimum(rng.integers(1, 24, n), width - x)
    val = np.zeros((n, C), np.int64)
    inc = np.zeros((n, C), np.int64)
    val[:, 0] = rng.integers(0, 40, n) << F.ATTR_FRAC          # depths that collide often
    inc[:, 0] = rng.integers(-3 << F.ATTR_FRAC, 3 << F.ATTR_FRAC, n) * rng.integers(0, 2, n)
    val[:, 1:] = rng.integers(-40 << F.ATTR_FRAC, 300 << F.ATTR_FRAC, (n, C - 1))   # clamps too
    inc[:, 1:] = rng.integers(-20 << F.ATTR_FRAC, 20 << F.ATTR_FRAC, (n, C - 1))
    if n:
        val[0, 0] = -(5 << F.ATTR_FRAC)                            # z clamps at 0
        val[-1, 0] = (1 << 48) - 1                                 # and at Z_MAX_SAMPLE
    z1 = np.zeros(n, np.int64)
    return G.Segments(np.full(n, y), x, ln, val, inc, np.arange(n), np.arange(n),
                      np.array([0] * (y + 1) + [n]), z1, z1, mode)


def multi_line_segments(rng: np.random.Generator, counts: list[int], width: int,
                        mode: int = F.MODE_COLOUR) -> G.Segments:
    """Random segments on lines 0..len(counts)-1 (``counts[y]`` on line y)."""
    parts = [random_segments(rng, c, width, mode, y=0) for c in counts]
    cat = {k: np.concatenate([getattr(p, k) for p in parts]) for k in ("x", "len", "val", "inc")}
    ys = np.concatenate([np.full(c, y) for y, c in enumerate(counts)]).astype(np.int64)
    n = ys.size
    line_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    z1 = np.zeros(len(counts), np.int64)
    return G.Segments(ys, cat["x"], cat["len"], cat["val"], cat["inc"], np.arange(n), np.arange(n),
                      line_start, z1, z1, mode)


def random_doublez(rng: np.random.Generator, n: int) -> G.DoubleZ:
    """Random upstream merge-input pixels (s0 nearer or equal; some empty)."""
    d = G.DoubleZ.empty((n,))
    z = np.sort(rng.integers(0, 40, (n, 2)), axis=1)
    z[rng.random((n, 2)) < 0.3] = F.Z_EMPTY
    d.z[:] = np.sort(z, axis=1)
    d.a[:] = rng.integers(0, 256, (n, 2))
    d.c[:] = rng.integers(0, 256, (n, 2, 4))
    d.a[d.z == F.Z_EMPTY] = 0
    d.c[d.z == F.Z_EMPTY] = 0
    return d


def random_triangles(rng: np.random.Generator, n: int, width: int, height: int, size: float = 12.0):
    """``n`` random screen triangles (some partly off screen) as ScreenTriangles."""
    c = rng.uniform([-4, -4], [width + 4, height + 4], (n, 1, 2))
    xy = c + rng.uniform(-size, size, (n, 3, 2))
    z = rng.uniform(0.1, 0.9, (n, 3))
    return ScreenTriangles(width=width, height=height, xy=xy, z=z,
                           zq=np.round(z * ((1 << 24) - 1)).astype(np.int64),
                           colour=rng.uniform(0, 1, (n, 3, 3)), poly_id=np.arange(n),
                           uv=rng.uniform(0, 1, (n, 3, 2)))


def first_triangles(tris: ScreenTriangles, k: int) -> ScreenTriangles:
    """The first ``k`` triangles of ``tris`` (submission order kept)."""
    cut = {f: getattr(tris, f)[:k] for f in ("xy", "z", "zq", "colour", "poly_id")}
    if tris.uv is not None:
        cut["uv"] = tris.uv[:k]
    return replace(tris, **cut)
