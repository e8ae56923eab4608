"""The i860 timing model (golden_model/snu/i860.py): scheduler rules, stage programs tied to the
paper's recipe counts, the Newton-step count justified by precision, and independence from
the paper's table."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu import balance, i860, recipe


def _check_schedule(p: i860.Program, cpu: i860.I860) -> dict:
    """Every dependency and every per-clock issue limit holds."""
    r = i860.schedule(p, cpu)
    lat = [cpu.latency(u, k) for u, k, _c, _s in p.ops]
    for i, (_u, _k, _c, srcs) in enumerate(p.ops):
        for s in srcs:
            assert r["issue"][i] >= r["issue"][s] + lat[s]
    per_clock: dict[int, list[str]] = {}
    for i, (u, *_rest) in enumerate(p.ops):
        per_clock.setdefault(r["issue"][i], []).append(u)
    for units in per_clock.values():
        assert all(units.count(u) <= 1 for u in i860.UNITS)
        fp = [u for u in units if u != "C"]
        if len(fp) == 2:
            assert cpu.dual_operation and set(fp) == {"A", "M"}
        if not cpu.dual_instruction:
            assert not (fp and "C" in units)
    assert r["clocks"] == max(r["issue"][i] + lat[i] for i in range(len(p.ops)))
    return r


def test_chains_and_independent_work():
    cpu = i860.I860()
    p = i860.Program()
    x = p.add()
    for _ in range(4):
        x = p.add(x)
    assert _check_schedule(p, cpu)["clocks"] == 5 * 3  # 5 dependent adds, 3 clocks each
    p = i860.Program()
    for _ in range(10):
        p.mul()
    assert _check_schedule(p, cpu)["clocks"] == 10 + 2  # one issue per clock, 3-clock latency
    p = i860.Program()
    for _ in range(10):
        p.mul()
        p.add()
    assert _check_schedule(p, cpu)["clocks"] == 12  # dual-operation: add and mul together
    assert _check_schedule(p, i860.I860(dual_operation=False))["clocks"] == 22
    p = i860.Program()
    for _ in range(6):
        p.op("C", "ld", None)
        p.add()
    assert _check_schedule(p, cpu)["clocks"] == 8  # core and FP in the same clock
    assert _check_schedule(p, i860.I860(dual_instruction=False, dual_operation=False))["clocks"] == 12  # 12 issues, one per clock


@pytest.mark.parametrize("kw", [{}, {"dual_operation": False}, {"dual_instruction": False},
                                {"dual_instruction": False, "dual_operation": False}, {"newton_steps": 1}])
def test_stage_schedules_obey_the_rules(kw):
    cpu = i860.I860(**kw)
    for s in i860.STAGES + i860.EXTRA_STAGES:
        p = i860._triangles(s, 2, cpu)
        r = _check_schedule(p, cpu)
        c = i860.stage_clocks(s, cpu)
        assert c["bound"] <= c["stream"] <= c["clocks"] <= r["clocks"]


def test_random_programs_obey_the_rules():
    rng = np.random.default_rng(5)
    for cpu in (i860.I860(), i860.I860(dual_instruction=False)):
        for _ in range(20):
            p = i860.Program()
            for i in range(60):
                srcs = [int(j) for j in rng.integers(0, i, rng.integers(0, 3))] if i else []
                p.op(str(rng.choice(list(i860.UNITS))), "x", None, *srcs)
            _check_schedule(p, cpu)


def test_programs_run_the_recipes_counted_operations():
    """Each stage program counts, per triangle, exactly what the recipe's golden code counted."""
    counts = recipe.ops_per_triangle()
    for s in i860.STAGES + i860.EXTRA_STAGES:
        prog = i860.program_counts(i860._triangles(s, 1, i860.I860()))["counted"]
        want = {k: v for k, v in counts[s].items() if k != "total" and v}
        assert prog == want, s


def test_newton_steps_follow_from_precision():
    """An frcp seed good to 2^-7 needs two Newton steps for single precision; one step leaves
    2^-14, too coarse for a 1/256-pixel position on a 1280-pixel line (2^-19)."""
    rng = np.random.default_rng(0)
    a = rng.uniform(1.0, 2.0, 10_000)
    seed = (1.0 / a) * (1.0 + rng.uniform(-2.0 ** -7, 2.0 ** -7, a.size))
    y = seed
    err = []
    for _ in range(2):
        y = y * (2.0 - a * y)
        err.append(np.max(np.abs(y * a - 1.0)))
    assert err[0] > 2.0 ** -19 and err[1] < 2.0 ** -24
    assert i860.NEWTON_STEPS == 2
    one = i860.stage_clocks("perspective_divide", i860.I860(newton_steps=1))
    two = i860.stage_clocks("perspective_divide")
    assert two["units"]["M"] - one["units"]["M"] == 3 * 2  # 2 mul per step per vertex


def test_model_does_not_read_the_paper_table(monkeypatch):
    before = i860.table1_model()
    fake = {s: {"ops": 1, "clocks": 1, "percent": 1.0} for s in balance.STAGES}
    monkeypatch.setattr(balance, "PAPER_TABLE1", fake)
    assert i860.table1_model() == before


def test_model_numbers():
    """The model's clocks as documented in docs/snu_geometry.md (update both together)."""
    m = i860.table1_model()
    assert {s: m[s]["clocks"] for s in i860.STAGES} == {
        "vertex_transform": 44, "normal_transform": 32, "normalise": 53, "light": 48, "clip": 21,
        "perspective_divide": 32, "screen_map": 11}
    assert m["total"]["clocks"] == 241
    # multiplier-bound stages: the busiest unit sets the software-pipelined rate
    assert m["perspective_divide"]["bound"] == 24 and m["normalise"]["bound"] == 42


def test_inner_loop_clocks():
    ex = {"pixels": 10, "add_addr": 10, "add_count": 10, "store": 10, "branch": 10,
          "add_r": 10, "add_g": 10, "add_b": 10, "add_z": 10}
    assert i860.inner_loop_clocks(ex) == 4
    assert i860.inner_loop_clocks(ex, i860.I860(dual_instruction=False)) == 8
    with pytest.raises(RasterhwError, match="pixel"):
        i860.inner_loop_clocks(dict(ex, pixels=0))


def test_bad_parameters():
    with pytest.raises(RasterhwError, match="add_latency"):
        i860.I860(add_latency=0)
    with pytest.raises(RasterhwError, match="newton_steps"):
        i860.I860(newton_steps=-1)
    with pytest.raises(RasterhwError, match="clock_hz"):
        i860.I860(clock_hz=0)
    with pytest.raises(RasterhwError, match="unknown stage"):
        i860.stage_program("nope")
    with pytest.raises(RasterhwError, match="unit"):
        i860.Program().op("X", "x", None)
    p = i860.Program()
    p.ops.append(("A", "x", None, (3,)))
    with pytest.raises(RasterhwError, match="not before"):
        i860.schedule(p)
