# amaranth: UnusedElaboratable=no
"""``experts-slp`` (the SLP's list work in HDL) against its golden side
(``golden_model/experts/slp_cycles.py``, built on ``slp_run``'s sorts as run): the ASL update's x
equals the golden records, the ASL order and block lists equal ``slp_run``, and the HDL gives the
golden words and cycles."""

from __future__ import annotations

import pytest
from amaranth.sim import Simulator
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.experts.slp_cycles import _x, band_run, tri_words
from rasterhw.golden_model.experts.slp_run import run_band
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.hdl.experts.slp import ExpertsSlp
from rasterhw.sim.experts.testbench import slp_words


def _frame(name="experts-tilt-1000", w=96, h=48, aj="c"):
    return render_frame(run_geometry(build_scene(name), w, h, z_bits=16), model="bit", aj=aj)


def test_asl_update_x_is_the_golden_records():
    fr = _frame()
    rec, tws = fr.records, tri_words(fr.setup)
    got = [_x(tws[int(rec.tri[r])], int(rec.row[r])) for r in range(rec.tri.size)]
    assert got == list(zip(rec.xl.tolist(), rec.xr.tolist(), strict=True))


@pytest.mark.parametrize("guard", [0, 1])
def test_band_run_is_slp_runs_asl_and_block_lists(guard):
    fr = _frame()
    b = equal_bounds(96, 3)
    br = band_run(tri_words(fr.setup), (10, 30), b, width=96, guard=guard)
    rb = run_band(fr.setup, fr.records, (10, 30), b, W=96, guard=guard)
    assert br["asl"] == [[int(fr.records.tri[r]) for r in line] for line in rb.asl]
    for k, (lead, bk) in enumerate(zip(rb.lead, rb.buckets, strict=True)):
        words = [w for w in br["words"] if w[4] == 10 + k]
        assert [next((w[2] for w in words if w[0] == 1 and w[1] == p), -1) for p in range(3)] == lead
        assert [[w[2] for w in words if w[0] == 2 and w[1] == p] for p in range(3)] == bk
    # every term: band start, then per line at least start + bucket walk + end-of-line
    assert br["start_cycles"] == 1 + 20 + 4 + fr.setup.n + 1
    assert br["cycles"] == br["start_cycles"] + sum(br["line_cycles"])
    assert min(br["line_cycles"]) >= 3


def _run(dut, words, n_out):
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got, lcs = [], []

    async def feed(ctx):
        for w in words:
            ctx.set(dut.i.payload.as_value(), w)
            ctx.set(dut.i.valid, 1)
            await ctx.tick().until(dut.i.ready)
        ctx.set(dut.i.valid, 0)

    async def sink(ctx):
        ctx.set(dut.o.ready, 1)
        t = 0
        async for _c, _r, v, pl in ctx.tick().sample(dut.o.valid, dut.o.payload.as_value()):
            if v:
                got.append((t, pl))
                if pl & 3 == 3:
                    lcs.append(ctx.get(dut.line_cycles))
            t += 1
            if len(got) >= n_out or t > 10 ** 6:
                return
    sim.add_testbench(feed, background=True)
    sim.add_testbench(sink)
    sim.run()
    return got, lcs


@pytest.mark.parametrize("band", [(0, 6), (20, 26)])
def test_slp_hdl_words_and_cycles_equal_golden(band):
    """Two bands (the frame's first lines: everything enters by X-merge; a middle band: L-sort of
    survivors, leaving segments) at 3 ranges with the A.J. guard."""
    fr = _frame(w=64, h=32)
    sw = slp_words(fr, band, equal_bounds(64, 3), guard=1)
    dut = ExpertsSlp(width=64, tris=1024, lines=32, asl=256, guard=1)
    got, _ = _run(dut, sw["in"], len(sw["out"]))
    assert [w for _, w in got] == sw["out"]
    assert got[-1][0] + 1 == sw["cycles"]
    assert len(sw["out"]) > 6 * 10


def test_slp_bad_parameters():
    for kw in ({"width": 0}, {"tris": 1}, {"asl": 600}, {"guard": 2}, {"lines": True}):
        with pytest.raises(ValueError):
            ExpertsSlp(**kw)


@pytest.mark.parametrize("name", ["experts-tilt-1000", "c100", "experts-solids"])
def test_asl_update_asb_is_the_golden_asb(name):
    """Every ASB the SLP writes (x_L, x_R, z_L, i_L by its edge accumulators, the A.J. slopes of the
    edges of that line, the triangle's set-up values) is the golden record's, field for field."""
    from rasterhw.golden_model.experts.slp_cycles import asb
    from rasterhw.golden_model.experts.span_cycles import line_asl
    fr = _frame(name, 96, 48)
    tws = tri_words(fr.setup)
    n = 0
    for y in range(48):
        segs, _ = line_asl(fr, y)
        for s in segs:
            assert asb(tws[s["addr"]], y) == s
            n += 1
    assert n > 300


@pytest.mark.parametrize(("scene", "size"), [("c300", 512), ("experts-2000", 512), ("c50", 64)])
def test_every_triangle_word_fits_the_slp_input_fields(scene, size):
    """The SLP's input fields hold every value the golden set-up gives (c300 at 512 x 512 puts a
    vertex on x = 512, 32768 in Q.6: it once wrapped to -32768 in a 16-bit field and the SLP never
    finished)."""
    from rasterhw.hdl.experts.slp import slp_in_layout

    fr = render_frame(run_geometry(build_scene(scene), size, size, z_bits=16), model="bit", aj="c")
    tws = tri_words(fr.setup)
    for name, field in slp_in_layout():
        if name not in tws[0]:
            continue
        s = field.shape
        lo, hi = (-(1 << (s.width - 1)), (1 << (s.width - 1)) - 1) if s.signed else (0, (1 << s.width) - 1)
        vals = [t[name] for t in tws]
        assert lo <= min(vals) and max(vals) <= hi, (name, min(vals), max(vals), s)
