"""The coupled-matrix cycle model (golden_model/sparse/cycles.py): its invariants on c300, and an
independent cycle-by-cycle simulation of the same semantics on random service times."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.sparse.cycles import (
    SETUP_CYCLES,
    coupled_matrix,
    matrix_cycles,
    service_times,
    stage_cycles,
)
from rasterhw.golden_model.sparse.search import sparse_render


def _step_sim(s: np.ndarray, D: int, g: int) -> dict:
    """Cycle by cycle, with explicit queues: registered FIFO levels at the start of a cycle decide
    the push; a processor pops a record pushed on an earlier cycle when it is free."""
    P, T = s.shape
    q = [deque() for _ in range(P)]
    free_at = [0] * P
    nxt, avail = 0, 0
    offer, bc = [], []
    pop = np.full((P, T), -1)
    peak = [0] * P
    c = 0
    while nxt < T or any(q) or any(f > c for f in free_at):
        levels = [len(x) for x in q]
        push = nxt < T and c >= avail and all(v < D for v in levels)
        pops = [k for k in range(P) if levels[k] > 0 and free_at[k] <= c]
        # the edge at the end of cycle c
        for k in pops:
            t = q[k].popleft()
            pop[k, t] = c
            free_at[k] = c + int(s[k, t])
        if push:
            offer.append(avail)
            bc.append(c)
            for x in q:
                x.append(nxt)
            nxt += 1
            avail = c + g
        for k in range(P):
            peak[k] = max(peak[k], len(q[k]))
        c += 1
        if c > 10_000_000:
            raise AssertionError("runaway")
    frame = max(free_at) if T else 0
    return {"frame": frame, "stall": int(sum(b - o for b, o in zip(bc, offer, strict=True))), "pop": pop,
            "bc": np.array(bc), "peak": np.array(peak)}


@pytest.mark.parametrize("seed", range(6))
def test_coupled_model_equals_a_cycle_by_cycle_simulation(seed):
    rng = np.random.default_rng(seed)
    P, T = int(rng.integers(1, 6)), int(rng.integers(1, 40))
    s = rng.integers(1, 12, size=(P, T))
    if seed % 2:
        s[int(rng.integers(P)), :] += 9  # one slow processor
    for D in (1, 2, 3, 8):
        for g in (1, 3):
            r = coupled_matrix(s, D, issue_interval=g)
            e = _step_sim(s, D, g)
            assert r.frame_cycles == e["frame"], (D, g)
            assert r.stall_cycles == e["stall"], (D, g)
            assert np.array_equal(r.pop, e["pop"]), (D, g)
            assert np.array_equal(r.broadcast, e["bc"]), (D, g)
            assert np.array_equal(r.fifo_peak, e["peak"]), (D, g)
            assert (r.fifo_peak <= D).all()


@pytest.fixture(scope="module")
def c300():
    tris = run_geometry(build_scene("c300"), 512, 512)
    return sparse_render(tris, "4x4", depth="fixed", per_record=True)


def test_per_record_counts_add_up_to_the_golden_counts(c300):
    w = c300.stats["windows_per_record"]
    assert np.array_equal(w.sum(axis=1), c300.windows_per_proc)
    # stage cycles without headers or parameters are the coverage tests the HDL is checked against
    assert np.array_equal(stage_cycles(w, headers=False).sum(axis=1), c300.tests_per_proc[:, 1:])


def test_coupled_matrix_invariants_on_c300(c300):
    runs = {D: matrix_cycles(c300, D) for D in (1, 2, 8, 64)}
    for D, r in runs.items():
        assert max(r["fifo_peak"]) <= D
        assert r["frame_cycles"] >= r["slowest_alone"]
        assert all(b + i == r["frame_cycles"] for b, i in zip(r["busy"], r["idle"], strict=True))
    assert runs[1]["stall_cycles"] > 0
    assert runs[1]["frame_cycles"] > runs[64]["frame_cycles"]
    assert runs[1]["fifo_peak_max"] == 1 and runs[8]["fifo_peak_max"] == 8
    frames = [runs[D]["frame_cycles"] for D in (1, 2, 8, 64)]
    assert frames == sorted(frames, reverse=True)


def test_deep_fifo_frame_is_the_slowest_processor_alone_plus_the_push(c300):
    w = c300.stats["windows_per_record"]
    s = service_times(w)
    T = s.shape[1]
    r = coupled_matrix(s, T)
    assert r.stall_cycles == 0
    assert r.frame_cycles == 1 + int(s.sum(axis=1).max())
    # a slow geometry processor: the max-plus closed form
    g = 97
    r = coupled_matrix(s, T, issue_interval=g)
    tail = np.cumsum(s[:, ::-1], axis=1)[:, ::-1]  # sum_(u >= t) s[k, u]
    assert r.frame_cycles == int((np.arange(T) * g + 1 + tail).max())


def test_stack_processor_costs_every_test_and_the_pipeline_its_busiest_stage(c300):
    w = c300.stats["windows_per_record"]
    st = service_times(w, vp="stack")
    pi = service_times(w, vp="pipeline")
    assert np.array_equal(st, SETUP_CYCLES + 4 * w[:, :, :-1].sum(axis=2))
    assert (pi <= st).all() and (pi >= 4).all()
    # the k_p/k_e term of (5): depth and RGB (k_p = 4) on the three edge adders
    st4 = service_times(w, vp="stack", kp=4)
    assert np.array_equal(st4 - st, (-(-w[:, :, 1:] * 4 // 3)).sum(axis=2))


@pytest.mark.parametrize("bad", [dict(depth=0), dict(depth=1.5), dict(issue_interval=0)])
def test_bad_coupling_parameters_are_rejected(bad):
    kw = {"depth": 2, **bad}
    with pytest.raises(RasterhwError, match="sparse cycles"):
        coupled_matrix(np.ones((2, 3), dtype=np.int64), **kw)


@pytest.mark.parametrize("s", [np.zeros((2, 3), dtype=np.int64), np.ones((2, 3)), np.ones(3, dtype=np.int64)])
def test_bad_service_times_are_rejected(s):
    with pytest.raises(RasterhwError, match="service times"):
        coupled_matrix(s, 2)


def test_bad_vp_and_a_frame_without_records_are_rejected(c300):
    with pytest.raises(RasterhwError, match="vp must be"):
        service_times(c300.stats["windows_per_record"], vp="tree")
    tris = run_geometry(build_scene("c50"), 64, 64)
    with pytest.raises(RasterhwError, match="per_record"):
        matrix_cycles(sparse_render(tris, "2x2"), 4)
    with pytest.raises(RasterhwError, match="windows per record"):
        stage_cycles(np.ones((2, 3)))
