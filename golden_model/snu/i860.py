"""A timing model of the Intel i860 (XR) for the SNU geometry stages -- from the processor's
documented behaviour, **not** fitted to the paper's table 1.

Sources (cited in ``docs/snu_geometry.md``): the *i860 64-bit Microprocessor Programmer's
Reference Manual* (Intel, 1989/1990 -- the paper's reference [7]), chapter 6 "Floating-point
instructions", and the i860 XR data sheet. What the model takes from them:

* **Floating-point adder**: a 3-stage pipeline, one new operation per clock, result 3 clocks
  after issue (PRM 6.2: "three-stage pipelining as found in the floating-point adder").
  Adds, subtracts, compares (``pfgt``/``pfle``, which set the condition code) and
  float -> integer conversion (``ftrunc``/``fix``) all run here.
* **Floating-point multiplier**: 3 stages for single-precision sources (PRM 6.2: "also in the
  floating-point multiplier when single-precision input operands are employed"), one new
  operation per clock.
* **No divide and no square root instruction**: ``frcp`` and ``frsqr`` give seeds whose
  significand is good to about 2^-7 (PRM, instruction pages); software refines them with
  Newton-Raphson steps, each of which doubles the good bits. Single precision (24 bits) needs
  two steps (7 -> 14 -> 28 bits); one step (14 bits) would not place a vertex on the 1/256
  pixel grid of a 1280-pixel line (2^-19 needed), so :data:`NEWTON_STEPS` = 2 comes from
  precision, not from the table. Reciprocal step ``y' = y (2 - a y)``: 2 mul + 1 add;
  reciprocal square root step ``y' = y (1.5 - (a/2) y y)``: 3 mul + 1 add (``a/2`` once).
  We place the seed instructions in the multiplier unit with its latency (our reading).
* **Dual-operation instructions** (``pfam``, ``pfmam`` ...): one adder and one multiplier
  operation issued together, the source of the 80 Mflops peak of a 40 MHz part (2 per
  clock). We let *any* ready add pair with *any* ready multiply; the real data paths
  (the multiplier result or the KR/KI/T registers feeding the adder) are narrower, so this
  is optimistic -- model clocks are a lower bound for a hand-scheduled program.
* **Dual-instruction mode** (``d.`` prefix): one core instruction and one floating-point
  instruction per clock. Core instructions: loads, stores, branches on the condition code,
  integer adds, ``fxfr`` (FP -> integer register). Without dual-instruction mode only one
  instruction issues per clock.
* **Loads**: a cached ``fld``/``ld`` issues in one clock and its result can be used two
  clocks later (one load-delay clock).
* **Bus**: 64 bits wide, a bus cycle takes 2 clocks (160 MB/s at 40 MHz, the XR data sheet's
  figure).
* **Graphics unit** (``faddp``/``faddz``, 64-bit integer adds on FP registers, 1 stage): used by
  the scan-conversion inner loop, see :func:`inner_loop_clocks`.

A stage is written as the dependency graph (DAG) of the instructions it runs for **one
vertex** (:func:`stage_program`); a triangle is three independent copies; a list scheduler
issues instructions clock by clock under the limits above, ready operations on the longest
remaining path first. ``clocks`` is the clock in which the last result is ready (pipes
empty at the start, drained at the end: the paper's one-polygon-at-a-time view); ``stream``
is the clocks per triangle when many triangles are scheduled together (software pipelining,
the best a programmer could do). Every parameter of :class:`I860` is one of the documented
facts above.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass, field

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["EXTRA_STAGES", "I860", "NEWTON_STEPS", "Program", "STAGES", "inner_loop_clocks", "program_counts", "scan_clocks", "schedule", "setup_program",
           "stage_clocks", "stage_program", "table1_model"]

#: Newton-Raphson steps after an ``frcp``/``frsqr`` seed (about 7 good bits) for single precision.
NEWTON_STEPS = 2
STAGES = ("vertex_transform", "normal_transform", "normalise", "light", "clip",
          "perspective_divide", "screen_map")
#: Programs outside table 1 (the paper counts no float -> integer step).
EXTRA_STAGES = ("to_integer",)
UNITS = ("A", "M", "G", "C")  # FP adder, FP multiplier, graphics unit, core


@dataclass(frozen=True)
class I860:
    """Documented i860 XR timing (see the module docstring). All in clocks."""

    add_latency: int = 3
    mul_latency: int = 3
    graphics_latency: int = 1
    core_latency: int = 1
    load_latency: int = 2
    dual_instruction: bool = True
    dual_operation: bool = True
    clock_hz: float = 40e6  # the paper never says; 40 MHz was the XR's top grade
    bus_bytes_per_cycle: int = 8
    bus_clocks_per_cycle: int = 2
    newton_steps: int = NEWTON_STEPS

    def __post_init__(self) -> None:
        for name in ("add_latency", "mul_latency", "graphics_latency", "core_latency", "load_latency",
                     "bus_bytes_per_cycle", "bus_clocks_per_cycle"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise RasterhwError(f"{name} must be a positive integer, not {v!r}")
        if isinstance(self.newton_steps, bool) or not isinstance(self.newton_steps, int) or self.newton_steps < 0:
            raise RasterhwError(f"newton_steps must be an integer >= 0, not {self.newton_steps!r}")
        if not self.clock_hz > 0:
            raise RasterhwError(f"clock_hz must be > 0, not {self.clock_hz!r}")

    def latency(self, unit: str, kind: str) -> int:
        if unit == "A":
            return self.add_latency
        if unit == "M":
            return self.mul_latency
        if unit == "G":
            return self.graphics_latency
        return self.load_latency if kind in ("load", "lookup") else self.core_latency


@dataclass
class Program:
    """Instructions with dependencies. ``ops[i] = (unit, kind, counted, srcs)``: ``kind`` is the
    instruction, ``counted`` the operation category it belongs to in the paper's count (``mul``,
    ``add``, ``cmp``, ``div``, ``sqrt``, ``lookup``) or ``None`` for work the count leaves out
    (a branch on a compare, an ``fxfr``)."""

    ops: list = field(default_factory=list)
    newton_steps: int = NEWTON_STEPS

    def op(self, unit: str, kind: str, counted: str | None, *srcs: int) -> int:
        if unit not in UNITS:
            raise RasterhwError(f"unit must be one of {UNITS}, not {unit!r}")
        self.ops.append((unit, kind, counted, tuple(x for x in srcs if x is not None)))
        return len(self.ops) - 1

    # counted operations ------------------------------------------------------------------
    def mul(self, *s):
        return self.op("M", "fmul", "mul", *s)

    def add(self, *s):
        return self.op("A", "fadd", "add", *s)

    def cmp(self, *s):
        c = self.op("A", "pfgt", "cmp", *s)
        return self.op("C", "bc", None, c)  # the core tests the condition code

    def recip(self, a: int, counted: str = "div") -> int:
        y = self.op("M", "frcp", counted, a)
        for _ in range(self.newton_steps):
            e = self.op("M", "fmul", None, a, y)
            f = self.op("A", "fsub", None, e)
            y = self.op("M", "fmul", None, y, f)
        return y

    def rsqrt(self, a: int) -> int:
        """1/sqrt(a): the paper's "square root + reciprocal" (counted sqrt 1 + div 1)."""
        y = self.op("M", "frsqr", "sqrt", a)
        h = self.op("M", "fmul", "div", a)  # a/2, once; the reciprocal's share of the count
        for _ in range(self.newton_steps):
            yy = self.op("M", "fmul", None, y, y)
            t = self.op("M", "fmul", None, h, yy)
            f = self.op("A", "fsub", None, t)
            y = self.op("M", "fmul", None, y, f)
        return y

    def lookup(self, idx: int) -> int:
        x = self.op("C", "fxfr", None, idx)
        return self.op("C", "lookup", "lookup", x)

    def dot3(self, a, b=(None, None, None)):
        m = [self.mul(a[i]) if b[i] is None else self.mul(a[i], b[i]) for i in range(3)]
        return self.add(self.add(m[0], m[1]), m[2])

    def concat(self, other: Program) -> list[int]:
        base = len(self.ops)
        for unit, kind, counted, srcs in other.ops:
            self.ops.append((unit, kind, counted, tuple(s + base for s in srcs)))
        return list(range(base, base + len(other.ops)))


def stage_program(stage: str, *, newton_steps: int = NEWTON_STEPS) -> Program:
    """One vertex of ``stage`` as the paper's recipe computes it (``golden_model/snu/recipe.py``);
    inputs and constants are in registers at clock 0 (a ``None`` or absent source is one)."""
    p = Program(newton_steps=newton_steps)
    if stage == "vertex_transform":  # 4 rows: m0 x + m1 y + m2 z + t, summed as a tree
        for _ in range(4):
            a, b, c = p.mul(), p.mul(), p.mul()
            p.add(p.add(a, b), p.add(c))
    elif stage == "normal_transform":
        for _ in range(3):
            p.dot3((None, None, None))
    elif stage == "normalise":
        r = p.rsqrt(p.dot3((None, None, None)))  # x x + y y + z z, then 1/sqrt
        for _ in range(3):
            p.mul(r)
    elif stage == "light":
        d = p.dot3((None, None, None))  # the one inner product
        s = p.add(d)  # d + n_z
        u = p.add(s)  # + magic: table index in the mantissa
        t = p.lookup(u)
        for _ in range(3):
            e = p.add(p.mul(d))  # A_c + D_c d
            g = p.mul(e)  # x Cd_c
            h = p.mul(t)  # S_c t
            p.cmp(p.add(g, h))  # clamp at 1
    elif stage == "clip":
        for _ in range(6):
            p.cmp()
    elif stage == "perspective_divide":
        r = p.recip(None)  # 1/w
        for _ in range(3):
            p.mul(r)
    elif stage == "screen_map":
        p.mul()
        p.add(p.mul())
        p.add(p.mul())
    elif stage == "to_integer":  # outside table 1: z to an integer with the 24-bit clamp,
        z = p.op("A", "fix", "cvt")  # r, g, b floored at 0 (recipe.py)
        p.op("C", "fxfr", None, z)
        for _ in range(4):
            p.cmp()
    else:
        raise RasterhwError(f"unknown stage {stage!r}; stages are {', '.join(STAGES + EXTRA_STAGES)}")
    return p


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
    scan line) from :func:`setup_program`, scheduled; ``pixel`` (per pixel) from
    :func:`inner_loop_clocks` on the counts of one executed pixel."""
    cpu = cpu or I860()
    one = {"pixels": 1, **{k: 1 for k in ("add_addr", "add_count", "store", "branch",
                                         "add_r", "add_g", "add_b", "add_z")}}
    return {"triangle": schedule(setup_program("triangle", newton_steps=cpu.newton_steps), cpu)["clocks"],
            "span": schedule(setup_program("span", newton_steps=cpu.newton_steps), cpu)["clocks"],
            "pixel": inner_loop_clocks(one, cpu)}


def program_counts(p: Program) -> dict:
    """Counted operations of ``p`` by category (what the paper's count covers) and instructions
    by unit (what the processor really issues)."""
    counted: dict[str, int] = {}
    units = dict.fromkeys(UNITS, 0)
    for unit, _kind, c, _ in p.ops:
        units[unit] += 1
        if c is not None:
            counted[c] = counted.get(c, 0) + 1
    return {"counted": counted, "units": units, "instructions": len(p.ops)}


def schedule(p: Program, cpu: I860 | None = None) -> dict:
    """List-schedule ``p`` on ``cpu``; returns ``clocks`` (last result ready), ``issue`` (clock of
    each instruction) and ``busy`` (instructions per unit)."""
    cpu = cpu or I860()
    n = len(p.ops)
    succ: list[list[int]] = [[] for _ in range(n)]
    for i, (_u, _k, _c, srcs) in enumerate(p.ops):
        for s in srcs:
            if not 0 <= s < i:
                raise RasterhwError(f"instruction {i} depends on {s}, which is not before it")
            succ[s].append(i)
    lat = [cpu.latency(u, k) for u, k, _c, _s in p.ops]
    prio = [0] * n  # longest path to the end, for the ready-list order
    for i in range(n - 1, -1, -1):
        prio[i] = lat[i] + max((prio[j] for j in succ[i]), default=0)
    ready_at = [0] * n
    waiting = [len(srcs) for _u, _k, _c, srcs in p.ops]
    issue = [-1] * n
    ready = [i for i in range(n) if waiting[i] == 0]
    t, done, end = 0, 0, 0
    while done < n:
        cand = sorted((i for i in ready if ready_at[i] <= t), key=lambda i: (-prio[i], i))
        taken = {"A": None, "M": None, "G": None, "C": None}
        for i in cand:
            u = p.ops[i][0]
            if taken[u] is not None:
                continue
            fp = [x for x in ("A", "M", "G") if taken[x] is not None]
            n_instr = (1 if fp else 0) + (1 if taken["C"] is not None else 0)
            if u in ("A", "M", "G"):
                if fp:  # a second FP operation only as the other half of a dual-operation
                    if not (cpu.dual_operation and {u, *fp} <= {"A", "M"}):
                        continue
                elif not cpu.dual_instruction and n_instr >= 1:
                    continue
            elif not cpu.dual_instruction and n_instr >= 1:
                continue
            taken[u] = i
        for i in taken.values():
            if i is None:
                continue
            issue[i] = t
            ready.remove(i)
            done += 1
            r = t + lat[i]
            end = max(end, r)
            for j in succ[i]:
                ready_at[j] = max(ready_at[j], r)
                waiting[j] -= 1
                if waiting[j] == 0:
                    ready.append(j)
        t += 1
    busy = dict.fromkeys(UNITS, 0)
    for u, _k, _c, _s in p.ops:
        busy[u] += 1
    return {"clocks": end, "issue": issue, "busy": busy}


def _triangles(stage: str, n: int, cpu: I860) -> Program:
    one = stage_program(stage, newton_steps=cpu.newton_steps)
    p = Program(newton_steps=cpu.newton_steps)
    for _ in range(3 * n):
        p.concat(one)
    return p


def stage_clocks(stage: str, cpu: I860 | None = None, *, stream_triangles: int = 16) -> dict:
    """Clocks of one triangle (three vertices) of ``stage`` on ``cpu``.

    ``clocks``: one triangle alone, pipes empty before and drained after;
    ``stream``: clocks per triangle over ``stream_triangles`` triangles scheduled together;
    ``serial``: three times one vertex alone (vertices one after another, not interleaved);
    ``bound``: the busiest unit's instruction count per triangle (no schedule can beat it);
    ``counted``: the paper-style operation counts per triangle of the program.
    """
    cpu = cpu or I860()
    one = _triangles(stage, 1, cpu)
    many = _triangles(stage, stream_triangles, cpu)
    vertex = stage_program(stage, newton_steps=cpu.newton_steps)
    c = program_counts(one)
    fp = c["units"]["A"] + c["units"]["M"] + c["units"]["G"]
    if cpu.dual_instruction:
        bound = max(c["units"]["A"], c["units"]["M"], c["units"]["C"], c["units"]["G"])
        if not cpu.dual_operation:
            bound = max(bound, fp)
    else:
        bound = c["instructions"] - (min(c["units"]["A"], c["units"]["M"]) if cpu.dual_operation else 0)
    return {"stage": stage, "clocks": schedule(one, cpu)["clocks"],
            "stream": schedule(many, cpu)["clocks"] / stream_triangles,
            "serial": 3 * schedule(vertex, cpu)["clocks"],
            "bound": bound, "counted": c["counted"], "units": c["units"]}


def table1_model(cpu: I860 | None = None) -> dict:
    """Stage -> :func:`stage_clocks` for table 1's seven stages, plus ``total`` clocks.
    (Scheduled once per processor configuration; each call gets its own copy.)"""
    return copy.deepcopy(_table1_model(cpu or I860()))


@functools.lru_cache(maxsize=32)
def _table1_model(cpu: I860) -> dict:
    rows = {s: stage_clocks(s, cpu) for s in STAGES}
    rows["total"] = {k: sum(r[k] for r in rows.values()) for k in ("clocks", "stream", "serial", "bound")}
    return rows


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
