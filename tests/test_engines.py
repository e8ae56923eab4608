"""The generic engines (sim/engines/) on registered testbenches (sim/testbench.py): Amaranth pysim,
plain Verilator and cocotb (on Verilator and on Icarus) give the same words and the same cycle
stamps, with idle gaps and back-pressure, equal to the golden model's words."""

from __future__ import annotations

import shutil

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.engines import run
from rasterhw.sim.engines.pattern import ready_pattern, xorshift32
from rasterhw.sim.testbench import Expected, compare, find_testbench

#: every block with a testbench, at a small size
SMALL = {
    "experts-dmm": {"depth": 16},
    "experts-pxp": {"width": 64, "aj": "c"},
    "experts-pxp-span": {"width": 64, "aj": "c"},
    "experts-pxp-coherent": {"width": 64, "aj": "c"},
    "experts-pxp-unit": {"width": 64, "depth": 64},
    "pixelbus": {"width": 20, "height": 8},
    "pixelbus-bank": {"depth": 64},
    "experts-slp": {"width": 64, "tris": 256, "lines": 16, "asl": 64},
    "experts-slp-setup": {"height": 64},
    "experts-group": {"width": 64, "pn": 2, "tris": 256, "lines": 8, "asl": 64, "depth": 256},
    "zbm-chip": {"interleave": 2, "chip": 1, "width": 32},
    "zbm-loop": {"interleave": 2, "width": 32},
    "sparse-matrix": {"n": 3, "p": 2, "q": 2, "in_depth": 4},
    "sparse-vp": {"n": 3, "p": 2, "q": 2, "colour": True, "kp": 4},
    "sparse-stack-vp": {"n": 3, "p": 2, "q": 2, "colour": True, "kp": 4},
    "zbm-merger": {"fifo_depth": 4},
    "zbm-pixel": {"index": 3, "interleave": 1, "width": 128},
    "zbm-seggen": {"width": 48, "height": 24, "capacity": 64},
    "zbm-unit": {"interleave": 2, "width": 32, "height": 16, "capacity": 16},
}


def _need(exp: Expected) -> dict[str, int]:
    return {k: len(v) for k, v in exp.words.items()}


def _case(block: str, seed: int):
    """``block``'s testbench at its small size, a random stimulus and what the golden model expects."""
    tb = find_testbench(block)
    p = tb.params(**SMALL[block])
    stim = tb.stimulus(p, seed=seed)
    return tb, p, stim, tb.expect(p, stim)


def test_every_testbench_names_a_registered_block():
    blocks = registry.blocks()
    for m in registry.machines().values():
        for block, ref in m.testbenches.items():
            assert block in blocks and block in m.blocks, (m.name, block)
            assert registry.load(ref)().block == block
    # every registered testbench runs in the tests below
    assert set(SMALL) == {b for m in registry.machines().values() for b in m.testbenches}


@pytest.mark.parametrize("block", sorted(SMALL))
def test_pysim_matches_golden_with_idle_and_back_pressure(block):
    tb, p, stim, exp = _case(block, 11)
    assert sum(_need(exp).values()) > 50
    plain = run(tb, p, stim, engine="pysim", expect_words=_need(exp))
    slow = run(tb, p, stim, engine="pysim", idle=0.3, stall=90, seed=5, expect_words=_need(exp))
    assert compare(exp, plain)["mismatches"] == 0 and compare(exp, slow)["mismatches"] == 0
    assert compare(exp, plain)["cycle_mismatches"] in (0, None)              # where the model gives cycles
    assert compare(exp, slow, cycle_exact=False)["cycle_mismatches"] in (0, None)
    assert slow.cycles > plain.cycles          # the gaps and the stalls cost clocks


#: the PXPs' Verilator case runs their testbench with the line log (``log=True``: one more sink, the
#: log port, beside the pixels') in the scene runs' memories: the model
#: tests/experts/test_experts_pxp_engines.py builds at the same parameters, so a fresh run builds
#: each PXP's bench once, not twice (the block and its pixel port are the same)
LOGGED = ("experts-pxp", "experts-pxp-coherent", "experts-pxp-span")


@pytest.mark.heavy
@pytest.mark.cocotb
@pytest.mark.parametrize("block", sorted(SMALL))
def test_verilator_gives_the_pysim_words_and_cycle_stamps(block):
    tb, p, stim, exp = _case(block, 12)
    need, build = _need(exp), None
    if block in LOGGED:
        from rasterhw.sim.experts.scene import IN_DEPTH, OUT_DEPTH
        tb, build = type(tb)(log=True), {"depth": IN_DEPTH, "out_depth": OUT_DEPTH}
        need["log"] = len(tb.expect(p, stim).words["log"])
    for kw in ({}, {"idle": 0.25, "stall": 120, "seed": 9}):
        a = run(tb, p, stim, engine="pysim", expect_words=need, **kw)
        b = run(tb, p, stim, engine="verilator", expect_words=need, build=build, **kw)
        assert compare(exp, b)["mismatches"] == 0, kw
        assert (a.words, a.stamps) == (b.words, b.stamps) and set(b.words) == set(need), kw


#: Icarus runs every block's bench where it is installed (its builds take about a second); cocotb on
#: Verilator one block in the suite (a build is a Verilator model with cocotb's VPI), every block slow
ICARUS = pytest.mark.skipif(shutil.which("iverilog") is None, reason="iverilog not on PATH")
COCOTB_CASES = [("cocotb-verilator", "zbm-merger"),
                *[pytest.param("cocotb-verilator", b, marks=pytest.mark.slow) for b in sorted(SMALL) if b != "zbm-merger"],
                *[pytest.param("cocotb-icarus", b, marks=ICARUS) for b in sorted(SMALL)]]


@pytest.mark.cocotb
@pytest.mark.parametrize("engine,block", COCOTB_CASES)
def test_cocotb_gives_the_pysim_words_and_cycle_stamps(engine, block):
    """The generic cocotb test clocks the plain engine's bench top on either simulator: no bench
    of the block's own, the same words, stamps and status values as pysim."""
    tb, p, stim, exp = _case(block, 12)
    for kw in ({}, {"idle": 0.25, "stall": 120, "seed": 9}):
        a = run(tb, p, stim, engine="pysim", expect_words=_need(exp), **kw)
        b = run(tb, p, stim, engine=engine, expect_words=_need(exp), **kw)
        assert b.engine == engine and compare(exp, b)["mismatches"] == 0 and b.protocol_errors == 0, kw
        assert (a.words, a.stamps, a.status) == (b.words, b.stamps, b.status), kw


def test_compare_counts_wrong_missing_and_extra_words_and_cycles():
    from rasterhw.sim.testbench import Run

    exp = Expected({"o": [1, 2, 3]}, cycles=10)
    assert compare(exp, Run("x", {"o": [1, 2, 3]}, {"o": [3, 5, 9]}))["mismatches"] == 0
    r = compare(exp, Run("x", {"o": [1, 7]}, {"o": [3, 9]}))
    assert r["mismatches"] == 2 and r["cycle_mismatches"] == 0
    assert compare(exp, Run("x", {"o": [1, 2, 3, 4]}, {"o": [1, 2, 3, 11]}))["cycle_mismatches"] == 1
    # with gaps or stalls a run may be slower than the model, never faster
    assert compare(exp, Run("x", {"o": [1, 2, 3]}, {"o": [1, 2, 20]}), cycle_exact=False)["cycle_mismatches"] == 0
    assert compare(exp, Run("x", {"o": [1, 2, 3]}, {"o": [1, 2, 5]}), cycle_exact=False)["cycle_mismatches"] == 1


def test_bad_runs_are_refused_in_one_line():
    tb = find_testbench("zbm-seggen")
    p = tb.params(**SMALL["zbm-seggen"])
    stim = tb.stimulus(p, seed=1)
    for kw, msg in (({"engine": "modelsim"}, "engine must be"), ({"stall": 256}, "stall must be"),
                    ({"idle": 1.0}, "idle must be"), ({}, "how many words")):
        with pytest.raises(RasterhwError, match=msg):
            run(tb, p, stim, **({"expect_words": {"o": 1}} if kw else {}) | kw)
    with pytest.raises(RasterhwError, match="no parameter"):
        tb.params(interleave=2)
    with pytest.raises(RasterhwError, match="no testbench for block 'nope'"):
        find_testbench("nope")


def test_hierarchical_build_needs_a_module_named_once():
    """``build={"hier": True}``: only for a testbench that names modules to verilate once, each
    defined once in the bench's Verilog (the marker goes after its header); refused before a build."""
    from rasterhw.sim.engines.verilator import hier_marked

    tb = find_testbench("zbm-seggen")
    p = tb.params(**SMALL["zbm-seggen"])
    stim = tb.stimulus(p, seed=1)
    with pytest.raises(RasterhwError, match="names no module"):
        run(tb, p, stim, engine="verilator", expect_words={"o": 1}, build={"hier": True})
    with pytest.raises(RasterhwError, match="hier must be"):
        run(tb, p, stim, engine="verilator", expect_words={"o": 1}, build={"hier": 1})
    text = "module top(a);\n  cell c0 (a);\nendmodule\nmodule cell(a);\nendmodule\n"
    assert "module cell(a); /*verilator hier_block*/\n" in hier_marked(text, ("cell",))
    assert "module top(a);\n" in hier_marked(text, ("cell",))
    with pytest.raises(RasterhwError, match="defined 0 times"):
        hier_marked(text, ("other",))


def test_back_pressure_pattern_is_the_benches_xorshift():
    assert xorshift32(1) == 270369 and xorshift32(270369) == 67634689   # x ^= x<<13; x ^= x>>17; x ^= x<<5
    pat = ready_pattern(7, 128)
    got = [next(pat) for _ in range(1000)]
    assert 350 < sum(got) < 650                  # about half the clocks ready at stall 128
    assert all(next(ready_pattern(s, 0)) for s in range(5))   # stall 0: always ready


def test_machines_json_names_every_block_with_its_testbench():
    import json

    from click.testing import CliRunner
    from rasterhw.sim.cli.main import cli

    out = CliRunner().invoke(cli, ["machines", "--json"])
    assert out.exit_code == 0, out.output
    ms = {m["name"]: m for m in json.loads(out.output)["rows"]}
    assert set(ms) == set(registry.machines())
    blocks = {b: info for m in ms.values() for b, info in m["blocks"].items()}
    assert set(blocks) == set(registry.blocks())
    for block in SMALL:   # the testbenches tests run, with both engines
        assert blocks[block]["testbench"] and {"pysim", "verilator"} <= set(blocks[block]["engines"]), block
    assert all(info["engines"] == [] for info in blocks.values() if info["testbench"] is None)


def test_a_seed_that_would_never_raise_ready_is_refused():
    """Output k's back-pressure is the xorshift seeded seed + k; a zero seed stays zero, so the
    sink would never take a word: refused before the run, not found by the watchdog."""
    tb, p, stim, exp = _case("zbm-merger", 3)
    with pytest.raises(RasterhwError, match="back-pressure seed of 0"):
        run(tb, p, stim, engine="pysim", stall=32, seed=0, expect_words=_need(exp))
    r = run(tb, p, stim, engine="pysim", stall=0, seed=0, expect_words=_need(exp))   # no stalls: fine
    assert compare(exp, r)["mismatches"] == 0


def test_always_ready_outputs_are_never_back_pressured():
    """``Testbench.always_ready``: those outputs' sinks take every word when it comes, whatever the
    run's ``stall`` (and a zero back-pressure seed is no matter for them)."""
    tb, p, stim, exp = _case("zbm-merger", 3)
    free = type("Free", (type(tb),), {"always_ready": tuple(tb.outputs_of(p))})()
    port = tb.outputs_of(p)[0]
    assert free.stall_of(port, 200) == 0 and tb.stall_of(port, 200) == 200
    plain = run(tb, p, stim, engine="pysim", expect_words=_need(exp))
    stalled = run(free, p, stim, engine="pysim", stall=200, seed=0, expect_words=_need(exp))
    assert (stalled.words, stalled.stamps) == (plain.words, plain.stamps)


def test_verilator_build_settings_are_checked():
    """``build={"depth": N, "out_depth": M}``: the bench's memories hold at least so many words
    (inputs / every output's sink: one build for runs of many sizes); bad values are one-line errors."""
    from rasterhw.sim.engines.verilator import _settings
    assert _settings({"depth": 1 << 10, "out_depth": 1 << 12}, "-O1")[3:5] == (1 << 10, 1 << 12)
    assert _settings(None, "-O1")[3:] == (0, 0, False)
    assert _settings({"hier": True}, "-O1")[5] is True
    for bad, msg in (({"out_depth": -1}, "out_depth must be"), ({"depth": 1.5}, "depth must be"),
                     ({"fifo": 3}, "no fifo")):
        with pytest.raises(RasterhwError, match=msg):
            _settings(bad, "-O1")


def test_dump_decoding_fast_path_gives_the_same_ints():
    """``verilator._ints``: words of up to 64 bits in one NumPy pass, wider ones row by row; both
    equal ``int.from_bytes`` of every dumped row (widths 1..9 bytes, extreme values)."""
    import numpy as np
    from rasterhw.sim.engines.verilator import _ints

    rng = np.random.default_rng(7)
    for nbytes in range(1, 10):
        b = rng.integers(0, 256, (50, nbytes), dtype=np.uint8)
        b[0], b[1] = 0, 255
        assert _ints(b) == [int.from_bytes(r.tobytes(), "big") for r in b]


def test_block_parameters_are_read_only():
    """``hdl/params.py``: ``@params`` gives a read-only property per name, reading ``self._NAME``."""
    from rasterhw.hdl.params import params

    @params("width", "ram")
    class Block:
        def __init__(self):
            self._width, self._ram = 40, "memory"

    b = Block()
    assert (b.width, b.ram) == (40, "memory")
    with pytest.raises(AttributeError):
        b.width = 3
