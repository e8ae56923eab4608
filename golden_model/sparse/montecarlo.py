"""Monte-Carlo window counts per level: polygons of one area and shape at random positions and
rotations on one processor's window lattice (seed 002: counts are means "на множестве
многоугольников, одинаковых по площади и форме, но разных по расположению на растре").

Level ``i`` of a ``p x q`` matrix with ``2**n x 2**n`` sparse rasters has window centres on a
lattice of periods ``Px = p*2**(n-i)``, ``Py = q*2**(n-i)`` px and windows of
``[p(2**(n-i) - 1) + alpha] x [q(2**(n-i) - 1) + beta]`` px. A position uniform over one period
of level 1 is uniform modulo every finer period, so one random offset per polygon serves every
level (and every processor: processors differ only by the lattice offset). The lattice is taken
unbounded (polygons well inside the raster), as the paper's counts are.

Two coverage tests:

* ``"exact"`` — the window rectangle meets the polygon (separating axes: the polygon's edge
  normals and the two axes). The mean count is then exactly the filtered area ("площадь
  фильтрованного многоугольника") over the cell area.
* ``"edges"`` — only the polygon's edges (what a raster processor holding edge equations tests,
  and what :mod:`.search` does): a window survives unless one edge has the whole window outside.
  It also accepts windows near a vertex that miss the polygon.

Counting is exact per polygon: the windows a polygon generates are the lattice points inside the
convex region {c : G c <= h} (one half-plane per test), counted column by column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["MCResult", "count_windows", "rectangles", "triangles_from_scene", "level_counts", "s_k_measured"]

Z95 = 1.959963984540054


@dataclass
class MCResult:
    """Mean windows per level with 95 % intervals. Arrays are indexed by level 1..n (index 0 unused)."""

    mean: np.ndarray
    half95: np.ndarray
    samples: int

    @property
    def lo(self) -> np.ndarray:
        return self.mean - self.half95

    @property
    def hi(self) -> np.ndarray:
        return self.mean + self.half95


def rectangles(S, M: int, *, aspect: float = 5.0, seed: int = 0, rng=None,
               rotation: float | None = None) -> np.ndarray:
    """``M`` rectangles of area ``S`` and sides ``aspect : 1`` at random rotation (or at the fixed
    angle ``rotation``, radians), centred at a random point of the unit square (scaled by the
    caller), CCW: ``(M, 4, 2)``. The shape and the random numbers depend on ``seed`` only, so
    counts are monotone in ``S`` for a fixed seed."""
    rng = np.random.default_rng(seed) if rng is None else rng
    theta = rng.random(M) * math.pi
    if rotation is not None:
        if not math.isfinite(rotation):
            raise RasterhwError(f"sparse Monte-Carlo: rotation must be a finite angle, not {rotation!r}")
        theta = np.full(M, float(rotation))
    off = rng.random((M, 2))
    a = math.sqrt(S * aspect) / 2.0
    b = math.sqrt(S / aspect) / 2.0
    base = np.array([[-a, -b], [a, -b], [a, b], [-a, b]])
    c, s = np.cos(theta), np.sin(theta)
    rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (M, 2, 2)
    return np.einsum("mij,kj->mki", rot, base), off


def triangles_from_scene(xy: np.ndarray, M: int, *, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``M`` triangles drawn (with replacement) from a scene's screen triangles ``(T, 3, 2)``, each
    centred on its centroid, randomly rotated; degenerate ones (area < 1e-6 px) are skipped.
    Returns ``(polys (M, 3, 2) CCW, offsets (M, 2) in [0, 1))``."""
    xy = np.asarray(xy, dtype=np.float64)
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    ar = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    good = np.flatnonzero(np.abs(ar) > 1e-6)
    if good.size == 0:
        raise RasterhwError("sparse Monte-Carlo: the scene has no triangle of non-zero area")
    rng = np.random.default_rng(seed)
    pick = good[rng.integers(0, good.size, M)]
    t = xy[pick] - xy[pick].mean(axis=1, keepdims=True)
    flip = ar[pick] < 0
    t[flip] = t[flip][:, ::-1]
    theta = rng.random(M) * 2 * math.pi
    c, s = np.cos(theta), np.sin(theta)
    rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    return np.einsum("mij,mkj->mki", rot, t), rng.random((M, 2))


def _halfplanes(poly: np.ndarray, hx: float, hy: float, test: str):
    """Constraints ``G c <= h`` on window centres ``c``: (M, K', 2), (M, K')."""
    v0 = poly
    v1 = np.roll(poly, -1, axis=1)
    e = v1 - v0
    nrm = np.stack([e[..., 1], -e[..., 0]], -1)  # outward for CCW
    d = np.einsum("mkj,mkj->mk", nrm, v0)
    h = d + np.abs(nrm[..., 0]) * hx + np.abs(nrm[..., 1]) * hy
    if test == "edges":
        return nrm, h
    lo = poly.min(axis=1)
    hi = poly.max(axis=1)
    M = poly.shape[0]
    ax = np.broadcast_to(np.array([[1.0, 0], [-1, 0], [0, 1], [0, -1]]), (M, 4, 2))
    hb = np.stack([hi[:, 0] + hx, -(lo[:, 0] - hx), hi[:, 1] + hy, -(lo[:, 1] - hy)], -1)
    return np.concatenate([nrm, ax], 1), np.concatenate([h, hb], 1)


def _xrange(poly, G, h, hx, test):
    """x extent of the region: the bbox grown by the window (exact) or the offset polygon (edges)."""
    if test == "exact":
        return poly[:, :, 0].min(1) - hx, poly[:, :, 0].max(1) + hx
    g0, h0 = G, h
    g1, h1 = np.roll(G, -1, axis=1), np.roll(h, -1, axis=1)
    det = g0[..., 0] * g1[..., 1] - g0[..., 1] * g1[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (h0 * g1[..., 1] - h1 * g0[..., 1]) / det
    x = np.where(np.isfinite(x), x, np.nan)
    return np.nanmin(x, 1), np.nanmax(x, 1)


def count_windows(poly: np.ndarray, Px: float, Py: float, hx: float, hy: float, *,
                  test: str = "exact", budget: int = 1 << 22) -> np.ndarray:
    """Windows (lattice points ``(Px j, Py l)`` with half sizes ``hx, hy``) each polygon generates.

    ``poly``: (M, K, 2) convex polygons, counter-clockwise, already placed. Returns (M,) int64.
    """
    if test not in ("exact", "edges"):
        raise RasterhwError(f"sparse Monte-Carlo: test must be 'exact' or 'edges', not {test!r}")
    poly = np.asarray(poly, dtype=np.float64)
    G, h = _halfplanes(poly, hx, hy, test)
    x0, x1 = _xrange(poly, G, h, hx, test)
    j0 = np.ceil(x0 / Px - 1e-9).astype(np.int64)
    j1 = np.floor(x1 / Px + 1e-9).astype(np.int64)
    ncol = np.maximum(j1 - j0 + 1, 0)
    out = np.zeros(poly.shape[0], dtype=np.int64)
    order = np.argsort(ncol, kind="stable")
    K = G.shape[1]
    start = 0
    M = poly.shape[0]
    while start < M:
        J = max(int(ncol[order[min(M - 1, start)]]), 1)
        # grow the chunk while the padded grid stays within budget
        end = start + 1
        step = max(1, budget // (J * K * 4))
        end = min(M, start + step)
        J = max(int(ncol[order[end - 1]]), 1)
        while end - start > 1 and (end - start) * J * K > budget:
            end = start + max(1, (end - start) // 2)
            J = max(int(ncol[order[end - 1]]), 1)
        idx = order[start:end]
        jj = j0[idx, None] + np.arange(J)[None, :]  # (m, J)
        valid = jj <= j1[idx, None]
        x = jj * Px
        g = G[idx]  # (m, K, 2)
        hh = h[idx]
        gx, gy = g[:, None, :, 0], g[:, None, :, 1]
        rhs = hh[:, None, :] - gx * x[:, :, None]  # gy * y <= rhs
        with np.errstate(divide="ignore", invalid="ignore"):
            b = rhs / gy
        ub = np.where(gy > 0, b, np.inf).min(-1)
        lb = np.where(gy < 0, b, -np.inf).max(-1)
        xok = np.where(gy == 0, rhs >= 0, True).all(-1)
        cnt = np.floor(ub / Py + 1e-9) - np.ceil(lb / Py - 1e-9) + 1
        cnt = np.where(valid & xok & np.isfinite(cnt), np.maximum(cnt, 0), 0)
        out[idx] = cnt.sum(1).astype(np.int64)
        start = end
    return out


def level_geometry(i: int, n: int, p: int, q: int, alpha: float, beta: float) -> tuple[float, float, float, float]:
    """``(Px, Py, hx, hy)`` of level ``i``: lattice periods and window half sizes in px."""
    N = 1 << (n - i)
    return p * N, q * N, (p * (N - 1) + alpha) / 2.0, (q * (N - 1) + beta) / 2.0


def level_counts(poly: np.ndarray, off: np.ndarray, n: int, p: int, q: int | None = None, *,
                 alpha: float = 2.0, beta: float | None = None, test: str = "exact",
                 levels=None) -> MCResult:
    """Mean windows per level (1..n) over the polygons ``poly`` (centred at 0) placed at
    ``off * (p 2**(n-1), q 2**(n-1))``; 95 % intervals from the sample standard deviation."""
    q = p if q is None else q
    beta = alpha if beta is None else beta
    M = poly.shape[0]
    if M < 2:
        raise RasterhwError("sparse Monte-Carlo: need at least 2 samples")
    mean = np.full(n + 1, np.nan)
    half = np.full(n + 1, np.nan)
    mean[0], half[0] = 1.0, 0.0
    shift = off * np.array([p * (1 << (n - 1)), q * (1 << (n - 1))], dtype=np.float64)
    placed = poly + shift[:, None, :]
    for i in (range(1, n + 1) if levels is None else levels):
        Px, Py, hx, hy = level_geometry(i, n, p, q, alpha, beta)
        c = count_windows(placed, Px, Py, hx, hy, test=test)
        mean[i] = c.mean()
        half[i] = Z95 * c.std(ddof=1) / math.sqrt(M)
    return MCResult(mean=mean, half95=half, samples=M)


def s_k_measured(k: int, *, m: int = 10, alpha: float = 2.0, aspect: float = 5.0, M: int = 20000,
                 seed: int = 0, test: str = "exact", rotation: float | None = None) -> tuple[float, float, float]:
    """The area where the measured pixel-level count is 1 (5:1 rectangles, ``p = q = 2**k``;
    ``rotation``: one fixed angle instead of uniform rotations).

    Bisection on the sample mean (monotone in S for fixed random numbers); the 95 % interval by
    the delta method, ``S_k -+ 1.96 sd(w_n) / (sqrt(M) dw_n/dS)``. Returns ``(S_k, lo, hi)``.
    """
    p = 1 << k
    n = m - k
    Px, Py, hx, hy = level_geometry(n, n, p, p, alpha, alpha)

    def stats(S):
        poly, off = rectangles(max(S, 1e-12), M, aspect=aspect, seed=seed, rotation=rotation)
        c = count_windows(poly + off[:, None, :] * np.array([Px, Py]) * 4, Px, Py, hx, hy, test=test)
        return c.mean(), c.std(ddof=1)

    w0, _ = stats(0.0)
    if w0 >= 1.0:
        return 0.0, 0.0, 0.0
    lo, hi = 0.0, 4.0 ** k
    for _ in range(32):  # 4**k / 2**32: far below the sampling interval
        mid = 0.5 * (lo + hi)
        if stats(mid)[0] < 1.0:
            lo = mid
        else:
            hi = mid
    S = 0.5 * (lo + hi)
    w, sd = stats(S)
    dS = max(0.05 * S, 0.05)
    slope = (stats(S + dS)[0] - stats(max(S - dS, 0.0))[0]) / (S + dS - max(S - dS, 0.0))
    half = Z95 * sd / math.sqrt(M) / slope if slope > 0 else float("inf")
    return S, S - half, S + half
