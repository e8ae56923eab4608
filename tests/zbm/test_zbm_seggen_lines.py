"""``seggen.segment_generator`` (every pair's lines at once) equals the line-by-line loop it
replaced, kept here as the specification: every segment field, the per-line counts, the stats,
the capacity error, for colour and mapping streams, clipped frames and the empty stream."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm.edgepair import EdgePairs
from rasterhw.golden_model.zbm.formats import (
    AEP_CAPACITY,
    HALF_X,
    MAX_WIDTH,
    MODE_MAPPING,
    OFF_FRAC,
    X_FRAC,
    wrap,
)
from rasterhw.golden_model.zbm.seggen import Segments, _px_ceil, check_edge_pair_stream


def _by_lines(eps: EdgePairs, height: int, *, width: int = MAX_WIDTH, capacity: int = AEP_CAPACITY) -> Segments:
    """The segment generator as written before its vectorisation (line by line): the specification
    (its argument checks, unchanged, left out)."""
    n = len(eps)
    check_edge_pair_stream(eps, height, who="segment generator")
    C = eps.val.shape[1]
    x = eps.x.copy()
    ln = eps.len.copy()
    val = eps.val.copy()
    left = eps.h.copy()
    active = np.zeros(0, np.int64)
    nxt = 0
    out = {k: [] for k in ("y", "x", "len", "val", "inc", "ep")}
    line_start = np.zeros(height + 1, np.int64)
    loads = np.zeros(height, np.int64)
    empty = np.zeros(height, np.int64)
    aep_max = 0
    count = 0
    for y in range(height):
        # (1) loader
        start = nxt
        while nxt < n and eps.y[nxt] <= y:
            nxt += 1
        if active.size + (nxt - start) > capacity:
            raise RasterhwError(f"segment generator: line {y} needs {active.size + nxt - start} "
                                f"simultaneously active edge pairs, more than the active-edge-pair "
                                f"memory's capacity {int(capacity)} (the hardware stalls with "
                                f"'overflow'; split the stream or raise capacity)")
        active = np.concatenate([active, np.arange(start, nxt)])
        loads[y] = nxt - start
        aep_max = max(aep_max, active.size)
        # (2) emit
        if active.size:
            a = active
            xs = np.maximum(_px_ceil(x[a]), 0)
            xe = np.minimum(_px_ceil(x[a] + ln[a]), width)
            cnt = xe - xs
            ok = cnt > 0
            empty[y] = int((~ok).sum())
            k = a[ok]
            if k.size:
                off = ((xs[ok] << X_FRAC) + HALF_X - x[k]) >> (X_FRAC - OFF_FRAC)   # Q.16, >= 0
                oi = (off >> OFF_FRAC)[:, None]
                of = (off & ((1 << OFF_FRAC) - 1))[:, None]
                d = eps.ddx[k]
                v0 = wrap(val[k] + oi * d + ((of * d) >> OFF_FRAC))
                for key, arr in (("y", np.full(k.size, y)), ("x", xs[ok]), ("len", cnt[ok]),
                                 ("val", v0), ("inc", d), ("ep", k)):
                    out[key].append(arr)
                count += k.size
            # step
            x[a] = wrap(x[a] + eps.dxdy[a])
            ln[a] = wrap(ln[a] + eps.dlendy[a])
            val[a] = wrap(val[a] + eps.ddy[a])
            left[a] -= 1
            active = a[left[a] > 0]
        line_start[y + 1] = count
    cat = {k: (np.concatenate(v) if v else np.zeros((0, C) if k in ("val", "inc") else 0, np.int64))
           for k, v in out.items()}
    stats = {"segments": count, "empty_segments": int(empty.sum()), "aep_max": aep_max,
             "aep_capacity": int(capacity),
             "edge_pairs": n}
    return Segments(cat["y"].astype(np.int64), cat["x"].astype(np.int64), cat["len"].astype(np.int64),
                    cat["val"].astype(np.int64), cat["inc"].astype(np.int64), cat["ep"].astype(np.int64),
                    eps.tag[cat["ep"].astype(np.int64)] if n else cat["ep"].astype(np.int64),
                    line_start, loads, empty, eps.mode, stats)



FIELDS = ("y", "x", "len", "val", "inc", "ep", "tag", "line_start", "loads", "empty")


def _same(a, b):
    for f in FIELDS:
        u, v = getattr(a, f), getattr(b, f)
        assert u.dtype == v.dtype and u.shape == v.shape and np.array_equal(u, v), f
    assert a.mode == b.mode and a.stats == b.stats


def _mapping(tris):
    tris.uv = np.random.default_rng(4).random((tris.n_triangles, 3, 2)) * 4 - 2
    return tris


CASES = [("c300 512", lambda: run_geometry(build_scene("c300"), 512, 512), 512, {}),
         ("random", lambda: ref.random_triangles(64, 48, 80, mean_area=150, seed=3), 64, {}),
         ("mapping", lambda: _mapping(ref.random_triangles(40, 30, 40, mean_area=120, seed=5)), 40, {"mode": MODE_MAPPING}),
         ("clipped to 24 wide", lambda: ref.random_triangles(64, 48, 80, mean_area=300, seed=7), 24, {})]


@pytest.mark.parametrize("name,make,width,kw", CASES, ids=[c[0] for c in CASES])
def test_segment_generator_equals_the_line_loop(name, make, width, kw):
    tris = make()
    eps = G.edge_pairs(tris, **kw)
    a = G.segment_generator(eps, tris.height, width=width)
    _same(a, _by_lines(eps, tris.height, width=width))
    assert a.stats["segments"] > 0 and a.stats["aep_max"] > 1
    if name.startswith("clipped"):
        assert a.stats["empty_segments"] > 0                 # segments wholly right of the frame


def test_the_same_capacity_error_and_the_empty_stream():
    eps = G.edge_pairs(ref.random_triangles(64, 48, 80, mean_area=150, seed=3))
    cap = G.max_active_edge_pairs(eps)[0] - 1
    msgs = []
    for f in (G.segment_generator, _by_lines):
        with pytest.raises(RasterhwError) as e:
            f(eps, 48, width=64, capacity=cap)
        msgs.append(str(e.value))
    assert msgs[0] == msgs[1] and "simultaneously active" in msgs[0]
    none = eps.take(np.zeros(0, np.int64))
    _same(G.segment_generator(none, 48, width=64), _by_lines(none, 48, width=64))
