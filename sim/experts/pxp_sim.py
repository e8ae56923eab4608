"""``rasterhw sim pxp``: a scene's frame through the EXPERTS PXP HDL, pixel for pixel and cycle for cycle.

The golden bit model (no A.J.) gives every PXP's clipped ASL for every line of every band and the
expected pixels; the jobs (one per PXP and line: the range's segments, then an end-of-line token
carrying the next job's range) run back to back through one PXP instance -- the Sn x Pn PXPs are
identical and independent ("他のPXPとの通信なしに独立に動作"), so each job's cycles are that PXP's
cycles on that line, and the frame takes as long as the busiest PXP's sum (the SLP and DMM/P are
not in the HDL). Engines: ``pysim`` (Amaranth; slow, for small frames) and ``verilator`` (a
timing-free bench, ``sim/experts/verilator/``, built once per Verilog hash under ``build/``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import ExpertsFrame, equal_bounds, render_frame
from rasterhw.golden_model.experts.pxp import pixel_words, to_rgb8
from rasterhw.golden_model.experts.pxp_cycles import line_segments, schedule
from rasterhw.sim.engines.runner import run_plain_verilator
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["jobs", "span_job_list", "span_ranges", "run_pysim", "run_verilator", "simulate_scene", "ENGINES", "PXPS"]

ENGINES = ("pysim", "verilator")
PXPS = ("span", "zbuffer")
BENCH_DIR = Path(__file__).resolve().parent / "verilator"
SEG_BITS = 194          # seg_layout().size (checked in jobs)


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


def _pack(seg: dict, layout) -> int:
    from rasterhw.hdl.pack import pack
    return pack(layout, seg)


def job_list(fr: ExpertsFrame, todo: list[tuple[int, int, int]]) -> dict:
    """Stimulus, expected pixels and cycles for PXP lines ``(y, lo, hi)`` run one after another."""
    from rasterhw.hdl.experts.pxp import seg_layout
    lay = seg_layout()
    if lay.size != SEG_BITS:
        raise RasterhwError(f"experts: the bench expects {SEG_BITS}-bit segments, the PXP has {lay.size}")
    aj = fr.aj
    W = fr.width
    words, exp_pix, lines, per_job = [], [], [], []
    pix = pixel_words(fr.setup, fr.fields).reshape(fr.height, W)
    for k, (y, lo, hi) in enumerate(todo):
        segs = line_segments(fr, y, lo, hi, aj=aj)
        for s in segs:
            words.append(_pack({"last": 0, **s}, lay))
        _, nlo, nhi = todo[k + 1] if k + 1 < len(todo) else todo[k]
        words.append((nhi << (SEG_BITS + 10)) | (nlo << SEG_BITS) | _pack({"last": 1}, lay))
        lines.append((segs, lo, hi))
        per_job.append(segs)
        exp_pix.append(pix[y, lo:hi])
    sch = schedule(lines, aj=aj, width=W)
    return {"words": words, "pixels": np.concatenate(exp_pix).astype(np.int64) if exp_pix else np.zeros(0, np.int64),
            "cycles": np.array(sch["line_cycles"], np.int64), "last_pixel": sch["last_pixel"],
            "lo0": todo[0][1], "hi0": todo[0][2], "lines": len(todo), "aj": aj, "segments": per_job}


SPAN_BITS = 204         # dmm_layout().size (checked in span_job_list)


def span_job_list(fr: ExpertsFrame, todo: list[tuple[int, int, int]], slp: dict | None = None) -> dict:
    """:func:`job_list` for the span PXP (``experts-pxp-span``): per PXP line ``(y, lo, hi)`` the
    DMM/P words the SLP writes (the line's whole ASL, the range's bucket list, the ``last`` token
    with the leading pointer and the next job's range), the expected pixels and the cycles of
    ``golden_model/experts/span_cycles.py``; ``visible`` per job (ASL record ids, -1 background).
    ``slp``: ``{(y, lo, hi): (the ASBs in ASL order, leading pointer, bucket list)}`` as an SLP
    (the ``experts-slp`` HDL) wrote them, instead of the golden SLP's."""
    from rasterhw.golden_model.experts.span_cycles import NO_PTR, dmm_line, line_asl, line_job
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    from rasterhw.hdl.experts.pxp_span import dmm_layout
    from rasterhw.hdl.pack import pack
    lay = dmm_layout()
    if lay.size != SPAN_BITS:
        raise RasterhwError(f"experts: the bench expects {SPAN_BITS}-bit DMM/P words, the span PXP has {lay.size}")
    W = fr.width
    aj = fr.aj
    pix = pixel_words(fr.setup, fr.fields).reshape(fr.height, W)
    cache: dict[int, tuple] = {}
    words, exp_pix, lines, steps, visible = [], [], [], [], []
    for k, (y, lo, hi) in enumerate(todo):
        if y not in cache:
            segs, ids = line_asl(fr, y)
            if slp is not None:       # the SLP's ASBs in its ASL order (wrong ones show as wrong pixels)
                rid = {s["addr"]: r for s, r in zip(segs, ids, strict=True)}
                segs = slp[(y, lo, hi)][0]
                if sorted(s["addr"] for s in segs) != sorted(rid):
                    raise RasterhwError(f"experts: the SLP's ASL of line {y} is not the line's segments")
                ids = np.array([rid[s["addr"]] for s in segs], np.int64)
            cache = {y: (segs, ids, [pack(lay, {"last": 0, "list": 0, "ptr": 0, **s}) for s in segs])}
        segs, ids, packed = cache[y]
        if slp is None:
            _, lead, buckets = dmm_line(fr, y, [lo, hi])
        else:
            _, ld, bk = slp[(y, lo, hi)]
            lead, buckets = [NO_PTR if ld < 0 else ld], [bk]
        job = line_job(segs, buckets[0], lead[0], lo, hi, aj=aj, width=W)
        _, nlo, nhi = todo[k + 1] if k + 1 < len(todo) else todo[k]
        words += packed
        words += [pack(lay, {"list": 1, "ptr": b}) for b in buckets[0]]
        words.append((nhi << (SPAN_BITS + 10)) | (nlo << SPAN_BITS) | pack(lay, {"last": 1, "ptr": lead[0]}))
        lines.append((job["words"], job["resolve"], job["drain"]))
        steps.append(job["steps"])
        visible.append(np.array([int(ids[v]) if v >= 0 else -1 for v in job["visible"]], np.int64))
        exp_pix.append(pix[y, lo:hi])
    sch = span_schedule(lines)
    return {"words": words, "pixels": np.concatenate(exp_pix).astype(np.int64) if exp_pix else np.zeros(0, np.int64),
            "cycles": np.array(sch["line_cycles"], np.int64), "last_pixel": sch["last_pixel"],
            "lo0": todo[0][1], "hi0": todo[0][2], "lines": len(todo), "aj": aj, "steps": steps,
            "visible": visible, "timing": lines, "seg_bits": SPAN_BITS}


def jobs(fr: ExpertsFrame, sn: int, pn: int, *, ranges: np.ndarray | None = None, pxp: str = "zbuffer",
         slp: dict | None = None) -> dict:
    """:func:`job_list` (``pxp="span"``: :func:`span_job_list`) for every (line, PXP) of an Sn x Pn
    split, in frame order, plus each PXP's
    own frame time by the cycle model (its band's lines back to back, as that PXP runs them):
    ``pxp_frame_cycles`` (Sn, Pn). ``ranges`` (H, Pn + 1): per-line boundaries (balancing);
    default the equal static split."""
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    H = fr.height
    bands = equal_bounds(H, sn)
    rbs = np.broadcast_to(equal_bounds(fr.width, pn) if ranges is None else np.asarray(ranges), (H, pn + 1))
    todo = [(y, int(rbs[y, p]), int(rbs[y, p + 1])) for y in range(H) for p in range(pn)]
    jb = span_job_list(fr, todo, slp) if pxp == "span" else job_list(fr, todo)
    jb["owner"] = [(int(np.searchsorted(bands, y, side="right") - 1), p) for y in range(H) for p in range(pn)]
    per = np.zeros((sn, pn), np.int64)
    for sidx in range(sn):
        for p in range(pn):
            # job k = y * pn + p (frame order): its segments were clipped once, in job_list
            ys = range(int(bands[sidx]), int(bands[sidx + 1]))
            if pxp == "span":
                per[sidx, p] = span_schedule([jb["timing"][y * pn + p] for y in ys])["last_pixel"] + 1
                continue
            own = [(jb["segments"][y * pn + p], int(rbs[y, p]), int(rbs[y, p + 1])) for y in ys]
            per[sidx, p] = schedule(own, aj=fr.aj, width=fr.width)["last_pixel"] + 1
    jb["pxp_frame_cycles"] = per
    return jb


def span_ranges(fr: ExpertsFrame, sn: int, pn: int, method: str) -> np.ndarray:
    """(H, Pn + 1) ranges for the span PXP set line by line by method i / ii
    (:func:`parallel.rebalance`) from the previous line's finish-time counters of every PXP of the
    band, each PXP's own lines back to back (``span_cycles.schedule``)."""
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
                j = line_job(segs, buckets[p], lead[p], int(b[p]), int(b[p + 1]), aj=fr.aj, width=W)
                own[p].append((j["words"], j["resolve"], j["drain"]))
                c[p] = span_schedule(own[p])["line_cycles"][-1]
            widths = rebalance(widths, c, method, Balance())
    return out


def run_pysim(jb: dict, *, width: int) -> dict:
    """Play the jobs through the Amaranth PXP in pysim."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.experts.pxp import ExpertsPxp
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan
    from rasterhw.sim.engines.harness import stream_sink
    bits = jb.get("seg_bits", SEG_BITS)
    dut = (ExpertsPxpSpan if bits == SPAN_BITS else ExpertsPxp)(width=width, aj=jb["aj"])
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got, cyc = [], []
    n_lines = jb["lines"]
    mask = (1 << bits) - 1

    async def feed(ctx):
        ctx.set(dut.lo, jb["lo0"])
        ctx.set(dut.hi, jb["hi0"])
        for w in jb["words"]:
            ctx.set(dut.i.payload.as_value(), w & mask)
            ctx.set(dut.i.valid, 1)
            await ctx.tick().until(dut.i.ready)
            ctx.set(dut.i.valid, 0)
            if w & 1:
                ctx.set(dut.lo, (w >> bits) & 0x3FF)
                ctx.set(dut.hi, (w >> (bits + 10)) & 0x7FF)

    npix = int(jb["pixels"].size)
    last = {}

    async def watch(ctx):
        seen = t = taken = 0
        async for _clk, _rst, n, c, v, r in ctx.tick().sample(dut.lines, dut.line_cycles, dut.o.valid, dut.o.ready):
            t += 1
            if v and r:
                taken += 1
                if taken == npix:
                    last["cycle"] = t
            if n != seen:
                cyc.append(c)
                seen = n
            if seen == n_lines and taken >= npix:
                return

    sim.add_testbench(feed)
    sim.add_testbench(stream_sink(dut.o, got), background=True)
    sim.add_testbench(watch)
    t = time.perf_counter()
    sim.run()
    return {"pixels": np.array(got, np.int64), "cycles": np.array(cyc, np.int64), "run_s": time.perf_counter() - t,
            "last_pixel": last.get("cycle")}


NSEG_MAX, NOUT_MAX, NLINE_MAX = 1 << 19, 1 << 18, 1 << 14


def _build(width: int, aj: str, bits: int = SEG_BITS) -> tuple[Path, float]:
    from rasterhw.hdl.experts.pxp import ExpertsPxp
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan
    from rasterhw.sim.engines.runner import build_plain_verilator
    from rasterhw.sim.engines.verilog_cache import convert_cached
    block, cls = ("experts-pxp-span", ExpertsPxpSpan) if bits == SPAN_BITS else ("experts-pxp", ExpertsPxp)
    # both PXPs go into the bench as module experts_pxp (same ports; the span PXP's words are wider)
    src = convert_cached(block, lambda: cls(width=width, aj=aj), params={"width": width, "aj": aj},
                         module="experts_pxp")
    params = {"NSEG": NSEG_MAX, "NOUT": NOUT_MAX, "NLINE": NLINE_MAX, "SEGW": bits}
    # 4 edges after done so the last line's finish-time counter is stored
    return build_plain_verilator(block, "tb_experts_pxp", [BENCH_DIR / "tb_experts_pxp.v"], params=params,
                                 defines={"RASTERHW_TAIL": 4}, generated={"experts_pxp.v": src})


def _read_hex(path: Path) -> np.ndarray:
    lines = [ln.strip() for ln in path.read_text().split("\n")]
    lines = [ln for ln in lines if ln and not ln.startswith("//") and not ln.startswith("@")]
    if any(c in ln for ln in lines for c in "xXzZ"):
        raise RasterhwError(f"{path}: the dump holds X or Z bits")
    return np.array([int(ln, 16) for ln in lines], np.int64)


def run_verilator(jb: dict, *, width: int, idle: int = 0, stall: int = 0, seed: int = 1) -> dict:
    """Play the jobs through the generated Verilog on plain Verilator. ``idle`` / ``stall``
    (0..255): random idle clocks on the input / random back-pressure on the output (the bench's
    +idle / +stall, seeded by ``seed``); both 0 is the cycle-exact run."""
    for what, v in (("idle", idle), ("stall", stall)):
        if not (isinstance(v, int) and 0 <= v <= 255):
            raise RasterhwError(f"experts PXP bench: {what} must be an integer in 0..255, not {v!r}")
    nseg, nout, nline = len(jb["words"]), int(jb["pixels"].size), jb["lines"]
    if nseg > NSEG_MAX or nout > NOUT_MAX or nline > NLINE_MAX:
        raise RasterhwError(f"experts: {nseg} words / {nout} pixels / {nline} lines exceed the bench's "
                            f"{NSEG_MAX} / {NOUT_MAX} / {NLINE_MAX}")
    exe, build_s = _build(width, jb["aj"], jb.get("seg_bits", SEG_BITS))
    run_dir = temp_run_folder(exe.parent.parent)
    (run_dir / "seg.hex").write_text("\n".join(f"{w:x}" for w in jb["words"]) + "\n")
    meta = run_plain_verilator(exe, [f"+seg={run_dir / 'seg.hex'}", f"+out={run_dir / 'out.hex'}",
                                     f"+cyc={run_dir / 'cyc.hex'}", f"+nseg={nseg}", f"+nout={nout}",
                                     f"+lo0={jb['lo0']}", f"+hi0={jb['hi0']}", f"+idle={idle}",
                                     f"+stall={stall}", f"+seed={seed}"],
                               run_dir=run_dir, maxcyc=(int(jb["cycles"].sum()) * 2 + 10000) * (1 + (idle + stall) // 16))
    # the bench dumps its whole frame and line memories (NOUT_MAX / NLINE_MAX words): this run's part
    out = {"pixels": _read_hex(run_dir / "out.hex")[:nout], "cycles": _read_hex(run_dir / "cyc.hex")[:nline],
           "run_s": meta["run_s"], "sim_cycles": meta["sim_cycles"], "build_s": build_s}
    release(run_dir)
    return out


def simulate_scene(scene, width: int, height: int, *, engine: str = "pysim", progress: bool = False,
                   sn: int | None = 8, pn: int | None = 8, aj: str | None = "c",
                   ranges: str | None = "static", idle: int = 0, stall: int = 0, seed: int = 1,
                   pxp: str | None = "span") -> dict:
    """Registry sim block ``pxp``: the whole frame through the PXP HDL, compared with the golden model.

    ``pxp``: ``"span"`` (default, the paper's PXP: ``experts-pxp-span``, span cull and depth search
    per span, the line's ASL and block lists through its DMM/P) or ``"zbuffer"`` (ours:
    ``experts-pxp``, a one-line Z-buffer; the same pixels).

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
    if ranges != "static" and pxp == "span":
        rb = span_ranges(fr, sn, pn, ranges)
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
    res = run_pysim(jb, width=width) if engine == "pysim" else run_verilator(jb, width=width, idle=idle,
                                                                             stall=stall, seed=seed)
    got = res["pixels"]
    n = min(got.size, jb["pixels"].size)
    mism = int(np.count_nonzero(got[:n] != jb["pixels"][:n])) + abs(got.size - jb["pixels"].size)
    cyc = res["cycles"][:jb["lines"]]
    model = jb["cycles"][:cyc.size]
    if not exact and pxp == "span":
        # input idle delays a line's start and so may shorten its wait for the drain: the floor
        # of a stalled span line is its own resolve work (+ the hand-over cycle)
        model = np.array([t[1] + 1 for t in jb["timing"]], np.int64)[:cyc.size]
    cyc_mism = int(np.count_nonzero(cyc != model if exact else cyc < model)) + (jb["lines"] - cyc.size)
    # the HDL ran every line of every PXP, interleaved, and matched the cycle model line for line;
    # a PXP's frame time (its own lines back to back) is then the model's
    # cycles simulated: up to the frame's last pixel (the DUT's first cycle samples the range)
    total = int(res["sim_cycles"] if engine == "verilator" else (res.get("last_pixel") or 0))
    frame_cycles = int(jb["pxp_frame_cycles"].max())
    return {"engine": engine, "cycles": total, "clock_hz": None, "pixels_compared": int(n),
            "mismatches": mism, "wall_s": round(time.perf_counter() - t0, 3),
            "cycles_per_s": round(total / res["run_s"], 1) if res["run_s"] > 0 else None,
            "cycle_mismatches": cyc_mism, "frame_cycles_busiest_pxp": frame_cycles,
            "last_pixel_mismatch": int(total != jb["last_pixel"] + (1 if pxp == "span" else 2)) if exact else 0,
            "pxp_cycles_per_line_mean": round(float(cyc.mean()), 2) if cyc.size else 0.0,
            "pxp_clock_for_30fps_hz": frame_cycles * 30, "sn": sn, "pn": pn, "aj": aj, "ranges": ranges,
            "pxp": pxp, "pxp_is": "the paper's (span cull + depth search)" if pxp == "span" else "ours (line Z-buffer)",
            **({"span_steps": {k: int(sum(st[k] for st in jb["steps"])) for k in jb["steps"][0]}}
               if pxp == "span" and jb["steps"] else {}),
            "run_s": round(res["run_s"], 3), "build_s": round(res.get("build_s", 0.0), 2),
            # the machine's frame on its Sn x Pn PXPs (all at once): the busiest PXP's
            "frame_cycles": frame_cycles, "frame_rgb": hdl_image(fr, got)}
