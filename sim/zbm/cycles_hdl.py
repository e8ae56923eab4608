"""Cycle counts of one ZB/M unit (``hdl/zbm/unit.py``) from HDL simulation, beside the exact
cycle model ``golden_model.zbm.cycles.hdl_cycles`` and the paper's Table 1 formula.

``measure_cycles_per_edge_pair(interleave)`` runs the paper's workload (sec. 6.1 cond. 1-2:
edge pairs of 5 lines x 5 pixels, one segment per line, ``zbm.cycles.paper_workload``) through
one head unit in Amaranth pysim. The frame is ``table1_width(interleave)`` pixels wide so each
chip's merge-bus readout of a line (``chip_pixels + 2`` cycles) is shorter than its loop work
and the count is the segment side's, as in the paper's estimate.
"""

from __future__ import annotations

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import EdgePairs
from rasterhw.golden_model.zbm import cycles as C
from rasterhw.golden_model.zbm.formats import AEP_CAPACITY, INTERLEAVES, check_interleave
from rasterhw.sim.engines.harness import stream_put

__all__ = ["run_unit_cycles", "measure_cycles_per_edge_pair", "table1_width", "measure_table1",
           "unit_golden_words"]


def table1_width(interleave: int) -> int:
    """Frame width for the Table 1 workload: 4 pixels per chip (8 at least, a 5-pixel segment
    must fit)."""
    return max(4 * interleave, 8)


def run_unit_cycles(eps: EdgePairs, height: int, *, width: int, interleave: int,
                    capacity: int = AEP_CAPACITY, schedule: str = "overlap",
                    max_cycles: int = 200_000) -> dict:
    """Run one head ``ZbmUnit`` in pysim: edge-pair words offered one per cycle from cycle 0,
    merge outputs always ready, merge clock = segment clock (the assumptions of
    ``zbm.cycles.hdl_cycles``). Returns ``cycles`` = value of ``ZbmUnit.cycles`` in the first
    cycle with ``ZbmUnit.lines == height`` (every chip has finished the frame), ``overflow``
    and ``line_cycles`` (``line_cycles[k]`` = ``ZbmUnit.cycles`` in the first cycle with
    ``ZbmUnit.lines == k + 1``)."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.zbm.unit import ZbmUnit

    words = [w for i in range(len(eps)) for w in eps.words(i)] + [0]   # h == 0: end of frame
    unit = ZbmUnit(interleave=interleave, width=width, height=height, capacity=capacity, head=True,
                   schedule=schedule)
    sim = Simulator(unit)
    sim.add_clock(1e-8, domain="sync")
    sim.add_clock(1e-8, domain="merge")
    out = {}

    async def src(ctx):
        for w in words:
            await stream_put(ctx, unit.i, w)

    async def bench(ctx):
        for c in range(interleave):
            ctx.set(unit.o_merge[c].ready, 1)
        marks = []
        for _ in range(max_cycles):
            _, _, lines, cyc, ovf = await ctx.tick().sample(unit.lines, unit.cycles, unit.overflow)
            while len(marks) < lines:
                marks.append(int(cyc))
            if lines == height or ovf:
                break
        out.update(cycles=cyc, lines=lines, overflow=ovf, line_cycles=marks)

    sim.add_testbench(src, background=True)
    sim.add_testbench(bench)
    sim.run()
    return out


def measure_cycles_per_edge_pair(interleave: int, *, n_edge_pairs: int = 8,
                                 engine: str = "pysim", schedule: str = "overlap") -> dict:
    """Cycles per edge pair of one unit on the paper's workload, from HDL simulation.

    Returns ``cycles`` (HDL, whole frame: first word offered .. every chip done), ``edge_pairs``,
    ``cycles_per_edge_pair`` (= cycles / edge_pairs, so it includes pipeline fill and drain),
    ``model_cycles`` (``zbm.cycles.hdl_cycles``, must equal ``cycles``), ``marginal_cycles_per_edge_pair``
    (model: cycles(n + 1) - cycles(n), the steady state) and ``paper_formula`` (74, 64, 59,
    54, 54: the paper's Table 1 estimate, not a measurement)."""
    check_interleave(interleave)
    if engine != "pysim":
        raise ValueError(f"engine must be 'pysim' (the only one wired here), not {engine!r}")
    if not (isinstance(n_edge_pairs, int) and 1 <= n_edge_pairs <= 100):
        raise ValueError(f"n_edge_pairs must be 1..100, not {n_edge_pairs!r}")
    width = table1_width(interleave)
    eps = C.paper_workload(n_edge_pairs, width=width)
    height = 5 * n_edge_pairs
    model = C.hdl_cycles(eps, height, width=width, interleave=interleave, schedule=schedule)
    more = C.hdl_cycles(C.paper_workload(n_edge_pairs + 1, width=width), height + 5, width=width,
                        interleave=interleave, schedule=schedule)
    hdl = run_unit_cycles(eps, height, width=width, interleave=interleave, schedule=schedule)
    if hdl["overflow"] or hdl["lines"] != height:
        raise RasterhwError(f"ZB/M unit did not finish the frame: {hdl}")
    return {"interleave": interleave, "cycles": int(hdl["cycles"]), "edge_pairs": n_edge_pairs,
            "cycles_per_edge_pair": hdl["cycles"] / n_edge_pairs, "model_cycles": model["cycles"],
            "marginal_cycles_per_edge_pair": more["cycles"] - model["cycles"],
            "paper_formula": C.formula_cycles_per_edge_pair(interleave), "width": width,
            "height": height, "schedule": schedule}


if __name__ == "__main__":
    for i in INTERLEAVES:
        print(measure_cycles_per_edge_pair(i))


def unit_golden_words(eps: EdgePairs, height: int, *, width: int, interleave: int):
    """Golden (s0, s1) (height, width) merge words of one head unit on ``eps``."""
    import numpy as np
    from rasterhw.golden_model import zbm as G
    from rasterhw.golden_model.zbm.unit import unit_scanline
    from rasterhw.golden_model.zbm.words import doublez_words

    segs = G.segment_generator(eps, height, width=width)
    px = G.DoubleZ.empty((height, width))
    for y in range(height):
        line, _ = unit_scanline(segs, y, interleave, width)
        px.z[y], px.a[y], px.c[y], px.tag[y] = line.z, line.a, line.c, line.tag
    s0, s1 = doublez_words(px)
    return np.asarray(s0).reshape(height, width), np.asarray(s1).reshape(height, width)


def measure_table1(interleave: int, *, schedule: str = "overlap", engine: str = "pysim",
                   n_edge_pairs: int = 4) -> dict:
    """Steady-state cycles per edge pair of one unit on the paper's workload, from ONE HDL run.

    The unit runs ``2 n`` paper edge pairs (``10 n`` lines, one segment per line); the cycle at
    which line ``5 n`` and line ``10 n`` are finished is read from the simulation (pysim:
    ``ZbmUnit.lines`` reaching the count; Verilator / Icarus: the bench's per-line log of the
    cycle in which the last chip slot's merge output finished that line), and
    ``(t(10 n) - t(5 n)) / n`` is the steady state: fill and drain cancel. Also returns the exact
    model's marginal ``hdl_cycles(k + 1) - hdl_cycles(k)`` and, on Verilator / Icarus, the
    number of merge words that differ from the golden model (must be 0).
    """
    check_interleave(interleave)
    C.check_schedule(schedule)
    n = n_edge_pairs
    width = table1_width(interleave)
    eps = C.paper_workload(2 * n, width=width)
    height = 10 * n
    m1 = C.hdl_cycles(C.paper_workload(n, width=width), 5 * n, width=width, interleave=interleave,
                      schedule=schedule)["cycles"]
    m2 = C.hdl_cycles(C.paper_workload(n + 1, width=width), 5 * n + 5, width=width, interleave=interleave,
                      schedule=schedule)["cycles"]
    out = {"interleave": interleave, "schedule": schedule, "engine": engine, "width": width,
           "height": height, "edge_pairs": 2 * n, "model_marginal": m2 - m1,
           "paper_formula": C.formula_cycles_per_edge_pair(interleave)}
    if engine == "pysim":
        r = run_unit_cycles(eps, height, width=width, interleave=interleave, schedule=schedule)
        if r["overflow"] or r["lines"] != height:
            raise RasterhwError(f"ZB/M unit did not finish the frame: {r}")
        marks, mism = r["line_cycles"], None
    else:
        g0, g1 = unit_golden_words(eps, height, width=width, interleave=interleave)
        from rasterhw.sim.zbm.scene_run import run_units_equal_clocks

        r = run_units_equal_clocks([eps], width=width, height=height, interleave=interleave, engine=engine,
                                   schedule=schedule, line_log=True)
        if r.get("timeout"):
            raise RasterhwError(f"ZB/M {engine}: the bench's watchdog fired")
        marks = r["line_cycles"]
        mism = int(((r["s0"] != g0) | (r["s1"] != g1)).sum())
        out["build_s"] = r["build_s"]
    out.update(t_half=marks[5 * n - 1], t_full=marks[10 * n - 1],
               per_edge_pair=(marks[10 * n - 1] - marks[5 * n - 1]) / n, mismatches=mism)
    return out
