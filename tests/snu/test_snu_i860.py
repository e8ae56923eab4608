"""The shared i860 model (golden_model/i860) and SNU's stage programs on it (golden_model/snu/i860.py):
scheduler rules in both schedules, the manual facts the model rests on, programs tied to the
recipe's counts, the Newton-step count justified by precision, independence from the paper's table
(no cache between a patch and the check), and an import with the paper-table modules blocked."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from rasterhw.golden_model import i860 as cpu_model
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.i860 import model as M
from rasterhw.golden_model.snu import balance, i860, recipe


def _check(p: cpu_model.Program, cpu: cpu_model.I860, mode: str) -> dict:
    """Every dependency (register or data path) and every per-clock issue limit holds."""
    r = cpu_model.schedule(p, cpu, mode)
    ins, issue = r["instructions"], r["issue"]
    assert all(t >= 0 for t in issue)
    for i, (_u, _k, srcs, *_x) in enumerate(ins):
        for s in srcs:
            if r["via_path"].get(i) == s:
                assert issue[i] > issue[s]  # taken on a data path as it leaves the pipe
            else:
                assert issue[i] >= issue[s] + (1 if ins[s][0] in "AM" and mode == "assembler" else
                                                cpu.latency(ins[s][0], ins[s][1]))
    per_clock: dict[int, list[str]] = {}
    for i, (u, *_x) in enumerate(ins):
        per_clock.setdefault(issue[i], []).append(u)
    for units in per_clock.values():
        fp = [u for u in units if u != "C"]
        assert units.count("C") <= 1
        assert len(fp) <= 2 and (len(fp) < 2 or (set(fp) == {"A", "M"} and cpu.dual_operation
                                                    and mode == "assembler"))
        if mode == "compiler" or not cpu.dual_instruction:
            assert len(units) - (len(fp) - 1 if len(fp) == 2 else 0) <= 1
    return r


def test_parameters_are_the_manuals():
    """Every field of I860 that is a processor fact has its source; f0/f1 leave 30 registers."""
    cpu = cpu_model.I860()
    for name, (value, source) in cpu_model.PARAMETERS.items():
        assert source and ("PRM" in source or "DS" in source), name
        if hasattr(cpu, name):
            assert getattr(cpu, name) == value, name
    assert cpu.fp_registers == 32 and cpu.zero_registers == 2 and cpu.value_registers == 30


def test_pipelines_advance_per_instruction():
    """A pipelined result leaves the 3-stage pipe only when three more instructions are issued to
    that unit (PRM §6.2): a lone dependent pair of adds needs drain pushes."""
    cpu = cpu_model.I860()
    p = cpu_model.Program()
    x = p.add()
    p.add(x)
    r = _check(p, cpu, "assembler")
    assert r["pushes"] == 6 and r["clocks"] == 8  # issue 0, pushes 1-3, issue 4, pushes 5-7
    assert _check(p, cpu, "compiler")["clocks"] == 6  # scalar: 3 + 3
    p = cpu_model.Program()
    for _ in range(10):
        p.mul()
    r = _check(p, cpu, "assembler")
    assert r["pushes"] == 3 and r["clocks"] == 13  # 10 issues, then 3 pushes drain the pipe
    assert _check(p, cpu, "compiler")["clocks"] == 30  # scalar: the unit is busy 3 clocks each


def test_dual_operation_follows_the_data_paths():
    """An add and a multiply share one instruction only within two register reads and one write."""
    p = cpu_model.Program()
    m = p.mul(None, None)  # 0: two register operands
    a = p.add(m, None)  # 1: the M-result and one register
    k = p.mul(None, "k")  # 2: one register and a constant
    ins, _ = M._lower(p, "assembler", cpu_model.I860())
    left = [1, 0, 0]
    # add takes the leaving multiply result on the M-result path: 1 read; the multiply by KR: 1 read
    assert M._pair_legal(a, k, None, m, ins, left, kr="k")
    # the constant not in KR is a register read: 1 + 2 = 3 > 2
    assert not M._pair_legal(a, k, None, m, ins, left, kr=None)
    # a multiply with two register operands leaves the add one read at most
    assert not M._pair_legal(a, 0, None, None, ins, [1, 0, 0], kr=None)
    # two leaving results that are both still needed: one destination register only
    assert not M._pair_legal(None, None, 1, 0, ins, [2, 1, 0], kr=None)


def test_register_file_limits_spill():
    """More live values than 30 registers cost stores and loads on the core."""
    p = cpu_model.Program()
    vals = p.load(40)
    acc = p.add(vals[0], vals[1])
    for v in vals[2:]:
        acc = p.add(acc, v)
    p.store(*(p.mul(v, acc) for v in vals))  # every value is read again after the sum: all live
    tight = _check(p, cpu_model.I860(), "assembler")
    roomy = _check(p, cpu_model.I860(fp_registers=80), "assembler")
    assert tight["spills"] > 0 and tight["peak_registers"] == 30
    assert roomy["spills"] == 0 and roomy["peak_registers"] > 30
    assert tight["clocks"] > roomy["clocks"]


@pytest.mark.parametrize("kw", [{}, {"dual_operation": False}, {"dual_instruction": False}, {"newton_steps": 1}])
@pytest.mark.parametrize("mode", ["compiler", "assembler"])
def test_stage_schedules_obey_the_rules(kw, mode):
    cpu = cpu_model.I860(**kw)
    for s in i860.STAGES + i860.EXTRA_STAGES:
        _check(i860._triangles(s, 2, cpu.newton_steps), cpu, mode)


def test_random_programs_obey_the_rules():
    rng = np.random.default_rng(5)
    for cpu in (cpu_model.I860(), cpu_model.I860(dual_instruction=False)):
        for _ in range(15):
            p = cpu_model.Program()
            for i in range(50):
                srcs = [int(j) for j in rng.integers(0, i, rng.integers(0, 3))] if i else []
                u = str(rng.choice(list(cpu_model.UNITS)))
                p.op(u, "fld" if u == "C" and rng.random() < 0.3 else "x", None, *srcs)
            for mode in cpu_model.SCHEDULES:
                _check(p, cpu, mode)


def test_programs_run_the_recipes_counted_operations():
    """Each stage program counts, per triangle, exactly what the recipe's golden code counted."""
    counts = recipe.ops_per_triangle()
    for s in i860.STAGES + i860.EXTRA_STAGES:
        prog = i860.program_counts(i860._triangles(s, 1, 2))["counted"]
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
    assert cpu_model.NEWTON_STEPS == 2
    one = i860.stage_clocks("perspective_divide", cpu_model.I860(newton_steps=1), stream_triangles=0)
    two = i860.stage_clocks("perspective_divide", stream_triangles=0)
    assert two["units"]["M"] - one["units"]["M"] == 3 * 2  # 2 mul per step per vertex


def test_model_does_not_read_the_paper_table(monkeypatch):
    before = i860.table1_model(stream_triangles=0)
    fake = {s: {"ops": 1, "clocks": 1, "percent": 1.0} for s in balance.STAGES}
    monkeypatch.setattr(balance, "PAPER_TABLE1", fake)
    assert i860.table1_model(stream_triangles=0) == before


def test_nothing_cached_between_a_patch_and_the_result(monkeypatch):
    """The check above can fail: patch what the model does read and the result moves at once."""
    before = i860.table1_model(stream_triangles=0)["total"]["clocks"]
    real = i860.stage_program
    monkeypatch.setattr(i860, "stage_program", lambda s, **kw: real("screen_map", **kw))
    assert i860.table1_model(stream_triangles=0)["total"]["clocks"] != before
    monkeypatch.setattr(i860, "stage_program", real)
    monkeypatch.setattr(balance, "PAPER_TABLE1", {s: {"clocks": 1} for s in balance.STAGES})
    monkeypatch.setattr(i860, "stage_clocks", lambda s, *a, **kw: {"clocks": balance.PAPER_TABLE1[s]["clocks"],
                                                                    "stream": None})
    assert i860.table1_model(stream_triangles=0)["total"]["clocks"] == 7


BLOCKER = textwrap.dedent("""
    import importlib.abc, sys
    BLOCKED = ("rasterhw.golden_model.snu.balance", "rasterhw.golden_model.opcount",
               "rasterhw.golden_model.snu.recipe", "rasterhw.golden_model.zbm.cycles", "rasterhw.sim")
    class Block(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.startswith(BLOCKED):
                raise ImportError(f"blocked paper-table module {name}")
    sys.meta_path.insert(0, Block())
""")


def test_model_imports_with_the_paper_tables_blocked():
    """The i860 model and both machines' programs import and run with every module that holds a
    paper's table (SNU table 1, ZB/M tables 1 and 2, the reports) blocked."""
    code = BLOCKER + textwrap.dedent("""
        from rasterhw.golden_model.i860 import I860, PARAMETERS
        from rasterhw.golden_model.snu import i860
        from rasterhw.golden_model.zbm import i860 as z
        print(i860.table1_model(stream_triangles=0)["total"]["clocks"], z.polygon_clocks()["assembler"])
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    # and the blocker does block: importing a paper-table module under it fails
    r = subprocess.run([sys.executable, "-c", BLOCKER + "import rasterhw.golden_model.snu.balance"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "blocked paper-table module" in r.stderr


def test_model_numbers():
    """The model's clocks as documented in docs/snu_geometry.md (update both together)."""
    asm = i860.table1_model(stream_triangles=0)
    cc = i860.table1_model(mode="compiler", stream_triangles=0)
    assert {s: asm[s]["clocks"] for s in i860.STAGES} == DOC_ASSEMBLER
    assert {s: cc[s]["clocks"] for s in i860.STAGES} == DOC_COMPILER


DOC_ASSEMBLER = {"vertex_transform": 74, "normal_transform": 43, "normalise": 64, "light": 72, "clip": 24,
                 "perspective_divide": 39, "screen_map": 21}
DOC_COMPILER = {"vertex_transform": 213, "normal_transform": 135, "normalise": 168, "light": 285, "clip": 84,
                "perspective_divide": 108, "screen_map": 63}


def test_inner_loop_clocks():
    ex = {"pixels": 10, "add_addr": 10, "add_count": 10, "store": 10, "branch": 10,
          "add_r": 10, "add_g": 10, "add_b": 10, "add_z": 10}
    assert i860.inner_loop_clocks(ex) == 4
    assert i860.inner_loop_clocks(ex, cpu_model.I860(dual_instruction=False)) == 8
    with pytest.raises(RasterhwError, match="pixel"):
        i860.inner_loop_clocks(dict(ex, pixels=0))


def test_bad_parameters():
    with pytest.raises(RasterhwError, match="add_stages"):
        cpu_model.I860(add_stages=0)
    with pytest.raises(RasterhwError, match="newton_steps"):
        cpu_model.I860(newton_steps=-1)
    with pytest.raises(RasterhwError, match="clock_hz"):
        cpu_model.I860(clock_hz=0)
    with pytest.raises(RasterhwError, match="register file"):
        cpu_model.I860(fp_registers=4)
    with pytest.raises(RasterhwError, match="unknown stage"):
        i860.stage_program("nope")
    with pytest.raises(RasterhwError, match="unit"):
        cpu_model.Program().op("X", "x", None)
    with pytest.raises(RasterhwError, match="not before"):
        cpu_model.Program().op("A", "x", None, 3)
    with pytest.raises(RasterhwError, match="schedule must be"):
        cpu_model.schedule(i860.stage_program("clip"), mode="fortran")
    with pytest.raises(RasterhwError, match="Newton steps"):
        cpu_model.schedule(i860.stage_program("clip"), cpu_model.I860(newton_steps=1))
    with pytest.raises(RasterhwError, match="empty"):
        cpu_model.schedule(cpu_model.Program())
