"""Separate clocks on the generic engines (``engines.run(..., clocks=...)``): every clock domain of a
block on its own half period and first edge, on Amaranth pysim (``add_clock``) and plain Verilator
(the one C++ main toggling bit k of the bench top's ``clocks`` port on domain k's schedule).

The two engines give the same words and per-domain stamps at unequal clocks; equal clocks in phase
give the one-clock run; and the ZB/M unit at a segment:merge ratio gives the cocotb bench's frame,
cycle count and per-line log (the run the soak's ratio rounds used to need cocotb for)."""

from __future__ import annotations

import shutil

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import run
from rasterhw.sim.testbench import Clock, Run, clocks_of, compare, find_testbench
from zbm_cocotb import records as R


def test_clock_edges_and_reference_cycles():
    c = Clock(3, 10)                       # rising edges at 10, 16, 22, ...
    assert [c.edge_time(k) for k in range(3)] == [10, 16, 22]
    assert [c.edges_before(t) for t in (0, 10, 11, 16, 17, 22, 23)] == [0, 0, 1, 1, 2, 2, 3]
    # a merge-domain port: its stamps count merge edges; cycles count sync edges before the next one
    r = Run("x", {"o": [1, 2]}, {"o": [0, 4]}, clocks={"sync": Clock(2, 0), "merge": Clock(5, 1)},
            port_domains={"o": "merge"})
    assert r.cycles_at("o", 5) == Clock(2, 0).edges_before(1 + 10 * 5) == 13
    assert r.cycles == 13
    one = Run("x", {"o": [1, 2]}, {"o": [0, 4]})
    assert one.cycles_at("o", 5) == one.cycles == 5


def test_bad_clocks_are_refused_in_one_line():
    for given, msg in (({"sync": 1}, "every clock domain"), ({"sync": 0, "merge": 1}, "half period"),
                       ({"sync": (2, -1), "merge": 1}, "first edge"), ([1, 2], "must be a dict"),
                       ({"sync": 1, "merge": 1, "video": 2}, "every clock domain")):
        with pytest.raises(RasterhwError, match=msg):
            clocks_of(given, ("sync", "merge"))
    tb = find_testbench("zbm-merger")
    p = tb.params(fifo_depth=4)
    with pytest.raises(RasterhwError, match="every clock domain"):
        run(tb, p, tb.stimulus(p, seed=1), expect_words={"o_merge": 1}, clocks={"merge": 2})
    assert clocks_of({"merge": (3, 4), "sync": 2}, ("sync", "merge")) == {"sync": Clock(2), "merge": Clock(3, 4)}


def _merger(seed: int):
    tb = find_testbench("zbm-merger")
    p = tb.params(fifo_depth=4)
    stim = tb.stimulus(p, seed=seed)
    exp = tb.expect(p, stim)
    return tb, p, stim, exp, {k: len(v) for k, v in exp.words.items()}


#: (sync, merge) clocks: merge slower and late, merge faster, coinciding edges now and then
RATIOS = [{"sync": (2, 0), "merge": (3, 1)}, {"sync": (7, 3), "merge": (2, 0)}, {"sync": (2, 0), "merge": (3, 0)}]


@pytest.mark.parametrize("clocks", RATIOS)
def test_pysim_merger_at_clock_ratios_is_golden(clocks):
    tb, p, stim, exp, need = _merger(3)
    got = run(tb, p, stim, engine="pysim", idle=0.2, stall=70, seed=4, expect_words=need, clocks=clocks)
    assert compare(exp, got)["mismatches"] == 0
    one = run(tb, p, stim, engine="pysim", idle=0.2, stall=70, seed=4, expect_words=need)
    assert got.stamps != one.stamps        # the clocks changed the timing, not the words


@pytest.mark.cocotb
@pytest.mark.parametrize("engine", ["verilator", pytest.param("cocotb-verilator", marks=pytest.mark.slow),
                                    pytest.param("cocotb-icarus", marks=pytest.mark.skipif(
                                        shutil.which("iverilog") is None, reason="iverilog not on PATH"))])
def test_verilator_gives_the_pysim_words_and_stamps_at_clock_ratios(engine):
    """One separate-clock build of the merger serves every ratio; each gives pysim's words and
    per-domain stamps; equal clocks in phase give the one-clock run's stamps. The same on cocotb
    (the generic test toggles the clocks on the plain main's schedule)."""
    tb, p, stim, exp, need = _merger(5)
    for clocks in RATIOS:
        kw = {"idle": 0.25, "stall": 90, "seed": 7, "expect_words": need, "clocks": clocks}
        a = run(tb, p, stim, engine="pysim", **kw)
        b = run(tb, p, stim, engine=engine, **kw)
        assert compare(exp, b)["mismatches"] == 0 and b.protocol_errors == 0, clocks
        assert (a.words, a.stamps) == (b.words, b.stamps), clocks
        assert a.cycles == b.cycles
    for eng in ("pysim", engine):
        kw = {"engine": eng, "stall": 90, "seed": 7, "expect_words": need}
        same = run(tb, p, stim, clocks={"sync": 5, "merge": 5}, **kw)
        one = run(tb, p, stim, **kw)
        assert (same.words, same.stamps, same.cycles) == (one.words, one.stamps, one.cycles), eng


@pytest.mark.cocotb
@pytest.mark.parametrize("case", ["ratio-2-3", "ratio-3-2", "ratio-7-2"])
def test_unit_at_a_clock_ratio_equals_the_cocotb_bench(case):
    """The ZB/M unit with the cocotb bench's clocks after reset (``bench_clocks``, merge 1 ns behind):
    the same frame as the golden model and as cocotb's ratio run, the same segment-clock count and
    the same per-line log -- cocotb's as recorded (``tests/zbm_cocotb/unit_records.json``, held equal
    to the cocotb bench by the slow tests/zbm/test_zbm_unit_records.py; was a cocotb run each)."""
    r = R.check_engine(case)
    assert len(r["line_cycles"]) == R.H
