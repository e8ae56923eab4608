"""ZB/M beyond one unit's Table 1, measured from HDL: output pixel rate against interleave
(sec. 5.3), condition 7's skew between neighbouring ZB/Ms (sec. 6.1) and chained units (sec. 6.1's
64 units, sec. 6.2's warning that a bus saturates first).

Every function runs HDL and returns what the simulator counted; ``report_rows`` turns them into
report rows whose ``source`` names the simulator that ran.

- **Pixel rate** (``pixel_rate``): "the output pixel rate is proportional to the interleave".
  One unit, a merge-bound frame (one small edge pair, then empty lines), pysim: the steady-state
  cycles per scan line from the unit's ``lines`` counter give pixels per segment clock.
- **Skew** (``skew``): condition 7, "half the time is waiting because of timing skew with the
  neighbouring ZB/M". Two chained units (each chip's neighbour on the merge chain is the same
  slot of the other unit), the paper's workload in both, the second unit's edge pairs offset by
  ``offset`` lines so their 9-cycle loads fall on different lines; Verilator. Measured: steady
  cycles per edge pair of the pair against one unit alone; the loss is what skew costs.
- **Chains** (``chain``): ``units`` chained units on one random scene (triangles dealt round
  robin), Verilator, every merge word checked against ``render_zbm``; throughput and the
  occupancy of the merge bus (words per merge clock on each slot's link).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import cycles as C
from rasterhw.golden_model.zbm.paper import PAPER_CLOCK_HZ
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import doublez_words

__all__ = ["pixel_rate", "skew", "chain", "report_rows", "report_tasks", "CHAIN_UNITS"]

CLOCK_HZ = PAPER_CLOCK_HZ  # condition 3
#: chains run on this machine (2 cores shared by 5 engineers, 24 GB): interleave 1, so 8 units are
#: 8 chip copies, one interleave-8 unit's build (~5 min cold under load); 16 units would double it
#: and 64 units (the paper's) would be 8x the largest build measured here
CHAIN_UNITS = (1, 2, 4, 8)


def pixel_rate(interleave: int, *, width: int = 128, height: int = 12,
               schedule: str = "overlap") -> dict:
    """Output pixels per segment clock of one unit whose lines are bound by the merge bus
    (pysim: the ``zbm-unit`` testbench on the generic engine, every merge word compared). One 5 x 5
    edge pair on lines 0-4, lines 5.. empty: per line a chip sends its ``ceil(width / interleave)``
    pixels down the merge bus, one per clock, all chips at once."""
    from rasterhw.sim.zbm.scene import run_units_equal_clocks

    eps = C.paper_workload(1, width=width)
    r = run_units_equal_clocks([eps], width=width, height=height, interleave=interleave, engine="pysim",
                               schedule=schedule, line_log=True)
    if r["overflow"] or not r["frames_ok"] or r["mismatches"]:
        raise RasterhwError(f"ZB/M unit did not finish the frame bit-exact: overflow {r['overflow']}, "
                            f"{r['mismatches']} merge words differ")
    t = r["line_cycles"]
    a, b = 6, height - 1                       # steady, empty lines
    per_line = (t[b] - t[a]) / (b - a)
    return {"interleave": interleave, "width": width, "cycles_per_line": per_line,
            "chip_pixels": -(-width // interleave), "pixels_per_cycle": width / per_line,
            "pixels_per_s": width / per_line * CLOCK_HZ, "engine": "pysim", "words_compared": r["words_compared"],
            "mismatches": r["mismatches"]}


def _offset_workload(n: int, width: int, offset: int) -> G.EdgePairs:
    eps = C.paper_workload(n, width=width)
    return G.EdgePairs(y=eps.y + offset, h=eps.h, x=eps.x, dxdy=eps.dxdy, len=eps.len, dlendy=eps.dlendy,
                       val=eps.val, ddy=eps.ddy, ddx=eps.ddx, tag=eps.tag, mode=eps.mode)


def skew(*, interleave: int = 1, offset: int = 2, n_edge_pairs: int = 4, schedule: str = "paper",
         engine: str = "verilator") -> dict:
    """Two neighbouring units (chained), the paper's workload in each, the second offset by
    ``offset`` lines; steady cycles per edge pair of each unit, beside one unit alone.

    Both runs use the same frame (``2 n`` pairs per unit, ``10 n + offset`` lines) and the bench's
    per-line log of the last unit's merge output over a window of ``5 n`` lines in the middle,
    where both units are busy: (t(line w0 + 5n - 1) - t(line w0 - 1)) / n, w0 = 5 (n // 2).
    """
    from rasterhw.sim.zbm.cycles_hdl import table1_width
    from rasterhw.sim.zbm.scene import run_units_equal_clocks

    n = n_edge_pairs
    width = table1_width(interleave)
    height = 10 * n + offset
    a = _offset_workload(2 * n, width, 0)
    b = _offset_workload(2 * n, width, offset)
    lo = 5 * (n // 2) - 1
    hi = lo + 5 * n
    res = {}
    for name, per_unit in (("alone", [a]), ("pair", [a, b])):
        r = run_units_equal_clocks(per_unit, width=width, height=height, interleave=interleave, engine=engine,
                                   schedule=schedule, line_log=True)
        gold = _chain_golden(per_unit, height, width, interleave)
        bad = int(((r["s0"] != gold[0]) | (r["s1"] != gold[1])).sum())
        if bad or r.get("timeout"):
            raise RasterhwError(f"ZB/M skew run ({name}): {bad} merge words differ / timeout")
        t = r["line_cycles"]
        res[name] = (t[hi] - t[lo]) / n
    return {"interleave": interleave, "offset": offset, "schedule": schedule, "engine": engine,
            "width": width, "height": height, "alone": res["alone"], "pair": res["pair"],
            "loss": 1 - res["alone"] / res["pair"], "paper_loss": 0.5}


def _chain_golden(eps_per_unit: list[G.EdgePairs], height: int, width: int, interleave: int):
    """Golden merge words of a chain (unit 0 = head) fed these edge pairs."""
    from rasterhw.golden_model.zbm.unit import unit_scanline

    acc = G.DoubleZ.empty((height, width))
    for eps in eps_per_unit:
        segs = G.segment_generator(eps, height, width=width)
        for y in range(height):
            own, _ = unit_scanline(segs, y, interleave, width)
            up = G.DoubleZ(acc.z[y], acc.a[y], acc.c[y], acc.tag[y])
            m = G.merge(up, own)
            acc.z[y], acc.a[y], acc.c[y], acc.tag[y] = m.z, m.a, m.c, m.tag
    s0, s1 = doublez_words(acc)
    return np.asarray(s0).reshape(height, width), np.asarray(s1).reshape(height, width)


def chain(units: int, *, interleave: int = 1, width: int = 64, height: int = 48, triangles: int = 96,
          seed: int = 3, schedule: str = "paper", engine: str = "verilator") -> dict:
    """``units`` chained units on ``triangles`` random triangles (dealt round robin), HDL vs
    ``render_zbm`` word for word. Returns cycles, polygons/s at 25 MHz, the merge-bus occupancy
    (merge words per clock on a slot's link: ``chip_pixels * height / cycles``) and the merge
    bound ``height * (chip_pixels + 2)`` (the bus alone, measured per line by ``pixel_rate``)."""
    from rasterhw.sim.zbm.scene import run_units_equal_clocks

    if not (isinstance(units, int) and 1 <= units <= 16):
        raise RasterhwError(f"units must be 1..16, not {units!r}")
    tris = random_triangles(np.random.default_rng(seed), triangles, width, height, size=10)
    eps = G.edge_pairs(tris)
    gold = G.render_zbm(tris, interleave=interleave, units=units)
    g0, g1 = doublez_words(gold.pixels)
    per_unit = [eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)]
    r = run_units_equal_clocks(per_unit, width=width, height=height, interleave=interleave, engine=engine, schedule=schedule)
    if r.get("timeout"):
        raise RasterhwError("ZB/M chain: the bench's watchdog fired")
    bad = int(((r["s0"] != np.asarray(g0).reshape(height, width)) |
               (r["s1"] != np.asarray(g1).reshape(height, width))).sum())
    npx = -(-width // interleave)
    cyc = int(r["cycles"])
    return {"units": units, "interleave": interleave, "width": width, "height": height,
            "triangles": triangles, "edge_pairs": len(eps), "schedule": schedule, "engine": engine,
            "cycles": cyc, "mismatches": bad, "polygons_per_s": triangles * CLOCK_HZ / cyc,
            "merge_occupancy": npx * height / cyc, "merge_bound_cycles": height * (npx + 2),
            "build_s": r["build_s"], "run_s": r["run_s"]}


#: interleaves whose pixel-rate run a fast report (``rasterhw report zbm --fast``, the
#: committed-report test) leaves unmeasured: building the pysim model of an 8- or 16-chip unit
#: takes 15-35 s on this machine, most of that test's time. ``make slow`` measures them
#: (tests/zbm/test_zbm_unit_pysim.py::test_pixel_rate_scales_with_interleave), as does a full report.
FAST_SKIP_PIXEL_RATE = (8, 16)
PIXEL_RATE_WIDTH = 128
#: chains a fast run leaves unmeasured: the 4- and 8-unit chains are the two largest Verilator
#: builds of the report (minutes each, cold); a full report measures them. The 1- and 2-unit
#: chains stay, so a fast run still checks chained units word for word against the golden model.
FAST_SKIP_CHAIN = (4, 8)


_SELF = "rasterhw.sim.zbm.scaling"


def _skipped(what: str, value: int, *, fast: bool, rows_only: bool) -> str | None:
    """Why the run ``what`` (``"pixel_rate"`` at interleave ``value``, ``"skew"``, ``"chain"`` of
    ``value`` units) is left out of this report, or ``None`` when it runs."""
    from rasterhw.sim.report.rows import ROWS_ONLY

    if rows_only:
        return ROWS_ONLY
    if fast and what == "pixel_rate" and value in FAST_SKIP_PIXEL_RATE:
        return (f"slow row: not measured in a fast run (the pysim model of a {value}-chip unit takes "
                "15-35 s to build; rasterhw report zbm without --fast measures it; cycles/line in the label: "
                f"the model's ceil({PIXEL_RATE_WIDTH} / {value}) + 2)")
    if fast and what == "chain" and value in FAST_SKIP_CHAIN:
        return (f"slow row: not measured in a fast run (a chain of {value} units is one of the report's two "
                "largest Verilator builds, minutes cold); rasterhw report zbm without --fast measures it")
    return None


def report_tasks(*, engine: str = "verilator", fast: bool = False, rows_only: bool = False) -> list:
    """The runs of :func:`report_rows`, as tasks (``sim/flow/tasks.py``), in the rows' order: the
    pixel rate at each interleave a ``fast`` run measures, the skew pair, then every chain
    (``rows_only``: none)."""
    from rasterhw.sim.flow.tasks import call

    def runs(what, value):
        return not _skipped(what, value, fast=fast, rows_only=rows_only)

    tasks = [call(f"{_SELF}:pixel_rate", interleave=i, width=PIXEL_RATE_WIDTH)
             for i in C.INTERLEAVES if runs("pixel_rate", i)]
    tasks += [call(f"{_SELF}:skew", engine=engine)] if runs("skew", 0) else []
    tasks += [call(f"{_SELF}:chain", units=u, engine=engine) for u in CHAIN_UNITS if runs("chain", u)]
    return tasks


def report_rows(*, progress: bool = False, engine: str = "verilator", fast: bool = False, rows_only: bool = False,
                scheduler: str = "serial", store=None, fresh: bool = False, results: list | None = None) -> list[dict]:
    """The rows of pixel rate, skew and chains. Their runs (:func:`report_tasks`) go to
    ``scheduler`` (``run_tasks``: in this process by default), unless ``results`` holds them
    already (the ZB/M report runs them with its Table 1 runs, on one cluster)."""
    if results is None:
        from rasterhw.sim.flow.tasks import run_tasks

        results = run_tasks(report_tasks(engine=engine, fast=fast, rows_only=rows_only), scheduler=scheduler,
                            store=store, fresh=fresh, progress=progress,
                            desc=f"ZB/M pixel rate, skew, chains ({engine})")
    return _rows(list(results), engine=engine, fast=fast, rows_only=rows_only)


def _defaults(fn) -> dict:
    from inspect import signature

    return {k: v.default for k, v in signature(fn).parameters.items()}


def _rows(results: list[dict], *, engine: str, fast: bool, rows_only: bool = False) -> list[dict]:
    """Rows from the runs' ``results`` in :func:`report_tasks`' order; a run left out gives its rows
    unmeasured with the reason, their labels from the run's defaults and the cycle model."""
    from rasterhw.sim.report.rows import make_row

    def result(what, value):
        why = _skipped(what, value, fast=fast, rows_only=rows_only)
        return (None, why) if why else (results.pop(0), None)

    out = []
    base = None
    for i in C.INTERLEAVES:
        p, why = result("pixel_rate", i)
        cycles_per_line = -(-PIXEL_RATE_WIDTH // i) + 2 if p is None else p["cycles_per_line"]
        rate = None if p is None else p["pixels_per_cycle"]
        base = base or rate
        out.append(make_row("zbm", "5.3", f"output pixels per segment clock, interleave {i} (one unit, "
                            f"{PIXEL_RATE_WIDTH}-px merge-bound lines; {cycles_per_line:.0f} cycles/line)",
                            paper=None, formula=float(i), measured=rate, unit="px/cycle",
                            source="hdl:pysim", reason=why, run=why is None))
        out.append(make_row("zbm", "5.3", f"output pixel rate / interleave-1 rate, interleave {i}",
                            paper=None, formula=float(i), measured=None if p is None else rate / base, unit="x",
                            source="hdl:pysim", reason=why, run=why is None))
    s, why = result("skew", 0)
    if s is None:   # the label from skew()'s defaults; "alone": the paper schedule's cycle model
        d = _defaults(skew)
        s = {"offset": d["offset"], "interleave": d["interleave"],
             "alone": float(C.formula_cycles_per_edge_pair(d["interleave"])), "pair": None, "loss": None}
    out.append(make_row("zbm", "6.1 cond. 7", f"cycles per edge pair, 2 neighbouring units, loads "
                        f"{s['offset']} lines apart (interleave {s['interleave']}, paper schedule; alone "
                        f"{s['alone']:.1f}; formula: 2 x the paper's cycles per edge pair, derived)", paper=None,
                        formula=2 * C.formula_cycles_per_edge_pair(s["interleave"]), measured=s["pair"],
                        unit="cycles", source=f"hdl:{engine}", reason=why, run=why is None))
    out.append(make_row("zbm", "6.1 cond. 7", "fraction of time lost to skew with the neighbour",
                        paper=0.5, formula=None, measured=s["loss"], unit="", source=f"hdl:{engine}", reason=why, run=why is None))
    one = None
    for u in CHAIN_UNITS:
        c, why = result("chain", u)
        if c is None:   # the label from chain()'s defaults; the bus-bound frame as chain() computes it
            d = _defaults(chain)
            c = {**d, "merge_bound_cycles": d["height"] * (-(-d["width"] // d["interleave"]) + 2),
                 "polygons_per_s": None, "merge_occupancy": None}
        elif c["mismatches"]:
            raise RasterhwError(f"ZB/M chain of {u}: {c['mismatches']} merge words differ")
        one = one or c["polygons_per_s"]
        tag = (f"{u} chained unit{'s' if u > 1 else ''}, interleave {c['interleave']}, {c['triangles']} triangles on "
               f"{c['width']}x{c['height']}")
        out.append(make_row("zbm", "6.1 (chain)", f"{tag}: speed-up over 1 unit", paper=None, formula=float(u),
                            measured=None if why else c["polygons_per_s"] / one, unit="x",
                            source=f"hdl:{engine}", reason=why, run=why is None))
        # the run's cycles are not in the label (a row's name must not change with its value)
        out.append(make_row("zbm", "6.1 (chain)", f"{tag}: merge-bus occupancy (words per clock per slot; "
                            f"bus-bound frame {c['merge_bound_cycles']} cycles)",
                            paper=None, formula=None, measured=c["merge_occupancy"], unit="",
                            source=f"hdl:{engine}", reason=why, run=why is None))
    return out
