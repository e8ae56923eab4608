"""SNU's geometry stages (seed 004, table 1) as i860 programs, scheduled on the shared i860 model
(``golden_model/i860``) -- not fitted to the paper's table 1 (this module never imports it).

Each stage is the instruction sequence the paper's recipe (``golden_model/snu/recipe.py``)
executes for **one vertex**: its input floats loaded from memory, its counted operations (tagged
with the recipe's categories, so a test holds them equal to what the recipe counted), the work
the count leaves out (Newton steps, branches on compares, ``fxfr``), its results stored. A
triangle is three copies. Two schedules (``golden_model/i860/model.py``): ``compiler`` (C of the
time: program order, scalar FP, one instruction per clock, constants loaded where used) and
``assembler`` (pipelined, dual-operation where the data paths allow, dual-instruction mode,
30 value registers). Table 1's 309 clocks are set beside the assembler schedule: "72 operations
in 60 clocks" needs more than one operation per clock, which only pipelined dual-operation code
gives.

``clocks`` = one triangle, pipes empty before and drained after (the paper's one-polygon view);
``stream`` = clocks per triangle when ``stream_triangles`` triangles are scheduled together.
Nothing here is cached: every call schedules again (``tests/snu/test_snu_i860.py`` patches a
function and checks the result moves).
"""

from __future__ import annotations

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.i860 import (
    I860,
    NEWTON_STEPS,
    PARAMETERS,
    SCHEDULES,
    UNITS,
    Program,
    counts,
    schedule,
)

__all__ = ["EXTRA_STAGES", "I860", "NEWTON_STEPS", "PARAMETERS", "Program", "SCHEDULES", "STAGES", "UNITS",
           "inner_loop_clocks", "program_counts", "scan_clocks", "STAGE_NOTES", "schedule", "setup_program", "stage_clocks",
           "stage_program", "table1_model"]

STAGES = ("vertex_transform", "normal_transform", "normalise", "light", "clip",
          "perspective_divide", "screen_map")
#: Programs outside table 1 (the paper counts no float -> integer step).
EXTRA_STAGES = ("to_integer",)


#: Stage by stage, the documented fact that decides where the model and table 1 differ (the
#: numbers are printed beside it by ``sim/snu/report.py``; ``docs/snu_geometry.md`` discusses them).
STAGE_NOTES = {
    "vertex_transform": "16 named constants (12 matrix entries, 4 offsets) stay in registers, leaving 14 of the 30 "
                        "(PRM ch. 2: f0/f1 read as zero) for three vertices' products; a dual-operation "
                        "instruction reads only src1 and src2 (PRM ch. 6, DPC table), so a multiply by a matrix "
                        "entry pairs with an add only if the entry is in KR; results leave the pipes only when "
                        "another instruction is issued to them (PRM §6.2): drain pushes",
    "normal_transform": "9 constants; 3-term dot products; the adder tree waits on pipelined results that leave "
                        "only when the next pipelined instruction issues (PRM §6.2)",
    "normalise": "the 1/sqrt chain: frsqr seed + 2 Newton steps (PRM ch. 6 FRSQR: seed good to 2^-7), each "
                 "step 4 dependent operations; the three vertices' chains overlap; the paper's code is not known",
    "light": "the exponent table lookup goes through the core (fxfr + fld, load delay: PRM ch. 5), the clamps "
             "branch on the condition code (core slot, dual-instruction mode: PRM ch. 7); 13 named constants",
    "clip": "18 compares, each an adder operation + a branch on the condition code in the core slot "
            "(dual-instruction mode, PRM ch. 7); table 1 counts 24 operations, the text 18",
    "perspective_divide": "1/w = frcp seed + 2 Newton steps (PRM ch. 6 FRCP: 2^-7 seed; 2 steps for single "
                          "precision): 8 dependent operations per vertex; the paper's 18 fits one step (14-bit)",
    "screen_map": "3 mul + 2 add per vertex is short work; the paper's 27 includes the float -> integer "
                  "conversion its text mentions (4.2): see the 'screen_map + float -> integer' row",
}


def stage_program(stage: str, *, newton_steps: int = NEWTON_STEPS) -> Program:
    """One vertex of ``stage`` as the paper's recipe computes it (``golden_model/snu/recipe.py``).
    Named constants (matrix entries, light terms) are strings; ``None`` is a register that
    reads as zero (f0) or a value kept in a register."""
    p = Program(newton_steps=newton_steps)
    if stage == "vertex_transform":  # 4 rows: m0 x + m1 y + m2 z + t
        p.store(*p.affine(p.load(3)))
    elif stage == "normal_transform":
        n = p.load(3)
        p.store(*(p.dot3(n, tuple(f"n{r}{k}" for k in range(3))) for r in range(3)))
    elif stage == "normalise":
        n = p.load(3)
        r = p.rsqrt(p.dot3(n, n))  # x x + y y + z z, then 1/sqrt
        p.store(*(p.mul(r, n[k]) for k in range(3)))
    elif stage == "light":
        n = p.load(3)
        cd = p.load(3)
        d = p.dot3(n, ("lx", "ly", "lz"))  # the one inner product
        s = p.add(d, n[2])  # d + n_z
        u = p.add(s, "magic")  # + magic: table index in the mantissa
        t = p.lookup(u)
        out = []
        for c in range(3):
            e = p.add(p.mul(d, f"D{c}"), f"A{c}")  # A_c + D_c d
            g = p.mul(e, cd[c])  # x Cd_c
            h = p.mul(t, f"S{c}")  # S_c t
            v = p.add(g, h)
            p.cmp(v, "one")  # clamp at 1
            out.append(v)
        p.store(*out)
    elif stage == "clip":
        x, y, z, w = p.load(4)
        for v in (x, y, z):
            p.cmp(v, None)  # v >= 0 (f0)
            p.cmp(w, v)  # v <= w
    elif stage == "perspective_divide":
        x, y, z, w = p.load(4)
        r = p.recip(w)  # 1/w
        p.store(*(p.mul(r, v) for v in (x, y, z)))
    elif stage == "screen_map":
        x, y, z = p.load(3)
        p.store(p.mul(x, "W"), p.add(p.mul(y, "mH"), "H"), p.add(p.mul(z, "mZ"), "Z"))
    elif stage == "to_integer":  # outside table 1: z to an integer with the 24-bit clamp,
        z, r, g, b = p.load(4)  # r, g, b floored at 0 (recipe.py)
        zi = p.op("A", "fix", "cvt", z)
        p.op("C", "fxfr", None, zi)
        p.cmp(zi, "zmax")
        for v in (r, g, b):
            p.cmp(v, None)
    else:
        raise RasterhwError(f"unknown stage {stage!r}; stages are {', '.join(STAGES + EXTRA_STAGES)}")
    return p


def _triangles(stage: str, n: int, newton_steps: int) -> Program:
    one = stage_program(stage, newton_steps=newton_steps)
    p = Program(newton_steps=newton_steps)
    for _ in range(3 * n):
        p.concat(one)
    return p


def program_counts(p: Program) -> dict:
    """Counted operations by category and instructions by unit (``golden_model.i860.counts``)."""
    return counts(p)


def _check_mode(mode: str) -> str:
    if mode not in SCHEDULES:
        raise RasterhwError(f"schedule must be one of {SCHEDULES}, not {mode!r}")
    return mode


def stage_clocks(stage: str, cpu: I860 | None = None, *, mode: str = "assembler",
                 stream_triangles: int = 8) -> dict:
    """Clocks of one triangle (three vertices) of ``stage`` on ``cpu``, scheduled as ``mode``.

    ``clocks``: one triangle alone, pipes empty before and drained after; ``stream``: clocks per
    triangle over ``stream_triangles`` triangles scheduled together, or ``clocks`` if running them
    one after another is faster (``None`` if ``stream_triangles`` is 0);
    ``counted``: the paper-style operation counts per triangle; ``units``: instructions per
    unit; plus the schedule's ``pushes``, ``dual_ops``, ``spills``, ``peak_registers``,
    ``fp_instructions`` and ``core_instructions`` for the one triangle.
    """
    cpu = cpu or I860()
    _check_mode(mode)
    one = _triangles(stage, 1, cpu.newton_steps)
    r = schedule(one, cpu, mode)
    c = counts(one)
    stream = None
    if stream_triangles:
        # the better of two legal programs: the triangles scheduled together, or one after
        # another (the list scheduler can lose when 30 registers limit the overlap)
        together = schedule(_triangles(stage, stream_triangles, cpu.newton_steps), cpu, mode)["clocks"]
        stream = min(together / stream_triangles, float(r["clocks"]))
    return {"stage": stage, "mode": mode, "clocks": r["clocks"], "stream": stream, "counted": c["counted"],
            "units": c["units"], **{k: r[k] for k in ("pushes", "dual_ops", "spills", "peak_registers",
                                                       "fp_instructions", "core_instructions")}}


def table1_model(cpu: I860 | None = None, *, mode: str = "assembler", stream_triangles: int = 8) -> dict:
    """Stage -> :func:`stage_clocks` for table 1's seven stages, plus ``total`` (clocks, stream).
    Scheduled on every call (no cache)."""
    rows = {s: stage_clocks(s, cpu, mode=mode, stream_triangles=stream_triangles) for s in STAGES}
    rows["total"] = {"clocks": sum(rows[s]["clocks"] for s in STAGES),
                     "stream": None if not stream_triangles else sum(rows[s]["stream"] for s in STAGES)}
    return rows


def setup_program(kind: str, *, newton_steps: int = NEWTON_STEPS) -> Program:
    """The scan converter's per-triangle and per-scan-line work (``gouraud.setup_spans``), as
    i860 instructions -- our sketch of what that code does, not the paper's (it gives none).

    ``"triangle"``: sort the corners by y (3 compares), twice the area (5 add, 2 mul), its
    reciprocal, the r, g, b, z plane gradients (per attribute 2 differences, then
    ``(da1 dy2 - da2 dy1) / den`` and the same for y: 6 mul + 4 add), three edge slopes
    (reciprocal + multiply each), per trapezoid the anchor value of each attribute (2 mul +
    2 add), and 16 float -> fixed conversions (scale, ``fix``, ``fxfr``).
    ``"span"``: one scan line of the outer loop: two Bresenham edge steps (add, compare,
    branch, conditional add on the core), four accumulator steps (graphics unit), the pixel
    count and the line's first address (core), the loop branch.
    """
    p = Program(newton_steps=newton_steps)
    if kind == "triangle":
        for _ in range(3):
            p.cmp()
        d = [p.add() for _ in range(4)]
        area = p.add(p.mul(d[0], d[1]), p.mul(d[2], d[3]))
        inv = p.recip(area, counted=None)
        for _ in range(4):
            da1, da2 = p.add(), p.add()
            for _axis in range(2):
                p.mul(p.add(p.mul(da1), p.mul(da2)), inv)
        for _ in range(3):
            p.mul(p.recip(p.add(), counted=None))
        for _ in range(2 * 4):
            p.add(p.mul(), p.add(p.mul()))
        for _ in range(16):
            p.op("C", "fxfr", None, p.op("A", "fix", None, p.mul()))
    elif kind == "span":
        for _ in range(2):  # edge: error += slope; if error >= 1: x += 1, error -= 1
            e = p.op("C", "adds", None)
            b = p.op("C", "bc", None, e)
            p.op("C", "addu", None, b)
        for _ in range(4):
            p.op("G", "faddz", None)
        n = p.op("C", "subs", None)
        a = p.op("C", "addu", None)
        p.op("C", "bla", None, n, a)
    else:
        raise RasterhwError(f"setup_program kind must be 'triangle' or 'span', not {kind!r}")
    return p


def scan_clocks(cpu: I860 | None = None) -> dict:
    """i860 clocks of the scan converter: ``triangle`` (set-up per triangle), ``span`` (per
    scan line) from :func:`setup_program`, scheduled as assembler; ``pixel`` (per pixel) from
    :func:`inner_loop_clocks` on the counts of one executed pixel."""
    cpu = cpu or I860()
    one = {"pixels": 1, **{k: 1 for k in ("add_addr", "add_count", "store", "branch",
                                         "add_r", "add_g", "add_b", "add_z")}}
    return {"triangle": schedule(setup_program("triangle", newton_steps=cpu.newton_steps), cpu)["clocks"],
            "span": schedule(setup_program("span", newton_steps=cpu.newton_steps), cpu)["clocks"],
            "pixel": inner_loop_clocks(one, cpu)}


def inner_loop_clocks(executed: dict, cpu: I860 | None = None) -> float:
    """Clocks per pixel of the Gouraud inner loop from the operations the scan converter
    *executed* (``gouraud.scan_convert(..., counts=...)``): adds on the address and the count
    are core instructions, adds on r, g, b, z run in the graphics unit (64-bit integer adds on
    FP registers), the store and the branch are core instructions. With dual-instruction mode
    the core and the graphics unit issue in the same clock: clocks = max(core, graphics) per
    pixel; without it, their sum."""
    cpu = cpu or I860()
    px = executed["pixels"]
    if px <= 0:
        raise RasterhwError("inner_loop_clocks needs at least one pixel")
    core = executed["add_addr"] + executed["add_count"] + executed["store"] + executed["branch"]
    gfx = executed["add_r"] + executed["add_g"] + executed["add_b"] + executed["add_z"]
    return (max(core, gfx) if cpu.dual_instruction else core + gfx) / px
