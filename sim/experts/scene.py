"""``rasterhw sim pxp`` and ``rasterhw sim experts``: EXPERTS' scene level (``sim/engines/scene.py``).

``sim pxp`` (:class:`PxpScene`): the golden bit model (no A.J. or (c)) gives every PXP's words for
every line of every band and the expected pixels; the jobs (one per PXP and line: the range's
segments or DMM/P words, then an end-of-line token carrying the next job's range;
``sim/experts/pxp_jobs.py``) run back to back through one PXP instance -- the Sn x Pn PXPs are
identical and independent ("他のPXPとの通信なしに独立に動作"), so each job's cycles are that PXP's
cycles on that line (the line log, checked against the cycle model), and the frame takes as long as
the busiest PXP's own lines back to back.

``sim experts`` (:class:`ExpertsScene`), the whole frame in three runs, each taking the one before's
words (:meth:`SceneRun.more`): every band's set-up through one ``experts-slp-setup`` (band word,
then the PL: ``slp_setup.pl_words``), words and stamps against ``slp_setup.band_setup``; every
band's list work through one ``experts-slp`` on the set-up HDL's words (the SLPs are identical and
independent, "ホスト計算機はすべての SLP に同一の PL を送出するだけ"), words and end-of-line stamps
against ``slp_cycles``; then the SLP HDL's lists as every PXP's DMM/P words through
``experts-pxp-coherent`` (``--pxp``: by default; ``span``: ``experts-pxp-span``) as ``sim pxp`` runs them. An SLP's frame is its band's set-up plus list-work
cycles (one processor's two phases, both as the HDL took them), a PXP's its own lines back to back;
the clock for 30 frames/s is the busiest one's cycles x 30 (the paper names no clock).
``path="group"``: every band through ``experts-group`` (SLP, DMM/P writers and Pn span PXPs
clocked together), pixels against golden, the band's cycles as measured (no cycle model).
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import ExpertsFrame, equal_bounds, render_frame
from rasterhw.golden_model.experts.pxp import to_rgb8
from rasterhw.golden_model.experts.pxp_cycles import schedule
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.sim.engines.scene import Done, Job, SceneRun, run_job
from rasterhw.sim.experts.pxp_jobs import SEG_BITS, SPAN_BITS, job_list, span_job_list
from rasterhw.sim.testbench import Expected, Stimulus

__all__ = ["ENGINES", "ExpertsScene", "PXPS", "PXP_IS", "PxpScene", "check_jobs", "decode_slp", "jobs", "pxp_job",
           "run_jobs", "simulate_frame", "simulate_scene", "span_ranges"]

ENGINES = ("pysim", "verilator", "cocotb-verilator", "cocotb-icarus", "icarus")   # icarus: cocotb on Icarus
PXPS = ("span", "coherent", "zbuffer")
#: what each PXP is: the paper's, or ours (with the paper's words it rests on)
PXP_IS = {"span": "ours: span cull at every segment end, a depth search per span (the paper's words: "
                  "span cull, depth search; Watkins' spans)",
          "coherent": "ours: span cull once per segment, a depth search only where the visible segment can "
                      "change (the paper's words: span cull, depth search, span coherence)",
          "zbuffer": "ours: a one-line Z-buffer (the paper argues against the Z-B method)"}
#: the Verilator engine's memories for the scene runs (one build serves every frame up to 512 x 512
#: at up to 16 x 64 PXP lines): input words, and every output port's words
IN_DEPTH, OUT_DEPTH = 1 << 19, 1 << 19


def hdl_image(fr: ExpertsFrame, got) -> np.ndarray | None:
    """The frame the HDL wrote, as 8-bit RGB: its pixel words (R3 G3 B3 I, frame order: every
    line's PXP ranges left to right) decoded and shown as the VOC shows them (``to_rgb8``);
    None when the run did not give one word per pixel."""
    return _image(_display(fr), got)


def _display(fr: ExpertsFrame) -> dict:
    """What :func:`hdl_image` needs of a frame: its size and the pixel word's format (the fields of
    its set-up that ``to_rgb8`` reads: ``bit``, ``fmt.i_max``)."""
    return {"width": int(fr.width), "height": int(fr.height), "intensity_bits": int(fr.setup.fmt.intensity_bits),
            "bit": bool(fr.setup.bit), "i_max": int(fr.setup.fmt.i_max)}


def _image(d: dict, got) -> np.ndarray | None:
    """:func:`hdl_image` from the frame's :func:`_display`."""
    from types import SimpleNamespace

    H, W, ib = d["height"], d["width"], d["intensity_bits"]
    w = np.asarray(got, np.int64)
    if w.size != H * W:
        return None
    fields = np.stack([(w >> (6 + ib)) & 7, (w >> (3 + ib)) & 7, (w >> ib) & 7, w & ((1 << ib) - 1)], axis=1)
    return to_rgb8(SimpleNamespace(bit=d["bit"], fmt=SimpleNamespace(i_max=d["i_max"])), fields, H, W)


#: the jobs' fields a scene run reads (``pxp_job``, :meth:`PxpScene.result`), kept in the build cache
_KEPT = ("pixels", "cycles", "last_pixel", "lo0", "hi0", "lines", "aj", "seg_bits", "pxp", "datapath",
         "pxp_frame_cycles")


def _cached_jobs(tris, compute, **options) -> dict:
    """``compute()`` (the golden frame's display format and :func:`jobs`) for these triangles and
    ``options``, kept as a build-cache entry (``verilog_cache.arrays_cached``:
    ``build/verilog/experts-pxp-jobs-<digest>.npz``, SHA-256 checked) keyed by the triangles' bytes,
    the options and the digest of every Python source the jobs are made from (this module and,
    transitively, every module of ours it imports: the golden model, the job packing, the HDL's
    layouts). A warm run so neither renders the frame nor walks the span cycle model (nor loads
    numba and Amaranth for it): experts-1000 at 512 x 512, 8 x 8: ~1 CPU-s. Kept: the words as
    packed rows (``sim/packed.py``, the input port's width), the fields of :data:`_KEPT`, ``resolve``
    (each line's resolve cycles: a stalled run's floor) and ``span_steps`` (the step counts summed)."""
    import json
    from pathlib import Path

    from rasterhw.sim.engines.verilog_cache import arrays_cached, fields_key
    from rasterhw.sim.experts.pxp_jobs import RANGE_BITS
    from rasterhw.sim.packed import as_bytes

    def arrays() -> dict:
        gold = compute()
        jb = gold["jb"]
        meta = {"fr": gold["fr"], **{k: jb.get(k) for k in _KEPT if not isinstance(jb.get(k), np.ndarray)},
                "span_steps": ({k: int(sum(st[k] for st in jb["steps"])) for k in jb["steps"][0]}
                               if jb.get("steps") else {})}
        out = {k: np.asarray(jb[k]) for k in _KEPT if isinstance(jb.get(k), np.ndarray)}
        out["rows"] = as_bytes(jb["words"], jb.get("seg_bits", SEG_BITS) + RANGE_BITS)
        out["resolve"] = np.array([t[1] for t in jb.get("timing", [])], np.int64)
        out["meta"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
        return out

    key = fields_key(tris) + [options]
    jb = arrays_cached("experts-pxp-jobs", Path(__file__), key, arrays)
    meta = json.loads(jb.pop("meta").tobytes())
    fr = meta.pop("fr")
    jb = {**jb, **meta}
    jb["words"] = jb.pop("rows")
    return {"fr": fr, "jb": jb}


def jobs(fr: ExpertsFrame, sn: int, pn: int, *, ranges: np.ndarray | None = None, pxp: str = "zbuffer",
         slp: dict | None = None) -> dict:
    """:func:`job_list` (``pxp="span"`` / ``"coherent"``: :func:`span_job_list`) for every (line, PXP) of an
    Sn x Pn split, in frame order, plus each PXP's own frame time by the cycle model (its band's lines
    back to back, as that PXP runs them): ``pxp_frame_cycles`` (Sn, Pn), and each job's PXP ``owner``
    (band, range). ``ranges`` (H, Pn + 1):
    per-line boundaries (balancing); default the equal static split."""
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    H = fr.height
    bands = equal_bounds(H, sn)
    rbs = np.broadcast_to(equal_bounds(fr.width, pn) if ranges is None else np.asarray(ranges), (H, pn + 1))
    todo = [(y, int(rbs[y, p]), int(rbs[y, p + 1])) for y in range(H) for p in range(pn)]
    jb = span_job_list(fr, todo, slp, pxp=pxp) if pxp in ("span", "coherent") else job_list(fr, todo)
    # each job's PXP (band, range): span_cycles.paper_jobs schedules every PXP's own lines again
    jb["owner"] = [(int(np.searchsorted(bands, y, side="right") - 1), p) for y in range(H) for p in range(pn)]
    per = np.zeros((sn, pn), np.int64)
    for sidx in range(sn):
        ys = range(int(bands[sidx]), int(bands[sidx + 1]))
        for p in range(pn):
            # job k = y * pn + p (frame order): its segments were clipped once, in job_list
            if pxp in ("span", "coherent"):
                per[sidx, p] = span_schedule([jb["timing"][y * pn + p] for y in ys])["last_pixel"] + 1
            else:
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


def _byte(what: str, v) -> None:
    if isinstance(v, bool) or not (isinstance(v, int) and 0 <= v <= 255):
        raise RasterhwError(f"experts PXP bench: {what} must be an integer in 0..255, not {v!r}")


def pxp_job(jb: dict, *, width: int, engine: str = "pysim", idle: int = 0, stall: int = 0, seed: int = 1) -> Job:
    """The jobs ``jb`` (:func:`job_list`; :func:`span_job_list`: the span or coherent PXP) as one run of
    the PXP's testbench with its line log (``PxpBench`` / ``PxpSpanBench`` / ``PxpCoherentBench``,
    ``log=True``): the pixel words compared, the line log collected (every line's finish-time
    counter). ``idle`` / ``stall`` (0..255): random idle clocks before every input word (each clock
    idle with probability ``idle / 256``, ``engines.with_gaps``) and random back-pressure on the
    pixel output, seeded by ``seed``; both 0 is the cycle-exact run."""
    from rasterhw.sim.engines import with_gaps
    from rasterhw.sim.experts.testbench import (
        PxpBench,
        PxpCoherentBench,
        PxpSpanBench,
        job_stimulus,
    )
    _byte("idle", idle)
    _byte("stall", stall)
    if engine not in ENGINES:
        raise RasterhwError(f"experts: PXP engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if jb.get("seg_bits", SEG_BITS) == SPAN_BITS:
        tb = (PxpCoherentBench if jb.get("pxp") == "coherent" else PxpSpanBench)(log=True)
    else:
        tb = PxpBench(log=True)
    if isinstance(jb["words"], np.ndarray):   # packed rows (the cached jobs: _cached_jobs): the range word packed too
        from rasterhw.sim.experts.pxp_jobs import RANGE_BITS
        from rasterhw.sim.packed import as_bytes

        first = job_stimulus({**jb, "words": []})
        rows = np.concatenate([as_bytes(first.words["i"], jb.get("seg_bits", SEG_BITS) + RANGE_BITS), jb["words"]])
        stim = replace(first, words={"i": rows}, source=jb)
    else:
        stim = job_stimulus(jb)
    if idle:
        # the range word first, always on edge 0 (the PXP's clock starts after it): gaps from the next
        g = with_gaps(stim, idle / 256, seed, ("i",)).gaps["i"]
        stim = replace(stim, gaps={"i": [0, *g[1:]]})
    npix, nlines, nwords = int(jb["pixels"].size), int(jb["lines"]), len(stim.words["i"])
    if engine == "verilator" and (nwords + 2 > IN_DEPTH or max(npix, nlines) + 2 > OUT_DEPTH):
        raise RasterhwError(f"experts: {nwords} words / {npix} pixels exceed the bench's {IN_DEPTH - 2} / "
                            f"{OUT_DEPTH - 2}")
    maxcyc = (int(jb["cycles"].sum()) * 2 + 10000 + int(np.sum(stim.gaps_of("i")))) * (1 + (idle + stall) // 16)
    run = {"stall": stall, "seed": seed, "max_cycles": maxcyc,
           "build": {"depth": IN_DEPTH, "out_depth": OUT_DEPTH} if engine == "verilator" else None}
    # the paper's jobs (span_cycles.paper_jobs: one multiplier) on the block built at the paper's datapath
    dp = {"datapath": "paper"} if jb.get("datapath") == "paper" else {}
    return Job(tb, tb.params(width=width, aj=jb["aj"], **dp), stim, Expected({"o": jb["pixels"].tolist()}), run,
               cycle_exact=False, name="PXP", collect={"log": nlines})


def _pxp_checks(jb: dict, d: Done, exact: bool, floor: np.ndarray | None = None) -> dict:
    """A :func:`pxp_job`'s run: ``pixels``, ``cycles`` (the line log), ``sim_cycles`` = ``last_pixel``
    (the PXP's edges up to and including the last pixel: the run's edge 0 takes the range word),
    ``pixel_mismatches`` and ``line_mismatches`` (lines whose counter differs from the cycle model's;
    not ``exact``: only a line faster than ``floor``, default the model's, counts), ``run_s``, ``build_s``."""
    got = d.got
    cyc, want = np.array(got.words["log"], np.int64), np.asarray(jb["cycles"], np.int64)
    model = want if floor is None else floor
    m = min(cyc.size, model.size)
    late = (cyc[:m] != model[:m]) if exact else (cyc[:m] < model[:m])
    last = int(got.stamps["o"][-1]) if got.stamps["o"] else 0
    return {"pixels": np.array(got.words["o"], np.int64), "cycles": cyc, "run_s": got.run_s, "build_s": got.build_s,
            "sim_cycles": last, "last_pixel": last, "pixel_mismatches": d.cmp["mismatches"],
            "line_mismatches": int(np.sum(late)) + abs(cyc.size - want.size)}


def check_jobs(jb: dict, *, width: int, engine: str, idle: int = 0, stall: int = 0, seed: int = 1) -> dict:
    """:func:`pxp_job` run and checked against the golden PXP (:func:`_pxp_checks`); a run that broke
    the stream rules is an error."""
    d = run_job(pxp_job(jb, width=width, engine=engine, idle=idle, stall=stall, seed=seed), engine)
    if d.got.protocol_errors:
        raise RasterhwError(f"experts: the PXP bench saw {d.got.protocol_errors} clocks that broke the stream rules")
    return _pxp_checks(jb, d, idle == 0 and stall == 0)


run_jobs = check_jobs


class PxpScene(SceneRun):
    """``rasterhw sim pxp``: the whole frame through the PXP HDL, compared with the golden model.

    ``pxp`` (:data:`PXP_IS`): ``"span"`` (``experts-pxp-span``: span cull at every segment end and a
    depth search per span, the line's ASL and block lists through its DMM/P), ``"coherent"``
    (``experts-pxp-coherent``: the same words, span cull once per segment and a depth search only
    where the visible segment can change) or ``"zbuffer"`` (``experts-pxp``, a one-line Z-buffer);
    the same pixels. ``ranges``: static, or set line by line by method i / ii from the previous
    line's finish-time counters. ``idle`` / ``stall`` (Verilator only, 0..255): random input idle
    clocks / output back-pressure; then ``cycle_mismatches`` counts the lines that finished
    *faster* than the cycle model (span PXP: than its resolve work alone); ``0, 0`` is the
    cycle-exact run. ``cycles``: the run's edges up to the frame's last pixel (every PXP line on
    one instance); extra ``frame_cycles``: the machine's frame, the busiest PXP's own lines."""

    block = "pxp"
    engines = ENGINES
    steps = ("golden model + PXP jobs", "HDL simulation", "frame")

    def check(self, engine: str, sn: int = 8, pn: int = 8, aj: str = "c", ranges: str = "static", idle: int = 0,
              stall: int = 0, seed: int = 1, pxp: str = "span") -> None:
        for name, v, ok in (("aj", aj, ("none", "c")), ("ranges", ranges, ("static", "i", "ii")), ("--pxp", pxp, PXPS)):
            if v not in ok:
                raise RasterhwError(f"experts: sim pxp {name} must be one of {', '.join(ok)}, not {v!r}"
                                    + (" (the PXP HDL has method (c))" if name == "aj" else ""))
        _byte("idle", idle)
        _byte("stall", stall)
        if (idle or stall) and engine != "verilator":
            raise RasterhwError("experts: idle and stall are settings of the Verilator bench")

    def golden(self, scene, width: int, height: int, *, engine: str, sn: int = 8, pn: int = 8, aj: str = "c",
               ranges: str = "static", pxp: str = "span", **_) -> dict:
        """``{"fr": the frame's display format (:func:`_display`), "jb": the jobs}``, the jobs kept
        as a build-cache entry (:func:`_cached_jobs`)."""
        tris = run_geometry(scene, width, height, z_bits=16)
        return _cached_jobs(tris, lambda: self._golden(tris, sn=sn, pn=pn, aj=aj, ranges=ranges, pxp=pxp),
                            sn=sn, pn=pn, aj=aj, ranges=ranges, pxp=pxp)

    @staticmethod
    def _golden(tris, *, sn: int, pn: int, aj: str, ranges: str, pxp: str) -> dict:
        fr = render_frame(tris, model="bit", aj=aj)
        rb = None
        if ranges != "static" and pxp != "zbuffer":
            rb = span_ranges(fr, sn, pn, ranges, pxp=pxp)
        elif ranges != "static":
            # ranges set line by line from the previous line's finish-time counters (the PXP HDL's
            # resolve cycles, as the cycle model the HDL matches gives them)
            from rasterhw.golden_model.experts.parallel import run_parallel
            rb = run_parallel(fr, sn, pn, band_method="equal", range_method=ranges, pxp_unit="cycles").ranges
        return {"fr": _display(fr), "jb": jobs(fr, sn, pn, ranges=rb, pxp=pxp)}

    def jobs(self, gold: dict, *, engine: str, idle: int = 0, stall: int = 0, seed: int = 1, **_) -> list[Job]:
        return [pxp_job(gold["jb"], width=gold["fr"]["width"], engine=engine, idle=idle, stall=stall, seed=seed)]

    def result(self, gold: dict, done: list[Done], *, engine: str, sn: int = 8, pn: int = 8, aj: str = "c",
               ranges: str = "static", idle: int = 0, stall: int = 0, pxp: str = "span", **_) -> dict:
        (d,), jb, exact = done, gold["jb"], idle == 0 and stall == 0
        # input idle delays a line's start and so may shorten its wait for the drain: the floor of a
        # stalled span line is its own resolve work (+ the hand-over cycle)
        floor = None if exact or pxp == "zbuffer" else np.asarray(jb["resolve"], np.int64) + 1
        r = _pxp_checks(jb, d, exact, floor)
        frame = int(jb["pxp_frame_cycles"].max())
        cyc = r["cycles"]
        return {"cycles": r["sim_cycles"], "pixels_compared": min(r["pixels"].size, jb["pixels"].size),
                "cycle_mismatches": r["line_mismatches"],
                "last_pixel_mismatch": int(r["sim_cycles"] != jb["last_pixel"] + (1 if pxp != "zbuffer" else 2))
                if exact else 0,
                "pxp_cycles_per_line_mean": round(float(cyc.mean()), 2) if cyc.size else 0.0,
                "pxp_clock_for_30fps_hz": frame * 30, "sn": sn, "pn": pn, "aj": aj, "ranges": ranges, "pxp": pxp,
                "pxp_is": PXP_IS[pxp],
                **({"span_steps": jb["span_steps"]} if jb["span_steps"] else {}),
                # the machine's frame on its Sn x Pn PXPs (all at once): the busiest PXP's
                "frame_cycles": frame, "frame_rgb": _image(gold["fr"], r["pixels"])}


simulate_scene = PxpScene().simulate


# ====================================================================== the whole frame
def decode_slp(words: list[int]) -> list[tuple]:
    """``experts-slp`` output words -> ``(kind, p, pos, t, y, ASB dict)`` (signed fields sign-extended)."""
    from amaranth import Shape
    from rasterhw.hdl.experts.slp import slp_out_layout
    lay = slp_out_layout()
    top = {n: (f.offset, Shape.cast(f.shape).width) for n, f in lay}
    sub = [(n, top["asb"][0] + f.offset, Shape.cast(f.shape)) for n, f in lay.members["asb"]]

    def field(v, off, w, signed=False):
        x = (v >> off) & ((1 << w) - 1)
        return x - (1 << w) if signed and x >> (w - 1) else x
    out = []
    for v in words:
        head = tuple(field(v, top[n][0], top[n][1]) for n in ("kind", "p", "pos", "t", "y"))
        out.append((*head, {n: field(v, off, sh.width, sh.signed) for n, off, sh in sub}))
    return out


#: the census's blocks as the result's keys name the frame's units
_UNIT = {"experts-slp-setup": "slp_setup", "experts-slp": "slp_list", "experts-pxp-span": "pxp_span",
         "experts-pxp-coherent": "pxp_coherent"}
#: ``sim experts --pxp``: the PXP the chained frame runs (``default``: the coherent span PXP; in
#: ``experts-group``, whose PXPs are span PXPs, the span PXP)
FRAME_PXPS = ("default", "coherent", "span")


def frame_pxp(pxp: str, path: str) -> str:
    """The PXP ``sim experts --pxp PXP --path PATH`` runs (:data:`FRAME_PXPS`)."""
    if pxp == "default":
        return "span" if path == "group" else "coherent"
    return pxp


@cache
def _census(datapath: str, width: int, height: int, aj: str, pxp: str = "span") -> dict:
    """``census.frame_census`` of the frame ``sim experts`` chains (its PXP ``pxp`` at ``datapath`` too).
    Elaborating the three designs costs ~14 s, so the count is a build-cache entry
    (``build/verilog/experts-census-<digest>.json``, SHA-256 checked) keyed by the three blocks'
    design digests, the counting code's own and the arguments: a run with none of them changed
    reads it back and elaborates nothing."""
    import hashlib
    import json
    from pathlib import Path

    from rasterhw.hdl.experts import census
    from rasterhw.sim.cachefile import read_entry, write_entry
    from rasterhw.sim.engines.verilog_cache import source_digest, sources_digest
    from rasterhw.sim.paths import BUILD_ROOT

    designs = [source_digest(b) for b in sorted(_UNIT)]
    key = json.dumps([designs, sources_digest([Path(census.__file__)]), datapath, width, height, aj, pxp])
    path = BUILD_ROOT / "verilog" / f"experts-census-{hashlib.sha1(key.encode()).hexdigest()[:16]}.json"
    got = read_entry(path, what="the EXPERTS multiplier census")
    if got is not None:
        return json.loads(got)
    text = json.dumps(census.frame_census(datapath, pxp_datapath=datapath, width=width, height=height, aj=aj,
                                          pxp=pxp))
    write_entry(path, text.encode(), root=BUILD_ROOT)
    return json.loads(text)   # as a read-back gives it (lists, not tuples), on every run


def _accuracy(tris, datapath: str, aj: str, error: bool, *, width: int, height: int, pxp: str = "span") -> dict:
    """The datapath's contract beside what the frame's HDL has, counted from its elaborated design
    (:func:`_census`, ``census_source`` hdl:elaborated): ``datapath_bits`` (the widest multiplier
    operand), ``multipliers`` (the most in one processor), ``hdl_multipliers`` (per unit: ``slp_setup``, ``slp_list``,
    ``pxp_span`` or ``pxp_coherent``: the frame's PXP ``pxp``);
    ``error``: also the golden bit model's error against float (``accuracy_source`` golden; the
    float model rendered for it)."""
    from rasterhw.golden_model.experts.formats import DATAPATHS
    dp, c = DATAPATHS[datapath], _census(datapath, width, height, aj, pxp)
    out = {"datapath": dp.name, "datapath_label": dp.label, "datapath_bits": c["datapath_bits"],
           "multipliers": c["multipliers"], "census_source": c["source"],
           "hdl_multipliers": {_UNIT[b]: v["multipliers"] for b, v in c["per_block"].items()},
           "contract_datapath_bits": dp.word_bits, "contract_multipliers": dp.multipliers}
    if error:
        from rasterhw.golden_model.experts.accuracy import float_error
        e = float_error(tris, datapath, aj=aj)
        out.update(max_abs_error=e["max_abs_error"], pixels_differing_from_float=e["pixels_differing_from_float"],
                   psnr_db=round(e["psnr_db"], 3), visible_differing_from_float=e["visible_differing"],
                   pixels_differing_from_ours=e["pixels_differing_from_ours"], accuracy_source="golden")
    return out


def _mism(want: list, have: list) -> int:
    return sum(a != b for a, b in zip(want, have, strict=False)) + abs(len(want) - len(have))


class ExpertsScene(SceneRun):
    """``rasterhw sim experts``: the frame's SLP bands and PXP lines in HDL, against golden (module
    doc). ``cycles``: the machine's frame, the slower of the busiest SLP (set-up + list work) and the
    busiest PXP; ``path="group"``: the slowest band of ``experts-group``. ``pxp``
    (:data:`FRAME_PXPS`, :func:`frame_pxp`): the chained frame's PXP, the coherent span PXP by
    default or the span PXP. ``datapath``: ours or
    paper (the golden bit model at the paper's widths, the SLP's and the PXP's HDL built at it;
    what the HDL has: ``datapath_bits`` / ``multipliers`` from its elaborated design);
    ``accuracy`` (always with ``datapath="paper"``): the bit model's error against float too."""

    block = "experts"
    engines = ENGINES
    steps = ("golden model + SLP words", "HDL simulation (set-up, list work, PXPs)", "frame")

    def check(self, engine: str, sn: int = 8, pn: int = 8, aj: str = "c", path: str = "chained",
              datapath: str = "ours", accuracy: bool = False, pxp: str = "default") -> None:
        from rasterhw.golden_model.experts.formats import DATAPATHS
        for name, v, ok in (("aj", aj, ("none", "c")), ("path", path, ("chained", "group")),
                            ("datapath", datapath, tuple(DATAPATHS)), ("pxp", pxp, FRAME_PXPS)):
            if v not in ok:
                raise RasterhwError(f"experts: sim experts {name} must be one of {', '.join(ok)}, not {v!r}")
        if datapath == "paper" and path != "chained":
            raise RasterhwError("experts: sim experts --datapath paper: experts-group has no 16-bit configuration; "
                                "leave --path at chained")
        if path == "group" and frame_pxp(pxp, path) != "span":
            raise RasterhwError("experts: sim experts --path group: experts-group's PXPs are span PXPs; "
                                "leave --pxp at default or give span")

    def golden(self, scene, width: int, height: int, *, engine: str, sn: int = 8, pn: int = 8, aj: str = "c",
               path: str = "chained", datapath: str = "ours", accuracy: bool = False, pxp: str = "default") -> dict:
        from rasterhw.golden_model.experts.formats import DATAPATHS, Formats
        from rasterhw.sim.experts.testbench import slp_words
        if not (1 <= sn <= height and 1 <= pn <= min(width, 63)):
            raise RasterhwError(f"experts: sn must be 1..{height} and pn 1..{min(width, 63)}")
        tris = run_geometry(scene, width, height, z_bits=16)
        fr = render_frame(tris, model="bit", aj=aj, fmt=Formats(datapath=DATAPATHS[datapath]))
        bands, bounds = equal_bounds(height, sn), equal_bounds(width, pn)
        # the list work's golden side first: it refuses a PL the SLP cannot hold before any HDL runs
        sws = [slp_words(fr, (int(bands[s]), int(bands[s + 1])), bounds, guard=1 if aj == "c" else 0)
               for s in range(sn)]
        gold = {"fr": fr, "bands": bands, "bounds": bounds, "sws": sws, "ex": DATAPATHS[datapath].acc_extra,
                "acc": _accuracy(tris, datapath, aj, accuracy or datapath == "paper", width=width, height=height,
                                 pxp=frame_pxp(pxp, path)),
                "datapath": datapath, "pxp": frame_pxp(pxp, path)}
        if path == "chained":
            from rasterhw.golden_model.experts.slp_setup import pl_words
            from rasterhw.sim.experts.testbench import setup_words
            gold["pls"] = pls = pl_words(fr.setup)
            gold["sus"] = [setup_words(pls, (int(bands[s]), int(bands[s + 1])), height, gold["ex"]) for s in range(sn)]
        return gold

    def jobs(self, gold: dict, *, engine: str, pn: int = 8, aj: str = "c", path: str = "chained", **_) -> list[Job]:
        from rasterhw.sim.experts.testbench import GroupBench, SlpSetupBench
        sws, fr = gold["sws"], gold["fr"]
        if path == "group":
            from rasterhw.golden_model.experts.pxp import pixel_words
            tb, b = GroupBench(), gold["bounds"]
            pix = pixel_words(fr.setup, fr.fields).reshape(fr.height, fr.width)
            p = tb.params(width=fr.width, pn=pn, aj=aj, tris=max(2, min(4095, max(sw["tris"] for sw in sws))),
                          lines=max(1, int(np.diff(gold["bands"]).max())), asl=256, depth=256)
            out = []
            for s, (y0, y1) in enumerate(zip(gold["bands"][:-1].tolist(), gold["bands"][1:].tolist(), strict=True)):
                want = {f"o[{k}]": pix[y0:y1, int(b[k]):int(b[k + 1])].ravel().tolist() for k in range(pn)}
                out.append(Job(tb, p, Stimulus({"i": sws[s]["in"]}), Expected(want),
                               {"max_cycles": 20 * sws[s]["cycles"] + 100000}, cycle_exact=False, name=f"band {s}"))
            return out
        if not gold["pls"]:       # an empty PL: no set-up work, nothing to run (each band word alone, 1 cycle)
            return []
        tb, sus = SlpSetupBench(), gold["sus"]
        cycles = sum(1 + su["cycles"] for su in sus)
        return [Job(tb, tb.params(height=fr.height, acc_extra=gold["ex"]), Stimulus({"i": [w for su in sus for w in su["in"]]}),
                    Expected({"o": [w for su in sus for w in su["out"]]}), {"max_cycles": 2 * cycles + 10000},
                    cycle_exact=False, name="SLP set-up")]

    def more(self, gold: dict, done: list[Done], *, engine: str, pn: int = 8, aj: str = "c", path: str = "chained",
             **_) -> list[Job]:
        names = [d.job.name for d in done]
        if path == "group" or "PXP" in names:
            return []
        if "SLP list work" not in names:       # the list work on the set-up HDL's words
            from rasterhw.sim.experts.testbench import SlpBench
            n_pl, nb, sws = len(gold["pls"]), 1 + len(gold["bounds"]), gold["sws"]
            have = done[0].got.words["o"] if n_pl else []
            ins = []
            for s, sw in enumerate(sws):
                hw = have[s * n_pl:(s + 1) * n_pl]
                ins += sw["in"][:nb] + list(hw) + sw["in"][nb + n_pl:] if len(hw) == n_pl else sw["in"]
            tb, fr = SlpBench(), gold["fr"]
            p = tb.params(width=fr.width, tris=max(2, min(4095, max(sw["tris"] for sw in sws))),
                          lines=max(1, int(np.diff(gold["bands"]).max())), asl=256, guard=1 if aj == "c" else 0,
                          acc_extra=gold["ex"])
            return [Job(tb, p, Stimulus({"i": ins}), Expected({"o": [w for sw in sws for w in sw["out"]]}),
                        {"max_cycles": 2 * sum(sw["cycles"] for sw in sws) + 10000}, cycle_exact=False,
                        name="SLP list work")]
        # the HDL SLP's lists -> every PXP's DMM/P words
        fr, bounds = gold["fr"], gold["bounds"]
        gold["dec"] = dec = decode_slp(done[-1].got.words["o"])
        lists: dict = {}
        line: dict = {"asl": [], "lead": {}, "bk": {}}
        for kind, q, pos, _t, y, a in dec:
            if kind == 0:
                line["asl"].append(a)
            elif kind == 1:
                line["lead"][q] = pos
            elif kind == 2:
                line["bk"].setdefault(q, []).append(pos)
            else:
                for r in range(pn):
                    lists[(y, int(bounds[r]), int(bounds[r + 1]))] = (line["asl"], line["lead"].get(r, -1),
                                                                      line["bk"].get(r, []))
                line = {"asl": [], "lead": {}, "bk": {}}
        if len(lists) != fr.height * pn:
            raise RasterhwError(f"experts: the SLP HDL gave lists for {len(lists) // max(pn, 1)} of {fr.height} lines")
        gold["jb"] = jb = jobs(fr, len(gold["bands"]) - 1, pn, pxp=gold["pxp"], slp=lists)
        if gold["datapath"] == "paper":      # the PXP's one multiplier and two-word z, i: its schedule
            from rasterhw.golden_model.experts.span_cycles import paper_jobs
            gold["jb"] = jb = paper_jobs(jb)
        return [pxp_job(jb, width=fr.width, engine=engine)]

    def result(self, gold: dict, done: list[Done], *, engine: str, sn: int = 8, pn: int = 8, aj: str = "c",
               path: str = "chained", **_) -> dict:
        head = {"sn": sn, "pn": pn, "aj": aj, **gold["acc"]}
        if path == "group":
            band = [int(d.got.cycles) for d in done]
            return {**head, "path": "group", "pxp": gold["pxp"], "pxp_block": "experts-group",
                    "pxp_is": PXP_IS[gold["pxp"]], "cycles": max(band), "cycle_mismatches": None,
                    "pixels_compared": sum(len(w) for d in done for w in d.job.expect.words.values()),
                    "group_cycles_per_band": band, "group_clock_for_30fps_hz": max(band) * 30,
                    "slp_cycles_alone": max(sw["cycles"] for sw in gold["sws"])}
        by = {d.job.name: d for d in done}
        su, slp, px = by.get("SLP set-up"), by["SLP list work"], by["PXP"]
        sus, sws, n_pl = gold["sus"], gold["sws"], len(gold["pls"])
        # set-up: every word on the edge band_setup's cycles put it, band after band
        su_stamps, t = [], 0
        for s in sus:
            su_stamps += [t + st for st in s["stamps"]]
            t += 1 + s["cycles"]
        su_got = list(su.got.stamps["o"]) if su else []
        if su and len(su_got) == sn * n_pl:    # each band's set-up cycles as the HDL took them
            last = [int(su_got[(s + 1) * n_pl - 1]) for s in range(sn)]
            setup_band = [last[0] + 1] + [last[s] - last[s - 1] for s in range(1, sn)]
        else:       # an empty PL, or a failed run (its mismatches say so): the cycle model's
            setup_band = [1 + s["cycles"] for s in sus]
        # list work: every end-of-line word on the golden cycle, band after band
        eol_want, t, band_end = [], 0, []
        for sw in sws:
            t += sw["start_cycles"]
            for c in sw["line_cycles"]:
                t += c
                eol_want.append(t - 1)
            band_end.append(len(eol_want) - 1)
        eol_got = [st for st, w in zip(slp.got.stamps["o"], gold["dec"], strict=False) if w[0] == 3]
        ends = [int(eol_got[k]) if k < len(eol_got) else 0 for k in band_end]
        list_band = [ends[0] + 1] + [ends[s] - ends[s - 1] for s in range(1, sn)]
        jb = gold["jb"]
        r = _pxp_checks(jb, px, True)
        # one SLP does its band's set-up, then its list work: its frame is the two, the busiest band's
        slp_band = [a + b for a, b in zip(setup_band, list_band, strict=True)]
        busiest = int(np.argmax(slp_band))
        slp_frame, pxp_frame = slp_band[busiest], int(jb["pxp_frame_cycles"].max())
        cyc = {"slp_cycle_mismatches": _mism(eol_want, eol_got), "pxp_cycle_mismatches": r["line_mismatches"],
               "slp_setup_cycle_mismatches": _mism(su_stamps, su_got)}
        return {**head, "cycles": max(slp_frame, pxp_frame),   # SLPs and PXPs side by side: the slower
                "pixels_compared": min(r["pixels"].size, jb["pixels"].size), "pixel_mismatches": r["pixel_mismatches"],
                "slp_word_mismatches": slp.cmp["mismatches"], "slp_words": len(slp.job.expect.words["o"]),
                "slp_setup_word_mismatches": su.cmp["mismatches"] if su else 0,
                "slp_setup_words": len(su.job.expect.words["o"]) if su else 0,
                "cycle_mismatches": sum(cyc.values()), **cyc,
                # the busiest SLP's band: set-up (experts-slp-setup) + list work (experts-slp), HDL cycles
                "slp_cycles": slp_frame, "slp_setup_cycles": int(setup_band[busiest]),
                "slp_list_cycles": int(list_band[busiest]), "slp_busiest_band": busiest,
                "slp_setup_cycles_per_band": [int(v) for v in setup_band],
                "slp_list_cycles_per_band": [int(v) for v in list_band], "pxp_cycles": pxp_frame,
                "slp_clock_for_30fps_hz": slp_frame * 30, "pxp_clock_for_30fps_hz": pxp_frame * 30,
                "bottleneck": "SLP" if slp_frame > pxp_frame else "PXP", "pxp": gold["pxp"],
                "pxp_block": f"experts-pxp-{gold['pxp']}", "pxp_is": PXP_IS[gold["pxp"]],
                "slp_run_s": round(slp.got.run_s, 3), "slp_setup_run_s": round(su.got.run_s, 3) if su else 0.0,
                "pxp_run_s": round(px.got.run_s, 3), "frame_rgb": hdl_image(gold["fr"], r["pixels"])}


simulate_frame = ExpertsScene().simulate
