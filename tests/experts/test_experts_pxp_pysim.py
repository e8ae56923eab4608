"""EXPERTS PXP HDL in Amaranth pysim: pixel- and cycle-exact with the bit-accurate golden PXP."""

from __future__ import annotations

import itertools
import random
from functools import cache

import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.experts.pxp_cycles import line_pixels, line_segments, schedule
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.hdl.experts.pxp import ExpertsPxp
from rasterhw.hdl.experts.unit import ExpertsPxpUnit
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put, stream_sink


def _line_watch(dut, n_lines: int, got: list, n_expect: int, cycles: list):
    """A testbench process that logs the PXP's per-line cycle count as each line ends, and stops
    once ``n_lines`` lines have ended and ``n_expect`` pixels came out."""
    async def watch(ctx):
        seen = 0
        async for _clk, _rst, n, c in ctx.tick().sample(dut.lines, dut.line_cycles):
            if n != seen:
                cycles.append(c)
                seen = n
            if seen == n_lines and len(got) >= n_expect:
                return
    return watch


@cache
def _frame(name: str = "experts-tilt-1000", aj: str = "none"):
    return render_frame(run_geometry(build_scene(name), 512, 512, z_bits=16), model="bit", aj=aj)


def _run(lines, lo, hi, *, ready=None, gap=0, name="experts-tilt-1000", fr=None, unit=False, aj="none"):
    fr = _frame(name, aj) if fr is None else fr
    dut = ExpertsPxpUnit(width=512, depth=256) if unit else ExpertsPxp(width=512, aj=aj)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got, log, cycles = [], [], []
    segs = {y: line_segments(fr, y, lo, hi, aj=aj) for y in lines}

    async def feed(ctx):
        ctx.set(dut.lo, lo)
        ctx.set(dut.hi, hi)
        for y in lines:
            for s in segs[y]:
                await stream_put(ctx, dut.i, {"last": 0, **s}, gap=gap)
            await stream_put(ctx, dut.i, {"last": 1, "xl": 0, "xr": 0, "zl": 0, "il": 0, "dzdx": 0, "didx": 0,
                                          "hue": 0, "addr": 0}, gap=gap)

    expect = [p for y in lines for p in line_pixels(fr, y, lo, hi)]

    watch = _line_watch(dut, len(lines), got, len(expect), cycles)
    sim.add_testbench(feed)
    sim.add_testbench(stream_sink(dut.o, got, ready=ready), background=True)
    sim.add_testbench(stream_protocol_checker(dut.o, "o", log), background=True)
    sim.add_testbench(watch)
    sim.run()
    want = schedule([(segs[y], lo, hi) for y in lines], aj=aj)["line_cycles"]
    return got, log, cycles, expect, want


@pytest.mark.parametrize("lo,hi", [(128, 192), (0, 37), (475, 512)])
def test_pixels_and_cycles_exact(lo, hi):
    got, log, cycles, expect, want = _run([100, 101, 300], lo, hi)
    assert got == expect and log == expect
    assert cycles == want
    assert any(p for p in got)  # the range is not empty background


@pytest.mark.parametrize("lo,hi", [(128, 192), (0, 37), (475, 512), (300, 301)])
def test_anti_jagging_c_pixels_and_cycles_exact(lo, hi):
    """Method (c) in the HDL: every blended edge pixel equal to the golden model's, guard pixels
    at the range ends included (the range's edges see their neighbours' pixels)."""
    got, log, cycles, expect, want = _run([100, 101, 300], lo, hi, aj="c")
    assert got == expect and log == expect and cycles == want
    plain = [p for y in (100, 101, 300) for p in line_pixels(_frame(), y, lo, hi)]
    if hi - lo > 30:
        assert got != plain   # some pixel was blended


def test_anti_jagging_on_the_solids_and_under_back_pressure():
    rng = random.Random(9)
    ready = [rng.randint(0, 1) for _ in range(6000)]
    got, log, cycles, expect, want = _run([200, 260], 160, 352, aj="c", name="experts-solids", ready=ready, gap=1)
    assert got == expect and log == expect
    assert all(c >= w for c, w in zip(cycles, want, strict=True))


def test_crossing_segments_and_ties_exact():
    # lines of the tilted scene where faces interpenetrate inside the range
    fr = _frame()
    w = fr.win.reshape(512, 512)
    rec = fr.records
    a, b = w[:, :-1], w[:, 1:]
    inside = (a != b) & (a >= 0) & (b >= 0)
    ys = [y for y in range(512) if inside[y, 200:260].any()
          and (rec.c1[a[y, 200:260]] > 200).any()][:2]
    got, _, cycles, expect, want = _run(ys, 200, 264)
    assert got == expect and cycles == want


def test_back_pressure_and_idle_input_keep_pixels_exact():
    rng = random.Random(5)
    ready = [rng.randint(0, 1) for _ in range(4000)]
    got, log, cycles, expect, want = _run([250], 300, 340, ready=ready, gap=2)
    assert got == expect and log == expect
    # stalls only add cycles (output back-pressure stalls the drain bank, not the resolve side)
    assert cycles[0] >= want[0]
    got2, _, _, expect2, _ = _run([250], 300, 340, ready=itertools.cycle([1, 1, 1, 0]))
    assert got2 == expect2


def test_z_tie_goes_to_the_lower_asb_address():
    """Two coplanar faces overlap; the one submitted first starts left, so the PXP meets it first
    and must keep it against the later one's equal z (and the reverse order too)."""
    import numpy as np
    from rasterhw.golden_model.screen import ScreenTriangles
    xy = np.array([[[100.3, 10.0], [100.3, 40.0], [200.3, 25.0]],     # submitted first, left
                   [[150.3, 10.0], [150.3, 40.0], [250.3, 25.0]],     # second, right: ties lose
                   [[300.3, 10.0], [300.3, 40.0], [400.3, 25.0]],     # second pair: the later face
                   [[250.3, 10.0], [250.3, 40.0], [350.3, 25.0]]])    # starts left, the earlier wins
    z = np.full((4, 3), 0.5)
    col = np.repeat(np.array([[0.9, 0.2, 0.2], [0.2, 0.9, 0.2], [0.2, 0.2, 0.9], [0.9, 0.9, 0.2]])[:, None], 3, 1)
    tris = ScreenTriangles(512, 64, xy, z, np.zeros((4, 3), np.int64), col, np.arange(4))
    fr = render_frame(tris, model="bit")
    got, _, cycles, expect, want = _run([25], 96, 416, fr=fr)
    assert got == expect and cycles == want
    hue = [p >> 7 for p in got]
    assert hue[175 - 96] == (7 << 6) | (2 << 3) | 2   # the first face (red) wins the tie
    assert hue[320 - 96] == (2 << 6) | (2 << 3) | 7   # face 2 (blue, before face 3) wins


def test_through_the_dmm_pixels_exact_and_never_faster():
    """DMM/P in front: the SLP writes the next line while the PXP works; same pixels, and the
    PXP's line cycles are at least the bare PXP's (it can only wait for its input)."""
    got, log, cycles, expect, want = _run([100, 101, 102], 64, 128, unit=True)
    assert got == expect and log == expect
    assert all(c >= w for c, w in zip(cycles, want, strict=True))


def _random_line(rng, n, lo, hi):
    segs = []
    for _ in range(n):
        a = rng.randrange((lo - 8) * 64 if lo >= 8 else 0, (hi + 8) * 64)
        b = a + rng.randrange(0, 40 * 64)
        segs.append({"xl": a, "xr": min(b, 512 * 64), "zl": rng.choice([rng.randrange(1 << 16), 30000]),
                     "il": rng.randrange(127 << 9), "dzdx": rng.choice([0, rng.randrange(-3000, 3000)]),
                     "didx": rng.randrange(-2000, 2000), "hue": rng.randrange(512), "addr": rng.randrange(4000)})
    segs.sort(key=lambda s: (s["xl"], s["addr"]))
    return segs


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_asls_against_the_per_pixel_reference(seed):
    """Random ASLs (no scene): crossing segments, equal depths (z ties), segments outside the
    range, ranges at odd alignments -- pixels from an independent per-pixel reference."""
    from rasterhw.golden_model.experts.pxp_cycles import reference_line
    rng = random.Random(seed)
    lo = rng.randrange(0, 400)
    hi = lo + rng.randrange(1, 100)
    lines = [_random_line(rng, rng.randrange(0, 12), lo, hi) for _ in range(3)]
    dut = ExpertsPxp(width=512)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got, cycles = [], []

    async def feed(ctx):
        ctx.set(dut.lo, lo)
        ctx.set(dut.hi, hi)
        for segs in lines:
            for s in segs:
                await stream_put(ctx, dut.i, {"last": 0, **s})
            await stream_put(ctx, dut.i, {"last": 1})

    expect = [p for segs in lines for p in reference_line(segs, lo, hi)]

    watch = _line_watch(dut, len(lines), got, len(expect), cycles)
    sim.add_testbench(feed)
    sim.add_testbench(stream_sink(dut.o, got), background=True)
    sim.add_testbench(watch)
    sim.run()
    assert got == expect
    assert cycles == schedule([(segs, lo, hi) for segs in lines])["line_cycles"]


def test_empty_line_is_background():
    got, _, cycles, expect, want = _run([0], 0, 16, name="experts-solid-15")
    assert got == expect == [0] * 16 and cycles == want


def test_bad_parameters():
    with pytest.raises(ValueError, match="width"):
        ExpertsPxp(width=0)
    from rasterhw.golden_model.errors import RasterhwError
    with pytest.raises(RasterhwError, match="intensity_bits"):
        ExpertsPxp(intensity_bits=9)


def test_per_pixel_reference_equals_the_golden_model_on_scene_lines():
    from rasterhw.golden_model.experts.pxp_cycles import reference_line
    fr = _frame()
    for y in (40, 200, 333):
        for lo, hi in ((0, 64), (250, 321)):
            assert reference_line(line_segments(fr, y, lo, hi), lo, hi) == line_pixels(fr, y, lo, hi)


@pytest.mark.parametrize("aj", ["none", "c"])
def test_ranges_at_every_alignment(aj):
    """One PXP, many lines, the range moving line to line: every start modulo 8, widths 1..65,
    the frame's edges -- pixels and cycles exact (the range is sampled when each line starts)."""
    from rasterhw.sim.experts.pxp_jobs import job_list
    from rasterhw.sim.experts.scene import run_jobs
    fr = _frame("experts-tilt-1000", aj)
    todo = [(120 + k, lo, min(lo + w, 512)) for k, (lo, w) in
            enumerate([(a, w) for a in (0, 1, 2, 3, 4, 5, 6, 7, 255, 448, 505, 511) for w in (1, 2, 9, 65)])]
    jb = job_list(fr, todo)
    r = run_jobs(jb, width=512, engine="pysim")
    assert r["pixels"].tolist() == jb["pixels"].tolist()
    assert r["cycles"].tolist() == jb["cycles"].tolist()
    # the double-banked DSLB: the frame's last pixel leaves when the schedule says
    assert r["last_pixel"] == jb["last_pixel"] + 2
