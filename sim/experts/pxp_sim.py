"""``rasterhw sim pxp``: a scene's frame through the EXPERTS PXP HDL, pixel for pixel and cycle for cycle.

The golden bit model (no A.J.) gives every PXP's clipped ASL for every line of every band and the
expected pixels; the jobs (one per PXP and line: the range's segments, then an end-of-line token
carrying the next job's range; ``sim/experts/pxp_jobs.py``) run back to back through one PXP
instance -- the Sn x Pn PXPs are identical and independent ("他のPXPとの通信なしに独立に動作"), so
each job's cycles are that PXP's cycles on that line, and the frame takes as long as the busiest
PXP's sum (the SLP and DMM/P are not in the HDL). The jobs run through the PXP's testbench
(``sim/experts/testbench.py``: ``PxpBench``, ``PxpSpanBench``) on the generic engines
(``sim/engines/``): ``pysim`` (Amaranth; slow, for small frames) and ``verilator`` (the engine's
bench top, built once per design and memory depth under ``build/``): :func:`run_jobs`.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import ExpertsFrame, equal_bounds, render_frame
from rasterhw.golden_model.experts.pxp import to_rgb8
from rasterhw.golden_model.experts.pxp_cycles import schedule
from rasterhw.sim.experts.pxp_jobs import SEG_BITS, SPAN_BITS, job_list, span_job_list

__all__ = ["ENGINES", "PXPS", "PXP_IS", "SEG_BITS", "SPAN_BITS", "check_jobs", "job_list", "jobs", "run_jobs", "simulate_scene",
           "span_job_list", "span_ranges"]

ENGINES = ("pysim", "verilator", "cocotb-verilator", "cocotb-icarus", "icarus")   # icarus: cocotb on Icarus
PXPS = ("span", "coherent", "zbuffer")
#: what each PXP is: the paper's, or ours (with the paper's words it rests on)
PXP_IS = {"span": "ours: span cull at every segment end, a depth search per span (the paper's words: "
                  "span cull, depth search; Watkins' spans)",
          "coherent": "ours: span cull once per segment, a depth search only where the visible segment can "
                      "change (the paper's words: span cull, depth search, span coherence)",
          "zbuffer": "ours: a one-line Z-buffer (the paper argues against the Z-B method)"}


def hdl_image(fr: ExpertsFrame, got: np.ndarray) -> np.ndarray | None:
    """The frame the HDL wrote, as 8-bit RGB: its pixel words (R3 G3 B3 I, frame order: every
    line's PXP ranges left to right) decoded and shown as the VOC shows them (``to_rgb8``);
    None when the run did not give one word per pixel."""
    H, W = fr.height, fr.width
    if got.size != H * W:
        return None
    ib = fr.setup.fmt.intensity_bits
    w = got.astype(np.int64)
    fields = np.stack([(w >> (6 + ib)) & 7, (w >> (3 + ib)) & 7, (w >> ib) & 7, w & ((1 << ib) - 1)], axis=1)
    return to_rgb8(fr.setup, fields, H, W)


def jobs(fr: ExpertsFrame, sn: int, pn: int, *, ranges: np.ndarray | None = None, pxp: str = "zbuffer",
         slp: dict | None = None) -> dict:
    """:func:`job_list` (``pxp="span"`` / ``"coherent"``: :func:`span_job_list`) for every (line, PXP) of an Sn x Pn
    split, in frame order, plus each PXP's
    own frame time by the cycle model (its band's lines back to back, as that PXP runs them):
    ``pxp_frame_cycles`` (Sn, Pn). ``ranges`` (H, Pn + 1): per-line boundaries (balancing);
    default the equal static split."""
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    H = fr.height
    bands = equal_bounds(H, sn)
    rbs = np.broadcast_to(equal_bounds(fr.width, pn) if ranges is None else np.asarray(ranges), (H, pn + 1))
    todo = [(y, int(rbs[y, p]), int(rbs[y, p + 1])) for y in range(H) for p in range(pn)]
    jb = span_job_list(fr, todo, slp, pxp=pxp) if pxp in ("span", "coherent") else job_list(fr, todo)
    jb["owner"] = [(int(np.searchsorted(bands, y, side="right") - 1), p) for y in range(H) for p in range(pn)]
    per = np.zeros((sn, pn), np.int64)
    for sidx in range(sn):
        for p in range(pn):
            # job k = y * pn + p (frame order): its segments were clipped once, in job_list
            ys = range(int(bands[sidx]), int(bands[sidx + 1]))
            if pxp in ("span", "coherent"):
                per[sidx, p] = span_schedule([jb["timing"][y * pn + p] for y in ys])["last_pixel"] + 1
                continue
            own = [(jb["segments"][y * pn + p], int(rbs[y, p]), int(rbs[y, p + 1])) for y in ys]
            per[sidx, p] = schedule(own, aj=fr.aj, width=fr.width)["last_pixel"] + 1
    jb["pxp_frame_cycles"] = per
    return jb


def span_ranges(fr: ExpertsFrame, sn: int, pn: int, method: str, *, pxp: str = "span") -> np.ndarray:
    """(H, Pn + 1) ranges for the span PXP set line by line by method i / ii
    (:func:`parallel.rebalance`) from the previous line's finish-time counters of every PXP of the
    band, each PXP's own lines back to back (``span_cycles.schedule``); ``pxp="coherent"``: the
    coherent span PXP's counters (``coherent.resolve``)."""
    from rasterhw.golden_model.experts.coherent import resolve as coherent_resolve
    from rasterhw.golden_model.experts.parallel import Balance, rebalance
    from rasterhw.golden_model.experts.span_cycles import dmm_line, line_job
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    H, W = fr.height, fr.width
    bands = equal_bounds(H, sn)
    out = np.zeros((H, pn + 1), np.int64)
    for s in range(sn):
        widths = np.diff(equal_bounds(W, pn))
        own: list[list] = [[] for _ in range(pn)]
        for y in range(int(bands[s]), int(bands[s + 1])):
            b = np.concatenate([[0], np.cumsum(widths)]).astype(np.int64)
            out[y] = b
            segs, lead, buckets = dmm_line(fr, y, b)
            c = np.zeros(pn)
            for p in range(pn):
                j = line_job(segs, buckets[p], lead[p], int(b[p]), int(b[p + 1]), aj=fr.aj, width=W,
                             resolver=coherent_resolve if pxp == "coherent" else None)
                own[p].append((j["words"], j["resolve"], j["drain"]))
                c[p] = span_schedule(own[p])["line_cycles"][-1]
            widths = rebalance(widths, c, method, Balance())
    return out


#: the Verilator engine's memories for the scene runs (one build serves every frame up to 512 x 512
#: at up to 16 x 64 PXP lines): input words, and every output port's words
IN_DEPTH, OUT_DEPTH = 1 << 19, 1 << 19


def run_jobs(jb: dict, *, width: int, engine: str = "pysim", idle: int = 0, stall: int = 0, seed: int = 1) -> dict:
    """Play the jobs ``jb`` (:func:`job_list`; :func:`span_job_list`: the span PXP) through the
    PXP's testbench (``PxpBench`` / ``PxpSpanBench``) on ``engine`` (``pysim`` or ``verilator``).

    ``idle`` / ``stall`` (0..255): random idle clocks before every input word (each clock idle with
    probability ``idle / 256``, drawn per word by the engines, ``engines.with_gaps``) and random
    back-pressure on the pixel output (``ready`` low when a seeded xorshift's low byte is below
    ``stall``), seeded by ``seed``; both 0 is the cycle-exact run.

    Returns ``pixels`` (the pixel words), ``cycles`` (every line's finish-time counter, from the
    testbench's line log), ``sim_cycles`` (= ``last_pixel``: the PXP's clock edges up to and
    including the frame's last pixel, counted from its first edge), ``run_s``, ``build_s``."""
    from rasterhw.sim.engines import run, with_gaps
    from rasterhw.sim.experts.testbench import (
        PxpBench,
        PxpCoherentBench,
        PxpSpanBench,
        job_stimulus,
    )
    for what, v in (("idle", idle), ("stall", stall)):
        if not (isinstance(v, int) and 0 <= v <= 255):
            raise RasterhwError(f"experts PXP bench: {what} must be an integer in 0..255, not {v!r}")
    if engine not in ENGINES:
        raise RasterhwError(f"experts: PXP engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if jb.get("seg_bits", SEG_BITS) == SPAN_BITS:
        tb = (PxpCoherentBench if jb.get("pxp") == "coherent" else PxpSpanBench)(log=True)
    else:
        tb = PxpBench(log=True)
    p = tb.params(width=width, aj=jb["aj"])
    stim = job_stimulus(jb)
    if idle:
        # the range word first, always on edge 0 (the PXP's clock starts after it): gaps from the next
        g = with_gaps(stim, idle / 256, seed, ("i",)).gaps["i"]
        stim = replace(stim, gaps={"i": [0, *g[1:]]})
    npix, nlines = int(jb["pixels"].size), int(jb["lines"])
    nwords = len(stim.words["i"])
    if engine == "verilator" and (nwords + 2 > IN_DEPTH or max(npix, nlines) + 2 > OUT_DEPTH):
        raise RasterhwError(f"experts: {nwords} words / {npix} pixels exceed the bench's {IN_DEPTH - 2} / "
                            f"{OUT_DEPTH - 2}")
    gaps = int(np.sum(stim.gaps_of("i")))
    maxcyc = (int(jb["cycles"].sum()) * 2 + 10000 + gaps) * (1 + (idle + stall) // 16)
    got = run(tb, p, stim, engine=engine, stall=stall, seed=seed, expect_words={"o": npix, "log": nlines},
              max_cycles=maxcyc, build={"depth": IN_DEPTH, "out_depth": OUT_DEPTH} if engine == "verilator" else None)
    if got.protocol_errors:
        raise RasterhwError(f"experts: the PXP bench saw {got.protocol_errors} clocks that broke the stream rules")
    st = got.stamps["o"]
    # the PXP's edge k is the run's edge k + 1 (edge 0 takes the range word): edges up to the last pixel
    last = int(st[-1]) if st else 0
    return {"pixels": np.array(got.words["o"], np.int64), "cycles": np.array(got.words["log"], np.int64),
            "run_s": got.run_s, "build_s": got.build_s, "sim_cycles": last, "last_pixel": last}


def check_jobs(jb: dict, *, width: int, engine: str, idle: int = 0, stall: int = 0, seed: int = 1) -> dict:
    """:func:`run_jobs`, checked against the golden PXP: ``pixel_mismatches`` (pixel words that
    differ, in order, and a missing or extra pixel counts too) and ``line_mismatches`` (lines whose
    finish-time counter differs from the golden cycle model's; with idle input or back-pressure only
    a line finishing sooner than the model says counts: waiting clocks lengthen a line)."""
    r = run_jobs(jb, width=width, engine=engine, idle=idle, stall=stall, seed=seed)
    want_pix, want_cyc = np.asarray(jb["pixels"], np.int64).ravel(), np.asarray(jb["cycles"], np.int64).ravel()
    got_pix, got_cyc = r["pixels"], r["cycles"]
    n = min(len(got_pix), len(want_pix))
    pix = int(np.sum(got_pix[:n] != want_pix[:n])) + abs(len(got_pix) - len(want_pix))
    m = min(len(got_cyc), len(want_cyc))
    late = (got_cyc[:m] != want_cyc[:m]) if idle == 0 and stall == 0 else (got_cyc[:m] < want_cyc[:m])
    lines = int(np.sum(late)) + abs(len(got_cyc) - len(want_cyc))
    return {**r, "pixel_mismatches": pix, "line_mismatches": lines}


def simulate_scene(scene, width: int, height: int, *, engine: str = "pysim", progress: bool = False,
                   sn: int | None = 8, pn: int | None = 8, aj: str | None = "c",
                   ranges: str | None = "static", idle: int = 0, stall: int = 0, seed: int = 1,
                   pxp: str | None = "span") -> dict:
    """Registry sim block ``pxp``: the whole frame through the PXP HDL, compared with the golden model.

    ``pxp`` (:data:`PXP_IS`): ``"span"`` (default: ``experts-pxp-span``, span cull at every segment
    end and a depth search per span, the line's ASL and block lists through its DMM/P),
    ``"coherent"`` (``experts-pxp-coherent``: the same DMM/P words, span cull once per segment and
    a depth search only where the visible segment can change) or ``"zbuffer"`` (``experts-pxp``, a
    one-line Z-buffer); the same pixels.

    ``idle`` / ``stall`` (Verilator only, 0..255): random input idle clocks / output back-pressure.
    Then the pixels are compared as always, and ``cycle_mismatches`` counts the lines that
    finished *faster* than the cycle model (a stalled line may only be slower; span PXP: faster
    than its resolve work alone); ``0, 0`` is the cycle-exact run (every line's finish-time
    counter equal to the model's)."""
    from rasterhw.golden_model.pipeline import run_geometry
    if engine not in ENGINES:
        raise RasterhwError(f"experts: sim pxp engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    sn = 8 if sn is None else sn
    pn = 8 if pn is None else pn
    t0 = time.perf_counter()
    aj = "c" if aj is None else aj
    if aj not in ("none", "c"):
        raise RasterhwError(f"experts: sim pxp aj must be none or c (the PXP HDL has method (c)), not {aj!r}")
    ranges = "static" if ranges is None else ranges
    if ranges not in ("static", "i", "ii"):
        raise RasterhwError(f"experts: sim pxp ranges must be static, i or ii, not {ranges!r}")
    pxp = "span" if pxp is None else pxp
    if pxp not in PXPS:
        raise RasterhwError(f"experts: sim pxp --pxp must be one of {', '.join(PXPS)}, not {pxp!r}")
    fr = render_frame(run_geometry(scene, width, height, z_bits=16), model="bit", aj=aj)
    rb = None
    if ranges != "static" and pxp != "zbuffer":
        rb = span_ranges(fr, sn, pn, ranges, pxp=pxp)
    elif ranges != "static":
        # ranges set line by line from the previous line's finish-time counters (the PXP HDL's
        # resolve cycles, as the cycle model the HDL matches gives them)
        from rasterhw.golden_model.experts.parallel import run_parallel
        rb = run_parallel(fr, sn, pn, band_method="equal", range_method=ranges, pxp_unit="cycles").ranges
    jb = jobs(fr, sn, pn, ranges=rb, pxp=pxp)
    if progress:
        print(f"experts: {jb['lines']} PXP lines, {len(jb['words'])} words, {int(jb['cycles'].sum()):,} cycles expected", file=sys.stderr)
    exact = idle == 0 and stall == 0
    if not exact and engine != "verilator":
        raise RasterhwError("experts: idle and stall are settings of the Verilator bench")
    res = run_jobs(jb, width=width, engine=engine, idle=idle, stall=stall, seed=seed)
    got = res["pixels"]
    n = min(got.size, jb["pixels"].size)
    mism = int(np.count_nonzero(got[:n] != jb["pixels"][:n])) + abs(got.size - jb["pixels"].size)
    cyc = res["cycles"][:jb["lines"]]
    model = jb["cycles"][:cyc.size]
    if not exact and pxp != "zbuffer":
        # input idle delays a line's start and so may shorten its wait for the drain: the floor
        # of a stalled span line is its own resolve work (+ the hand-over cycle)
        model = np.array([t[1] + 1 for t in jb["timing"]], np.int64)[:cyc.size]
    cyc_mism = int(np.count_nonzero(cyc != model if exact else cyc < model)) + (jb["lines"] - cyc.size)
    # the HDL ran every line of every PXP, interleaved, and matched the cycle model line for line;
    # a PXP's frame time (its own lines back to back) is then the model's
    # cycles simulated: up to the frame's last pixel (the DUT's first cycle samples the range)
    total = int(res["sim_cycles"])
    frame_cycles = int(jb["pxp_frame_cycles"].max())
    return {"engine": engine, "cycles": total, "clock_hz": None, "pixels_compared": int(n),
            "mismatches": mism, "wall_s": round(time.perf_counter() - t0, 3),
            "cycles_per_s": round(total / res["run_s"], 1) if res["run_s"] > 0 else None,
            "cycle_mismatches": cyc_mism, "frame_cycles_busiest_pxp": frame_cycles,
            "last_pixel_mismatch": int(total != jb["last_pixel"] + (1 if pxp != "zbuffer" else 2)) if exact else 0,
            "pxp_cycles_per_line_mean": round(float(cyc.mean()), 2) if cyc.size else 0.0,
            "pxp_clock_for_30fps_hz": frame_cycles * 30, "sn": sn, "pn": pn, "aj": aj, "ranges": ranges,
            "pxp": pxp, "pxp_is": PXP_IS[pxp],
            **({"span_steps": {k: int(sum(st[k] for st in jb["steps"])) for k in jb["steps"][0]}}
               if pxp != "zbuffer" and jb["steps"] else {}),
            "run_s": round(res["run_s"], 3), "build_s": round(res.get("build_s", 0.0), 2),
            # the machine's frame on its Sn x Pn PXPs (all at once): the busiest PXP's
            "frame_cycles": frame_cycles, "frame_rgb": hdl_image(fr, got)}
