# amaranth: UnusedElaboratable=no
"""The span PXP (``experts-pxp-span``, the paper's: span cull and depth search per span) against
its golden side (``golden_model/experts/span_cycles.py``): the same visible segment per pixel as
the per-pixel depth search and as ``span.py``, pixels and per-line cycles equal in pysim, work that
depends on the depth order (the line Z-buffer's does not)."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.golden_model.experts.span import span_pxp
from rasterhw.golden_model.experts.span_cycles import STEPS, dmm_line, line_job, resolve, schedule
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.experts.scene import jobs, simulate_scene


def _frame(name, w, h, aj="c", seed=0):
    return render_frame(run_geometry(build_scene(name, seed=seed), w, h, z_bits=16), model="bit", aj=aj)


@pytest.mark.parametrize("name", ["experts-tilt-1000", "experts-1000", "c100"])
@pytest.mark.parametrize("aj", ["none", "c"])
def test_golden_span_pxp_sees_the_per_pixel_visible_segment(name, aj):
    """Every pixel of every range: the span PXP's visible record (from the DMM/P words: whole ASL,
    bucket list, leading pointer) is the per-pixel depth search's and span.py's."""
    fr = _frame(name, 96, 48, aj)
    W, H, pn = fr.width, fr.height, 4
    b = equal_bounds(W, pn)
    jb = jobs(fr, 1, pn, pxp="span")
    got = np.full(H * W, -2, np.int64)
    for y in range(H):
        for p in range(pn):
            got[y * W + int(b[p]):y * W + int(b[p + 1])] = jb["visible"][y * pn + p]
    assert np.array_equal(got, fr.win)
    assert np.array_equal(got, span_pxp(fr.setup, fr.records, W, H, b).win)
    assert (got >= 0).sum() > W * H // 20                    # something is drawn


def test_resolve_counts_every_step_and_halves_where_depths_cross():
    """Two segments crossing inside one span: pass B fails, the span is halved until decided;
    every pixel written once; the schedule's terms add up."""
    s0 = {"xl": 0, "xr": 16 << 6, "zl": 100, "il": 0, "dzdx": 10 << 4, "didx": 0, "addr": 0}
    s1 = {"xl": 0, "xr": 16 << 6, "zl": 200, "il": 0, "dzdx": -(10 << 4), "didx": 0, "addr": 1}
    cyc, vis = resolve([s0, s1], [], 0, 0, 16)
    assert set(cyc) == set(STEPS) and cyc["write"] == 16 and len(vis) == 16
    z0 = [100 + 10 * x + 5 for x in range(16)]
    z1 = [200 - 10 * x - 5 for x in range(16)]
    assert vis == [0 if a <= b else 1 for a, b in zip(z0, z1, strict=True)]
    assert cyc["pass_b"] > 2 * 2 and cyc["pass_a"] > 2      # halved at least twice
    flat = dict(s1, zl=300, dzdx=0)
    c2, v2 = resolve([s0, flat], [], 0, 0, 16)
    assert v2 == [0] * 16 and c2["pass_a"] == 2 and c2["pass_b"] == 2   # decided from the end depths
    assert sum(c2.values()) < sum(cyc.values())
    # by hand: line 0 written 0..2, resolved 3..12, hands over at 13, drains 14..33; line 1 written
    # 3..5, resolve starts 14, done 24, waits for the drain until 34 (21 cycles), drains 35..54;
    # line 2's bank is free after line 0's drain: written 34..36, resolved 37..46, hands over at 55
    sch = schedule([(3, 10, 20), (3, 10, 20), (3, 10, 20)])
    assert sch["line_cycles"] == [11, 21, 19] and sch["last_pixel"] == 75
    assert schedule([(3, 10, 2)] * 3)["line_cycles"] == [11, 11, 11]
    # the paper's datapath with A.J.: line 0's drain (14, 15) holds the multiplier in its cycles 1 and 2;
    # line 1 takes its bank at 14 (not held), is held at 15: hands over at 25, not 24
    assert schedule([(3, 10, 2)] * 2, [[1, 2], []])["line_cycles"] == [11, 12]
    assert schedule([(3, 10, 2)] * 2, [[], []])["line_cycles"] == [11, 11]


def test_span_work_depends_on_depth_the_line_z_buffer_does_not():
    """experts-1000 and experts-tilt-1000 cover the same pixels with different depths: the line
    Z-buffer PXP's cycles are equal, the span PXP's differ (golden cycle models the HDL matches)."""
    a, b = _frame("experts-1000", 128, 64), _frame("experts-tilt-1000", 128, 64)
    za, zb = jobs(a, 2, 4, pxp="zbuffer"), jobs(b, 2, 4, pxp="zbuffer")
    sa, sb = jobs(a, 2, 4, pxp="span"), jobs(b, 2, 4, pxp="span")
    assert np.array_equal(za["cycles"], zb["cycles"])
    assert not np.array_equal(sa["cycles"], sb["cycles"])
    assert int(sa["pxp_frame_cycles"].max()) != int(sb["pxp_frame_cycles"].max())


@pytest.mark.parametrize("aj", ["none", "c"])
def test_small_frame_span_pxp_pysim_pixel_and_cycle_exact_same_pixels_as_zbuffer(aj):
    sc = build_scene("experts-tilt-1000")
    r = simulate_scene(sc, 64, 16, engine="pysim", sn=2, pn=4, aj=aj, pxp="span")
    z = simulate_scene(sc, 64, 16, engine="pysim", sn=2, pn=4, aj=aj, pxp="zbuffer")
    for q in (r, z):
        assert q["pixels_compared"] == 64 * 16 and q["mismatches"] == 0 and q["cycle_mismatches"] == 0
        assert q["last_pixel_mismatch"] == 0
    assert r["pxp"] == "span" and z["pxp"] == "zbuffer" and "ours" in r["pxp_is"] and "Z-buffer" in z["pxp_is"]
    # every guarded pixel written once: with A.J. each inner range end adds a guard pixel
    assert r["span_steps"]["write"] == 16 * (64 + (2 * 3 if aj == "c" else 0))
    assert r["span_steps"]["pass_a"] > 0 and r["frame_cycles"] != z["frame_cycles"]


def test_span_balanced_ranges_through_the_hdl():
    r = simulate_scene(build_scene("experts-uneven"), 128, 32, engine="pysim", sn=1, pn=4, aj="c", ranges="ii")
    assert r["mismatches"] == 0 and r["cycle_mismatches"] == 0 and r["last_pixel_mismatch"] == 0
    s = simulate_scene(build_scene("experts-uneven"), 128, 32, engine="pysim", sn=1, pn=4, aj="c")
    assert r["frame_cycles"] < s["frame_cycles"]


def test_block_lists_reach_the_pxp_as_data():
    """The bucket list and leading pointer the span PXP starts from are the golden SLP's
    (slp_run.block_lists): with them it never looks at a segment wholly left of its range."""
    fr = _frame("experts-tilt-1000", 128, 32)
    segs, lead, buckets = dmm_line(fr, 16, equal_bounds(128, 4))
    for p in range(4):
        lo, hi = 32 * p, 32 * p + 32
        glo = max(lo - 1, 0)
        for q in buckets[p]:
            c0 = (segs[q]["xl"] + 31) >> 6
            c1 = ((segs[q]["xr"] + 31) >> 6) - 1
            assert c0 < glo <= c1
        job = line_job(segs, buckets[p], lead[p], lo, hi, aj="c", width=128)
        assert len(job["visible"]) == 32 and job["words"] == len(segs) + len(buckets[p]) + 1


def test_bad_pxp_is_one_line_error():
    with pytest.raises(RasterhwError, match="--pxp must be one of span, coherent, zbuffer"):
        simulate_scene(build_scene("experts-tilt-1000"), 64, 16, pxp="linez")


def test_dmm_bank_overflow_stalls_the_writer_never_drops():
    """A line with more ASBs than a DMM/P bank holds: the word that does not fit is not taken,
    ``overflow`` rises and stays, and no pixel comes out of a half-written line."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan, dmm_layout
    from rasterhw.hdl.pack import pack
    lay = dmm_layout()
    seg = {"xl": 0, "xr": 8 << 6, "zl": 10, "il": 0, "dzdx": 0, "didx": 0, "addr": 1}
    words = [pack(lay, seg)] * 5 + [pack(lay, {"last": 1, "ptr": 0})]
    dut = ExpertsPxpSpan(width=16, depth=4)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    seen = {}

    async def bench(ctx):
        ctx.set(dut.hi, 16)
        ctx.set(dut.o.ready, 1)
        taken = outs = 0
        for _ in range(60):
            k = min(taken, len(words) - 1)
            ctx.set(dut.i.payload.as_value(), words[k])
            ctx.set(dut.i.valid, 1)
            _, _, rdy, ov = await ctx.tick().sample(dut.i.ready, dut.o.valid)
            taken += int(rdy)
            outs += int(ov)
        seen.update(taken=taken, outs=outs, overflow=ctx.get(dut.overflow), ready=ctx.get(dut.i.ready))

    sim.add_testbench(bench)
    sim.run()
    assert seen == {"taken": 4, "outs": 0, "overflow": 1, "ready": 0}


@pytest.mark.parametrize("seed", [1, 4])     # 66 and 8 extra cycles (seeds 2, 3, 5: no depth search)
def test_span_pxp_with_one_multiplier_pysim_word_and_cycle_exact(seed):
    """experts-pxp-span at datapath "paper": one 16 x 16 multiplier (pass A and pass B two cycles a
    segment, span_cycles.one_multiplier), pysim: pixels and cycles equal the golden side's; the same
    stimulus takes more cycles than ours' (the test can fail) and the elaborated design has one
    multiplier of 16 x 16 in the resolve side beside the drain's A.J. blend multipliers."""
    from rasterhw.golden_model.experts.span_cycles import one_multiplier
    from rasterhw.hdl.experts.census import multipliers
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan
    from rasterhw.sim.engines import run
    from rasterhw.sim.testbench import compare, find_testbench
    tb = find_testbench("experts-pxp-span")
    p = tb.params(width=64, depth=64, aj="c", datapath="paper")
    stim = tb.stimulus(p, seed=seed)
    exp = tb.expect(p, stim)
    ours = tb.expect(tb.params(width=64, depth=64, aj="c"), tb.stimulus(tb.params(width=64, depth=64, aj="c"), seed))
    extra = sum(one_multiplier(st) for st in stim.source["steps"])
    assert extra > 0 and exp.cycles > ours.cycles and exp.words == ours.words
    got = run(tb, p, stim, engine="pysim", expect_words={k: len(v) for k, v in exp.words.items()})
    c = compare(exp, got)
    assert c["mismatches"] == 0 and c["cycle_mismatches"] == 0
    assert multipliers(ExpertsPxpSpan(width=64, aj="none", datapath="paper")) == [(16, 16)]
    assert len(multipliers(ExpertsPxpSpan(width=64, aj="none"))) == 3


def test_paper_jobs_adds_the_multiplier_cycles_to_every_pxps_frame():
    """span_cycles.paper_jobs on a frame's jobs (pxp_sim.jobs): pixels unchanged, every line's resolve
    + pass_a + pass_b (one multiplier) + 2 (pass_a + pass_b) + its drawn pixels (two-word z and i),
    and each PXP's frame time rescheduled: with one PXP it is the whole job list's
    last pixel + 1; the coherent PXP's jobs carry their own rule (coherent.paper_resolve), and jobs
    of a PXP other than the span one without it are refused."""
    from rasterhw.golden_model.experts.span_cycles import multiword, one_multiplier, paper_jobs
    fr = render_frame(run_geometry(build_scene("experts-tilt-1000"), 64, 16, z_bits=16), model="bit", aj="c")
    jb = jobs(fr, 1, 1, pxp="span")
    pj = paper_jobs(jb)
    assert np.array_equal(pj["pixels"], jb["pixels"])
    # drawn: the guarded range's pixels a segment draws (the whole line here: one PXP, no guard)
    assert jb["drawn"] == [int((fr.win.reshape(16, 64)[y] >= 0).sum()) for y in range(16)]
    assert 0 < sum(jb["drawn"]) < sum(st["write"] for st in jb["steps"])
    assert [r for _, r, _ in pj["timing"]] == [r + 3 * (st["pass_a"] + st["pass_b"]) + dn for (_, r, _), st, dn in
                                               zip(jb["timing"], jb["steps"], jb["drawn"], strict=True)]
    assert [multiword(st, dn) for st, dn in zip(jb["steps"], jb["drawn"], strict=True)] == \
        [2 * one_multiplier(st) + dn for st, dn in zip(jb["steps"], jb["drawn"], strict=True)]
    assert int(pj["pxp_frame_cycles"][0, 0]) == pj["last_pixel"] + 1 > int(jb["pxp_frame_cycles"][0, 0])
    co = jobs(fr, 1, 1, pxp="coherent")
    assert paper_jobs(co)["last_pixel"] > co["last_pixel"]
    with pytest.raises(RasterhwError, match="coherent PXP's jobs carry no paper-datapath cycles"):
        paper_jobs({k: v for k, v in co.items() if k != "paper_extra"})


def test_paper_span_pxp_blends_on_its_one_multiplier_pysim_word_and_cycle_exact():
    """experts-pxp-span at datapath "paper" with A.J. (c) on a frame of many boundaries (experts-1000
    at 64 x 16, 4 ranges): the drain's blend takes the one multiplier, 4 or 5 multiplies a blended
    pixel (span_cycles.aj_blends / paper_drain), and the resolve side holds while it does
    (span_cycles.schedule's mul); pysim: every pixel and every line's finish-time counter equal
    the golden side's, and the holds are there (the schedule without them differs)."""
    from rasterhw.golden_model.experts.span_cycles import aj_blends, paper_jobs
    from rasterhw.sim.experts.scene import check_jobs
    fr = _frame("experts-1000", 64, 16)
    pj = paper_jobs(jobs(fr, 1, 4, pxp="span"))
    muls = [len(q["mul"]) for q in pj["paper_drain"]]
    assert sum(muls) > 200
    # every blended pixel costs its multiplies: 4 (steep edge) or 5, the drain that much longer
    segs, lead, buckets = dmm_line(fr, 8, equal_bounds(64, 4))
    job = line_job(segs, buckets[1], lead[1], 16, 32, aj="c", width=64)
    bl = aj_blends(job_vis := resolve(segs, buckets[1], lead[1], 15, 33)[1], segs, 16, 32, width=64)
    assert len(job_vis) == 18 and {n for _, n in bl} <= {4, 5}
    assert job["paper_drain"]["drain"] == job["drain"] + sum(n - 1 for _, n in bl)
    assert len(job["paper_drain"]["mul"]) == sum(n for _, n in bl)
    held = schedule(pj["timing"])["line_cycles"]
    assert held != pj["cycles"].tolist() and sum(held) < int(pj["cycles"].sum())
    r = check_jobs(pj, width=64, engine="pysim")
    assert r["pixel_mismatches"] == 0 and r["line_mismatches"] == 0
    assert r["pixels"].size == 64 * 16 and np.array_equal(r["pixels"], pj["pixels"])
    assert r["last_pixel"] == pj["last_pixel"] + 1          # the run's edge 0 takes the range word


def _extreme_line(rng, n: int, *, slope: int | None = None) -> list[dict]:
    """One line of ``n`` ASBs at 512 wide whose running z and i reach the formats' extremes: long
    segments, z_L and i_L at 0 or 65535, dz/dx and di/dx at -32768 / 32767 or anywhere, so z and i
    leave Q16.4 / 0..i_max both ways (negative and above 2**20, high words nonzero and negative).
    ``slope``: instead dz/dx within +-slope from mid-range z_L, so segments cross at small depth
    differences (the same high word, the low words' borrow deciding the guarded tests)."""
    def pick(ends, lo, hi):
        return int(rng.choice(ends)) if rng.random() < 0.6 else int(rng.integers(lo, hi + 1))
    segs = []
    for a in range(n):
        xl = int(rng.integers(0, 300 << 6))
        xr = int(min(xl + rng.integers(64, 400 << 6), 512 << 6))
        z = ({"zl": pick([0, 65535], 0, 65535), "dzdx": pick([-32768, 32767], -32768, 32767)} if slope is None else
             {"zl": int(rng.integers(20000, 40000)), "dzdx": int(rng.integers(-slope, slope + 1))})
        segs.append({"xl": xl, "xr": xr, **z, "il": pick([0, 65535], 0, 65535),
                     "didx": pick([-32768, 32767], -32768, 32767),
                     "hue": int(rng.integers(0, 512)), "addr": a + 1, "poly": a + 1})
    segs.sort(key=lambda s: (s["xl"], s["addr"]))
    return segs


def _run_lines(dut, words: list[int], n_lines: int, n_pix: int) -> tuple[list[int], list[int]]:
    """Feed ``words`` back to back into a span PXP (range [0, 512)), output always ready: its pixel
    words and each line's finish-time counter."""
    from amaranth.sim import Simulator
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    pix, lc = [], []

    async def bench(ctx):
        ctx.set(dut.hi, 512)
        ctx.set(dut.o.ready, 1)
        k, lines = 0, 0
        for _ in range(400_000):
            if k < len(words):
                ctx.set(dut.i.payload.as_value(), words[k])
            ctx.set(dut.i.valid, int(k < len(words)))
            _, _, rdy, ov, od, nl, lcy = await ctx.tick().sample(dut.i.ready, dut.o.valid, dut.o.payload,
                                                                 dut.lines, dut.line_cycles)
            k += int(rdy and k < len(words))
            if ov:
                pix.append(int(od))
            if nl != lines:
                lines = nl
                lc.append(int(lcy))
            if len(pix) == n_pix and lines == n_lines:
                break

    sim.add_testbench(bench)
    sim.run()
    return pix, lc


@pytest.mark.parametrize("pxp", ["span", "coherent"])
def test_paper_two_word_z_and_i_at_the_formats_extremes_pysim(pxp):
    """datapath "paper" keeps the running z and i in two 16-bit words, a word a cycle, in the span PXP
    and in the coherent span PXP (which shares its adder and guarded word tests): on lines whose
    z and i run far outside Q16.4 and 0..i_max both ways (z to about +-2**24, the formats' bound,
    the cases no scene reaches) and on lines of segments crossing at small depth differences, its pixels equal the golden side's (span_cycles.resolve's visible
    segment, the S.S. intensity clamped) and ours' 40-bit design's, and each line's finish-time
    counter equals span_cycles.schedule with the paper's cycles (+ one_multiplier + multiword; the
    coherent PXP: coherent.paper_resolve, whose entering segments' tests run here too)."""
    from rasterhw.golden_model.experts import coherent
    from rasterhw.golden_model.experts.formats import DZ_FRAC, X_FRAC, Formats
    from rasterhw.golden_model.experts.slp_run import block_lists
    from rasterhw.golden_model.experts.span_cycles import (
        multiword,
        one_multiplier,
        span_drain_cycles,
    )
    from rasterhw.hdl.experts.pxp_coherent import ExpertsPxpCoherent
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan, dmm_layout
    from rasterhw.hdl.pack import pack
    fmt, lay, W = Formats(), dmm_layout(), 512
    rng = np.random.default_rng(48)
    words, want, lines, zs, i_out, tested = [], [], {"ours": [], "paper": []}, [], 0, False
    entered = 0
    for slope in (None, None, None, 400, 400, 2000):
        segs = _extreme_line(rng, 7, slope=slope)
        c0 = np.array([(s["xl"] + 31) >> X_FRAC for s in segs])
        c1 = np.array([((s["xr"] + 31) >> X_FRAC) - 1 for s in segs])
        lead, buckets, _ = block_lists(list(range(len(segs))), c0, c1, np.array([0, W]), width=W)
        lead, bucket = (511 if lead[0] < 0 else lead[0]), buckets[0]
        words += [pack(lay, s) for s in segs] + [pack(lay, {"list": 1, "ptr": b}) for b in bucket]
        words.append(pack(lay, {"last": 1, "ptr": lead}))
        if pxp == "span":
            cyc, vis = resolve(segs, bucket, lead, 0, W)
        else:
            cyc, vis, cnt = coherent.resolve_counts(segs, bucket, lead, 0, W)
            entered += cnt["tests_enter"]
        tested = tested or cyc["pass_b"] > 0
        for c, v in enumerate(vis):
            s = segs[v] if v >= 0 else None
            d = (c << X_FRAC) + (1 << (X_FRAC - 1)) - s["xl"] if s else 0
            if s:
                zs.append((s["zl"] << DZ_FRAC) + ((d * s["dzdx"]) >> X_FRAC))
                i = s["il"] + ((d * s["didx"]) >> X_FRAC)
                i_out += not 0 <= i <= fmt.i_max << fmt.i_frac
            want.append((s["hue"] << fmt.intensity_bits) | (min(max(i, 0), fmt.i_max << fmt.i_frac) >> fmt.i_frac)
                        if s else 0)
        nw, r, dr = len(segs) + len(bucket) + 1, sum(cyc.values()), span_drain_cycles(vis, 0, W, aj="none", width=W)
        drawn = sum(1 for v in vis if v >= 0)
        lines["ours"].append((nw, r, dr))
        extra = (one_multiplier(cyc) + multiword(cyc, drawn) if pxp == "span" else
                 coherent.paper_resolve(cyc, drawn, cnt))
        lines["paper"].append((nw, r + extra, dr))
    # the lines reach what no scene does: visible z below 0 and above Q16.4, intensities clamped;
    # and pass B's guarded tests run (spans wider than a pixel with two segments or more)
    assert min(zs) < -(1 << 20) and max(zs) > 1 << 22 and i_out > 100 and tested
    assert pxp == "span" or entered > 5
    block = ExpertsPxpSpan if pxp == "span" else ExpertsPxpCoherent
    for dp in ("ours", "paper"):
        pix, lc = _run_lines(block(width=W, depth=16, datapath=dp), words, 6, len(want))
        assert pix == want, dp
        assert lc == schedule(lines[dp])["line_cycles"], dp
    assert sum(r for _, r, _ in lines["paper"]) > sum(r for _, r, _ in lines["ours"])
