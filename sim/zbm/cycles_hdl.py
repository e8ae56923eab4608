"""Cycle counts of one ZB/M unit (``hdl/zbm/unit.py``) from HDL simulation, beside the exact
cycle model ``golden_model.zbm.cycles.hdl_cycles`` and the paper's Table 1 formula.

:func:`measure_table1` runs the paper's workload (sec. 6.1 cond. 1-2: edge pairs of 5 lines x 5
pixels, one segment per line, ``zbm.cycles.paper_workload``) through one head unit on any engine
(the ``zbm-unit`` testbench, ``sim/zbm/scene.py: run_scene``), every merge word compared with
the golden model. The frame is ``table1_width(interleave)`` pixels wide so each chip's merge-bus
readout of a line (``chip_pixels + 2`` cycles) is shorter than its loop work and the count is the
segment side's, as in the paper's estimate.
"""

from __future__ import annotations

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import cycles as C
from rasterhw.golden_model.zbm.formats import check_interleave
from rasterhw.sim.zbm.scene import run_units_equal_clocks

__all__ = ["measure_table1", "table1_width"]


def table1_width(interleave: int) -> int:
    """Frame width for the Table 1 workload: 4 pixels per chip (8 at least, a 5-pixel segment
    must fit)."""
    return max(4 * interleave, 8)


def measure_table1(interleave: int, *, schedule: str = "overlap", engine: str = "pysim",
                   n_edge_pairs: int = 4) -> dict:
    """Steady-state cycles per edge pair of one unit on the paper's workload, from ONE HDL run.

    The unit runs ``2 n`` paper edge pairs (``10 n`` lines, one segment per line) on ``engine``
    (pysim, verilator or icarus: the ``zbm-unit`` testbench on the generic engine); the cycle at
    which line ``5 n`` and line ``10 n`` are finished is the run's per-line log (the segment clock
    in which the last chip slot's merge output finished that line: ``UnitBench.line_cycles``, from
    the output stamps of a run with every output ready), and ``(t(10 n) - t(5 n)) / n`` is the
    steady state: fill and drain cancel. Also returns the exact model's marginal
    ``hdl_cycles(k + 1) - hdl_cycles(k)``, ``words_compared`` (every merge word of the frame) and
    ``mismatches`` (those that differ from the golden model: must be 0), on every engine.
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
    r = run_units_equal_clocks([eps], width=width, height=height, interleave=interleave, engine=engine,
                               schedule=schedule, line_log=True)
    if r["overflow"] or not r["frames_ok"]:
        raise RasterhwError(f"ZB/M unit on {engine} did not finish the frame (overflow {r['overflow']})")
    marks = r["line_cycles"]
    out.update(t_half=marks[5 * n - 1], t_full=marks[10 * n - 1],
               per_edge_pair=(marks[10 * n - 1] - marks[5 * n - 1]) / n, words_compared=r["words_compared"],
               mismatches=r["mismatches"], build_s=r["build_s"])
    return out
