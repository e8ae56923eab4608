"""A test's own pysim loop of one ZB/M unit (not a user path): the unit's ``cycles`` counter read in
the first clock with ``lines == height`` (every chip has swapped the last line), the moment the
exact cycle model ``golden_model.zbm.cycles.hdl_cycles`` counts to; the scene runs and the report
run the unit on the generic engines (``sim/zbm/scene.py``, ``sim/zbm/cycles_hdl.py``)."""

from __future__ import annotations

from amaranth.sim import Simulator
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import EdgePairs
from rasterhw.golden_model.zbm import cycles as C
from rasterhw.golden_model.zbm.formats import AEP_CAPACITY, check_interleave
from rasterhw.hdl.zbm.unit import ZbmUnit
from rasterhw.sim.engines.harness import stream_put
from rasterhw.sim.zbm.cycles_hdl import table1_width


def run_unit_cycles(eps: EdgePairs, height: int, *, width: int, interleave: int,
                    capacity: int = AEP_CAPACITY, schedule: str = "overlap",
                    max_cycles: int = 200_000) -> dict:
    """Run one head ``ZbmUnit`` in pysim: edge-pair words offered one per cycle from cycle 0,
    merge outputs always ready, merge clock = segment clock (the assumptions of
    ``zbm.cycles.hdl_cycles``). Returns ``cycles`` = value of ``ZbmUnit.cycles`` in the first
    cycle with ``ZbmUnit.lines == height`` (every chip has finished the frame), ``overflow``
    and ``line_cycles`` (``line_cycles[k]`` = ``ZbmUnit.cycles`` in the first cycle with
    ``ZbmUnit.lines == k + 1``)."""

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


def measure_cycles_per_edge_pair(interleave: int, *, n_edge_pairs: int = 8, schedule: str = "overlap") -> dict:
    """Cycles per edge pair of one unit on the paper's workload, from HDL simulation.

    Returns ``cycles`` (HDL, whole frame: first word offered .. every chip done), ``edge_pairs``,
    ``cycles_per_edge_pair`` (= cycles / edge_pairs, so it includes pipeline fill and drain),
    ``model_cycles`` (``zbm.cycles.hdl_cycles``, must equal ``cycles``), ``marginal_cycles_per_edge_pair``
    (model: cycles(n + 1) - cycles(n), the steady state) and ``paper_formula`` (74, 64, 59,
    54, 54: the paper's Table 1 estimate, not a measurement)."""
    check_interleave(interleave)
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
