"""``rasterhw sim zbm``'s scene level (``sim/engines/scene.py``): a scene through ZB/M units in HDL (pysim,
plain Verilator or the cocotb bench), every double-Z pixel compared with the golden model and the
composited frame checked against the float model under docs/zbm.md's tolerance; :func:`run_scene`,
a chain of units on edge pairs, for the soak, the bench and the reports."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.cycles import check_schedule
from rasterhw.golden_model.zbm.words import words_to_doublez
from rasterhw.sim import engines
from rasterhw.sim.engines.scene import Job, SceneRun, run_job
from rasterhw.sim.testbench import Expected, find_testbench
from rasterhw.sim.zbm.edge_check import check_edge_pairs
from rasterhw.sim.zbm.testbench import deal, unit_watchdog

__all__ = ["CYCLE_MODEL", "PLAIN_BUILD", "SPEED_BUILD", "ZbmScene", "float_reference", "float_tolerance",
           "line_cycle_check", "run_scene", "run_units_equal_clocks", "scene_golden", "simulate",
           "unit_job"]


# ====================================================================== float tolerance
def float_reference(tris, gtag0: np.ndarray, segs=None) -> dict:
    """What :func:`float_tolerance` takes from the golden models, computed without the HDL:
    ``render_zbm_float``'s coverage (``cov``), nearest sample's Z in LSBs (``zf``, rounded and
    clamped), colour in LSBs (``frgb``) and whether its nearest triangle is the bit-accurate frame's
    (``same_tag``: ``gtag0``, that frame's nearest tags), and ``gtag0`` itself (int32). ``segs``:
    the edge pairs' segments, when the caller has them (one unit)."""
    fl = G.render_zbm_float(tris, segs=segs)
    cov = np.isfinite(fl["z"][..., 0])
    zf = np.clip(np.floor(np.where(cov, fl["z"][..., 0], 0) * G.Z_SCALE + 0.5), 0, F.Z_MAX_SAMPLE)
    return {"cov": cov, "zf": zf.astype(np.int32), "frgb": np.floor(fl["rgb"] * 255 + 0.5).astype(np.uint8),
            "same_tag": np.asarray(gtag0) == fl["tag"][..., 0], "gtag0": np.asarray(gtag0, np.int32)}


def float_tolerance(ref: dict, px: G.DoubleZ, rgb8: np.ndarray, eps: G.EdgePairs) -> dict:
    """Compare the composited HDL frame with ``render_zbm_float`` (``ref``: :func:`float_reference`)
    under docs/zbm.md's stated tolerance: coverage identical; nearest triangle identical (pixels with
    a different nearest triangle -- Z ties -- are counted and left out of the value checks); Z within
    ``1 + |dz/dx| * 2**-16`` LSB; opaque colour within 1 LSB (2 where the front sample is
    translucent)."""
    cov_h = px.z[..., 0] != F.Z_EMPTY
    cov_f = ref["cov"]
    tags0 = ref["gtag0"]
    same = cov_h & cov_f & ref["same_tag"]
    dz = np.abs(px.z[..., 0] - ref["zf"])
    # one slot per triangle tag (visible or not) plus a spare zero at index -1 for pixels
    # whose front sample is not the float model's
    dzdx = np.zeros(max(int(tags0.max(initial=-1)), int(eps.tag.max(initial=-1))) + 2)
    if len(eps):
        np.maximum.at(dzdx, eps.tag, np.abs(eps.ddx[:, 0]) / float(1 << F.ATTR_FRAC))
    zbound = 1 + dzdx[np.where(same, tags0, -1)] * 2.0 ** -16
    drgb = np.abs(rgb8.astype(np.int16) - ref["frgb"]).max(axis=-1)
    opaque = px.a[..., 0] == 255
    rbound = np.where(opaque, 1, 2)
    z_over = int(np.count_nonzero(same & (dz > zbound)))
    rgb_over = int(np.count_nonzero(same & (drgb > rbound)))
    cov_diff = int(np.count_nonzero(cov_h != cov_f))
    return {
        "stated": "coverage equal; nearest triangle equal (Z ties excepted); Z within 1 + |dz/dx|*2^-16 LSB; "
                  "RGB within 1 LSB (2 if translucent)",
        "coverage_mismatches": cov_diff,
        "nearest_mismatches": int(np.count_nonzero(cov_h & cov_f & ~same)),
        "pixels_compared": int(same.sum()),
        "z_max_diff_lsb": float(dz[same].max(initial=0)),
        "z_over_bound": z_over,
        "rgb_max_diff": int(drgb[same].max(initial=0)),
        "rgb_over_bound": rgb_over,
        "ok": cov_diff == 0 and z_over == 0 and rgb_over == 0,
    }


# ====================================================================== the driver
#: the build of ``sim zbm --engine verilator`` (and the soak, the bench's "after" row): the unit
#: testbench's speed Verilog (identical modules merged, the pixel processor out of line); with a
#: cached gcc profile of the design g++ -O2 and profile-guided optimisation, else -O1
#: (``RASTERHW_PGO=1`` or ``rasterhw bench`` trains the profile; ``RASTERHW_PGO=0`` never uses one)
SPEED_BUILD = {"speed": True, "pgo": "auto"}
#: the build before issue 31 (the bench's "before" row): one module per instance, g++ -O1
PLAIN_BUILD = {"speed": False, "opt": "-O1", "pgo": False}


def unit_job(eps_per_unit: list, *, width: int, height: int, interleave: int, schedule: str = "overlap",
             capacity: int = F.AEP_CAPACITY, engine: str = "verilator", stall: int = 0, seed: int = 1,
             gap_seed: int | None = None, build: dict | None = None, clocks: dict | None = None,
             segments: list | None = None, expect: Expected | None = None) -> Job:
    """Edge pairs through ``len(eps_per_unit)`` chained ZB/M units (unit ``k`` gets
    ``eps_per_unit[k]``; a scene's: ``testbench.deal``) as one job of the ``zbm-unit`` testbench
    (:class:`rasterhw.sim.zbm.testbench.UnitBench`; its expected words come from ``chain_frame``, the
    one golden route). ``build``: Verilator build settings (default :data:`SPEED_BUILD`);
    ``stall``, ``seed``: back-pressure on every merge slot; ``gap_seed``: random idle gaps on the
    edge-pair input (None: none); ``clocks``: separate segment and merge clocks (``{"sync": Clock,
    "merge": Clock}``, e.g. the cocotb bench's at a ratio: ``testbench.bench_clocks``; one build for
    every ratio; cycles stay in segment clocks); None: one clock for both. ``segments``: each unit's
    segments, when the caller has them (``chain_frame``); ``expect``: the expected words, when the
    caller has them (``rasterhw sim zbm``: from the build cache, :func:`scene_golden`)."""
    tb = find_testbench("zbm-unit")
    p = tb.params(interleave=interleave, width=width, height=height, capacity=capacity, schedule=schedule,
                  units=len(eps_per_unit))
    stim = tb.scene_stimulus(p, eps_per_unit, gap_seed=gap_seed)
    cap = unit_watchdog(sum(map(len, stim.words.values())), width=width, height=height, stall=stall,
                        ratio=(clocks["sync"].half, clocks["merge"].half) if clocks else (5, 5))
    run = {"stall": stall, "seed": seed, "max_cycles": cap, "clocks": clocks, "packed": True,
           "build": (SPEED_BUILD if build is None else build) if engine == "verilator" else None}
    return Job(tb, p, stim, tb.expect(p, stim, segments) if expect is None else expect, run, cycle_exact=False)


def run_scene(eps_per_unit: list, *, engine: str = "verilator", line_log: bool = False, **kw) -> dict:
    """:func:`unit_job` (its keywords) run on ``engine``: ``{"s0", "s1": (H, W) uint64 frame, "cycles"
    (segment clocks until the last merge word), "proto_errors", "run_s" (the clock loop on Verilator;
    the simulation on pysim), "build_s", "build", "words_compared" (merge words of the frame),
    "mismatches" (those that differ from the testbench's golden words: ``testbench.compare``), "golden"
    (the golden double-Z frame they were made from), "frames_ok", "overflow", ["line_cycles"]}``."""
    job = unit_job(eps_per_unit, engine=engine, **kw)
    d = run_job(job, engine)
    got = d.got
    s0, s1 = job.tb.frame(job.params, got.words)
    out = {"s0": s0, "s1": s1, "cycles": got.cycles, "proto_errors": got.protocol_errors, "run_s": got.run_s,
           "build_s": got.build_s, "build": got.build, "words_compared": sum(map(len, job.expect.words.values())),
           "mismatches": d.cmp["mismatches"], "golden": job.expect.golden, **got.status}
    if line_log:
        out["line_cycles"] = job.tb.line_cycles(job.params, got)
    return out


def run_units_equal_clocks(per_unit: list, *, width: int, height: int, interleave: int, engine: str,
                           schedule: str, line_log: bool = False) -> dict:
    """A chain of units with equal, in-phase clocks (the Table 1, pixel-rate, skew and chain runs) on
    the generic engine (:func:`run_scene`): pysim, Verilator (g++ ``-O0``: these frames are small, the
    build is what costs; held word-, cycle- and line-log-exact with the cocotb bench by
    ``tests/zbm/test_zbm_unit_engine.py``), or ``icarus`` (the same testbench under cocotb on Icarus)."""
    if engine == "verilator":
        return run_scene(per_unit, width=width, height=height, interleave=interleave, schedule=schedule,
                         line_log=line_log, build={"speed": True, "opt": "-O0"})
    return run_scene(per_unit, width=width, height=height, interleave=interleave, schedule=schedule,
                     line_log=line_log, engine=engines.ALIASES.get(engine, engine))


# ====================================================================== the golden cycle model, per line
#: what ``cycle_mismatches`` of ``rasterhw sim zbm`` compares (``extra.cycle_model``)
CYCLE_MODEL = ("golden_model/zbm/cycles.py: hdl_cycles, per line: the segment clock after the last merge "
               "word of line y left every chip slot")
#: why a chain of units compares no cycles (``extra.cycle_model``)
NO_CHAIN_MODEL = ("none: hdl_cycles models one unit; a chain's line timing also waits on the upstream "
                  "unit's merge words (its words are compared, its cycles are not)")


def line_cycle_check(model, hdl) -> dict:
    """The HDL's per-line log (``UnitBench.line_cycles``) against the exact cycle model's
    (``hdl_cycles(...)["line_cycles"]``: the segment clock, per line, after the last merge word of that line
    left every chip slot of one unit, words back to back, outputs ready, one clock: a scene run's
    conditions; :func:`scene_golden`; None: no model, a chain): ``cycle_mismatches`` (lines whose cycle differs, a line the HDL never
    finished counted too; None without a model), ``lines_compared``, ``cycles_golden`` (the model's
    last line: the frame's cycles) and ``cycle_model`` (what was compared)."""
    if model is None:
        return {"cycle_mismatches": None, "lines_compared": 0, "cycles_golden": None, "cycle_model": NO_CHAIN_MODEL}
    model, hdl = np.asarray(model, np.int64), np.asarray(hdl, np.int64)
    n = min(len(model), len(hdl))
    bad = int(np.count_nonzero(model[:n] != hdl[:n])) + abs(len(model) - len(hdl))
    return {"cycle_mismatches": bad, "lines_compared": len(model),
            "cycles_golden": int(model[-1]) if len(model) else 0, "cycle_model": CYCLE_MODEL}


def scene_golden(tris, eps, *, width: int, height: int, interleave: int, units: int, schedule: str) -> dict:
    """Everything ``rasterhw sim zbm`` compares the HDL with, from the golden models alone, kept in the
    build cache (``verilog_cache.arrays_cached``: ``build/verilog/zbm-scene-<digest>.npz``, SHA-256
    checked, keyed by the triangles, the parameters and the digest of this module and every module of
    ours it imports, transitively: an edit to a golden model computes it again): ``rows`` (every chip
    slot's expected merge words, packed rows, slot after slot; ``counts``: words per slot), the
    ``zbm-unit`` testbench's ``expect`` (``chain_frame``: the one golden route); :func:`float_reference`'s
    arrays (the float twin); and, for one unit, ``lines`` (``hdl_cycles(...)["line_cycles"]``, what :func:`line_cycle_check` compares). A warm run
    so neither renders the bit-accurate nor the float frame nor walks the cycle model (c300, I = 8:
    ~0.15 CPU-s of golden models and 1.1 CPU-s of the cycle model)."""
    from pathlib import Path

    from rasterhw.golden_model.zbm import cycles as C
    from rasterhw.sim.engines.verilog_cache import arrays_cached, fields_key

    def compute() -> dict:
        tb = find_testbench("zbm-unit")
        p = tb.params(interleave=interleave, width=width, height=height, units=units)
        # one unit: its segments are the float twin's too (the same generator on the same edge pairs)
        segs = G.segment_generator(eps, height, width=width) if units == 1 else None
        stim = tb.scene_stimulus(p, deal(eps, units))
        exp = tb.expect(p, stim, None if segs is None else [segs])
        rows = [exp.words[o] for o in tb.outputs_of(p)]
        out = {"rows": np.concatenate(rows), "counts": np.array([len(r) for r in rows], np.int64),
               **float_reference(tris, exp.golden.tag[..., 0], segs)}
        if units == 1:
            out["lines"] = C.hdl_cycles(eps, height, width=width, interleave=interleave,
                                        schedule=schedule)["line_cycles"]
        return out

    key = fields_key(tris) + [width, height, interleave, units, schedule]
    return arrays_cached("zbm-scene", Path(__file__), key, compute)


class ZbmScene(SceneRun):
    """``rasterhw sim zbm``: ``run_geometry`` -> ``edge_pairs`` -> checks (:func:`check_edge_pairs`: bad
    or over-capacity streams raise ``RasterhwError`` before any simulation) -> triangles dealt to
    units round-robin (triangle i -> unit i % units, as ``render_zbm``) -> HDL -> every merge word
    compared with the ``zbm-unit`` testbench's golden frame (``chain_frame``) -> composite -> the
    float tolerance. ``schedule``: ``"overlap"`` (ours) or ``"paper"`` (sec. 6.1's; the image is the
    same, only the timing differs). ``cycles``: segment clocks until the last merge word left the
    chain; ``mismatches``: merge words (pixels' 128-bit double-Z words) that differ;
    ``cycle_mismatches``: lines whose cycle in the HDL's per-line log (``UnitBench.line_cycles``) differs
    from the exact cycle model's (:func:`line_cycle_check`; one unit: a chain has no cycle model, None);
    extra: ``lines_compared``, ``cycles_golden``, ``cycle_model``,
    ``edge_pairs``, ``aep_peak``, ``triangles``, ``polygons_per_s`` (triangles x 25 MHz / cycles),
    ``float_tolerance``."""

    block = "zbm"
    steps = ("geometry + edge pairs + golden model", "HDL simulation", "composite + float tolerance")

    def check(self, engine: str, interleave: int = 8, units: int = 1, schedule: str = "overlap") -> None:
        F.check_interleave(interleave)
        check_schedule(schedule)
        if not isinstance(units, (int, np.integer)) or isinstance(units, bool) or not 1 <= units <= 16:
            raise RasterhwError(f"units must be an integer in 1..16, not {units!r}")

    def golden(self, scene, width: int, height: int, *, engine: str, interleave: int = 8, units: int = 1,
               schedule: str = "overlap") -> dict:
        for name, v, lo in (("width", width, interleave), ("height", height, 1)):
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not lo <= v <= 512:
                raise RasterhwError(f"ZB/M: {name} must be an integer in {lo}..512, not {v!r}")
        tris = run_geometry(scene, width, height)
        eps = G.edge_pairs(tris)
        peak = check_edge_pairs(eps, width, height, units=units)
        g = scene_golden(tris, eps, width=width, height=height, interleave=interleave, units=units, schedule=schedule)
        return {"tris": tris, "eps": eps, "peak": peak, "width": width, "height": height, **g}

    def jobs(self, gold: dict, *, engine: str, interleave: int = 8, units: int = 1, schedule: str = "overlap"):
        # icarus: the unit's testbench under cocotb on Icarus (the generic cocotb engine). On Verilator
        # the profiled build, trained with the first build (said on stderr; RASTERHW_PGO=0 skips it)
        engine = engines.ALIASES.get(engine, engine)
        tb = find_testbench("zbm-unit")
        outs = tb.outputs_of(tb.params(interleave=interleave, width=gold["width"], height=gold["height"], units=units))
        at = np.cumsum(np.concatenate([[0], gold["counts"]]))
        expect = Expected({o: gold["rows"][at[k]:at[k + 1]] for k, o in enumerate(outs)})
        return [unit_job(deal(gold["eps"], units), width=gold["width"], height=gold["height"], interleave=interleave,
                         schedule=schedule, engine=engine, expect=expect,
                         build={**SPEED_BUILD, "pgo": "train"} if engine == "verilator" else None)]

    def result(self, gold: dict, done: list, *, engine: str, interleave: int = 8, units: int = 1,
               schedule: str = "overlap") -> dict:
        (d,) = done
        px = words_to_doublez(*d.job.tb.frame(d.job.params, d.got.words))
        rgb8 = G.composite(px)
        cycles, n_tri = d.got.cycles, int(np.asarray(gold["tris"].xy).shape[0])
        clock = self.clock_hz(done)
        return {"interleave": interleave, "units": units, "schedule": schedule, "width": gold["width"],
                "height": gold["height"], "pixels_compared": gold["width"] * gold["height"],
                **line_cycle_check(gold.get("lines"), d.job.tb.line_cycles(d.job.params, d.got)),
                "edge_pairs": len(gold["eps"]), "aep_peak": gold["peak"], "triangles": n_tri,
                "polygons_per_s": n_tri * clock / cycles if cycles else float("inf"), "frame_rgb": rgb8,
                "float_tolerance": float_tolerance(gold, px, rgb8, gold["eps"])}


simulate = ZbmScene().simulate
