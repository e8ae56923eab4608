"""ZB/M's first-level processors (seed 003, §6.2, table 2) as i860 programs on the shared i860
model (``golden_model/i860``) -- not fitted to table 2 (this module never imports it).

The paper ran its first-level processing -- coordinate transform, perspective transform,
clipping, edge-pair set-up -- on one i860XR board at 33.3 MHz, in C, and again with "the
coordinate and perspective transforms partly rewritten in assembler (pipelined instructions and
parallel execution of integer and floating-point instructions)". We write the work our golden
code does (``golden_model/pipeline.py`` geometry, ``golden_model/zbm/edgepair.py`` set-up) as
i860 programs, schedule each stage as ``compiler`` or ``assembler`` code, and price a polygon:

* ``C`` column: every stage ``compiler``;
* ``assembler`` column: transform and perspective ``assembler``, clipping and set-up
  ``compiler`` (what the paper rewrote).

Per vertex: ``transform`` (4x4 with w = 1: 12 mul + 12 add; the viewport folded into the
matrix, as ``golden_model/snu/recipe.py`` does), ``perspective`` (1/w: ``frcp`` + Newton steps,
3 multiplies), ``clip`` (6 compares against the view volume, each with its branch). Per
triangle: ``setup_triangle`` (snap 6 coordinates to the 1/256 grid, sort 3 vertices by y, the
orientation determinant, 3 edge slopes, the plane gradients of every attribute channel).
Per edge pair: ``setup_edge_pair`` (left-edge start, length and their steps, each channel's
value at the start and its step down the left edge, every word converted to fixed point and
stored: 9 words in colour mode, as ``formats.pack_edge_pair``).
"""

from __future__ import annotations

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.i860 import I860, Program, schedule
from rasterhw.golden_model.i860.cache import DataCache
from rasterhw.golden_model.zbm.paper import PAPER_I860_CLOCK_HZ

__all__ = ["CLOCK_HZ", "STAGES", "polygon_cache", "polygon_clocks", "record_bytes", "stage_clocks", "stage_program"]

#: seed 003 §6.2: "i860XR 33.3MHz" (the commercial board the paper measured on)
CLOCK_HZ = PAPER_I860_CLOCK_HZ
STAGES = ("transform", "perspective", "clip", "setup_triangle", "setup_edge_pair")
#: attribute channels per mode (``formats.CHANNELS``: colour z r g b a; mapping z um vm ui vi a)
CHANNELS = {"colour": 5, "mapping": 6}


def _fixed(p: Program, v) -> int:
    """A float to a fixed-point word: scale, ``fix``, ``fxfr`` to the core, store."""
    f = p.op("A", "fix", "cvt", p.mul(v, "scale"))
    x = p.op("C", "fxfr", None, f)
    return p.op("C", "st", None, x)


def stage_program(stage: str, *, mode: str = "colour", newton_steps: int = 2) -> Program:
    """One vertex (transform, perspective, clip), one triangle (setup_triangle) or one edge pair
    (setup_edge_pair) of ``stage``, as our golden code computes it."""
    if mode not in CHANNELS:
        raise RasterhwError(f"mode must be one of {tuple(CHANNELS)}, not {mode!r}")
    nch = CHANNELS[mode]
    p = Program(newton_steps=newton_steps)
    if stage == "transform":
        p.store(*p.affine(p.load(3)))
    elif stage == "perspective":
        x, y, z, w = p.load(4)
        r = p.recip(w)
        p.store(*(p.mul(r, v) for v in (x, y, z)))
    elif stage == "clip":
        x, y, z, w = p.load(4)
        for v in (x, y, z):
            p.cmp(v, None)
            p.cmp(w, v)
    elif stage == "setup_triangle":
        xy = p.load(6)
        snapped = [p.op("A", "fix", "cvt", p.mul(v, "sub")) for v in xy]  # to the 1/256 grid
        for _ in range(3):  # sort three vertices by y
            p.cmp(snapped[1], snapped[3])
        e = [p.add(snapped[i], snapped[j]) for i, j in ((2, 0), (3, 1), (4, 0), (5, 1))]  # e1x e1y e2x e2y
        det = p.add(p.mul(e[0], e[3]), p.mul(e[2], e[1]))
        p.cmp(det, None)  # orientation: which side the middle vertex is
        for i, j in ((0, 4), (0, 2), (2, 4)):  # edge slopes dx/dy
            dy = p.add(xy[j + 1], xy[i + 1])
            p.store(p.mul(p.add(xy[j], xy[i]), p.recip(dy, counted=None)))
        inv = p.recip(det, counted=None)
        att = p.load(3 * nch)
        for c in range(nch):
            da1 = p.add(att[3 * c + 1], att[3 * c])
            da2 = p.add(att[3 * c + 2], att[3 * c])
            dadx = p.mul(p.add(p.mul(da1, e[3]), p.mul(da2, e[1])), inv)
            dady = p.mul(p.add(p.mul(e[0], da2), p.mul(e[2], da1)), inv)
            p.store(dadx, dady)
    elif stage == "setup_edge_pair":
        g = p.load(4 + 3 * nch)  # corners, slopes, each channel's vertex value and gradients
        yc = p.add(g[0], "half")
        r0 = p.op("A", "fix", "cvt", yc)  # first and last scan line
        r1 = p.op("A", "fix", "cvt", p.add(g[1], "half"))
        p.cmp(r1, r0)
        xl = p.add(p.mul(p.add(yc, g[1]), g[2]), g[0])  # left edge at the first line's centre
        xr = p.add(p.mul(p.add(yc, g[1]), g[3]), g[1])
        length = p.add(xr, xl)
        dlen = p.add(g[3], g[2])
        words = [xl, g[2], length, dlen]
        px = p.add(xl, g[0])
        py = p.add(yc, g[1])
        for c in range(nch):
            a0, dadx, dady = g[4 + 3 * c: 7 + 3 * c]
            val = p.add(p.add(a0, p.mul(dadx, px)), p.mul(dady, py))
            ddy = p.add(dady, p.mul(dadx, g[2]))
            words += [val, ddy, dadx]
        for w in words:
            _fixed(p, w)
        for _ in range(9 + (nch - 5)):  # pack and write the edge pair's words to the bus
            p.op("C", "st", None)
    else:
        raise RasterhwError(f"unknown stage {stage!r}; stages are {', '.join(STAGES)}")
    return p


def stage_clocks(stage: str, cpu: I860 | None = None, *, mode: str = "compiler", channels: str = "colour") -> int:
    """Clocks of one unit of ``stage`` (a vertex, a triangle or an edge pair) scheduled as
    ``mode`` (``compiler`` or ``assembler``)."""
    cpu = cpu or I860(clock_hz=CLOCK_HZ)
    return schedule(stage_program(stage, mode=channels, newton_steps=cpu.newton_steps), cpu, mode)["clocks"]


def polygon_clocks(*, vertices: float = 3.0, triangles: float = 1.0, edge_pairs: float = 2.0,
                   channels: str = "colour", cpu: I860 | None = None) -> dict:
    """i860 clocks per polygon for the paper's two columns: ``C`` (every stage compiled) and
    ``assembler`` (transform and perspective hand-scheduled, clipping and set-up compiled);
    ``per_stage`` gives each stage's clocks per polygon in both schedules. The polygon mix
    (vertices, triangles, edge pairs per polygon) is an argument: the paper does not give its own."""
    for name, v in (("vertices", vertices), ("triangles", triangles), ("edge_pairs", edge_pairs)):
        if not (isinstance(v, (int, float)) and v >= 0):
            raise RasterhwError(f"{name} per polygon must be a number >= 0, not {v!r}")
    cpu = cpu or I860(clock_hz=CLOCK_HZ)
    per = {"transform": vertices, "perspective": vertices, "clip": vertices,
           "setup_triangle": triangles, "setup_edge_pair": edge_pairs}
    stages = {s: {m: n * stage_clocks(s, cpu, mode=m, channels=channels) for m in ("compiler", "assembler")}
              for s, n in per.items()}
    c = sum(v["compiler"] for v in stages.values())
    asm = sum(stages[s]["assembler" if s in ("transform", "perspective") else "compiler"] for s in stages)
    return {"C": c, "assembler": asm, "per_stage": stages, "clock_hz": cpu.clock_hz,
            "C_polygons_per_s": cpu.clock_hz / c, "assembler_polygons_per_s": cpu.clock_hz / asm}


def record_bytes(channels: str = "colour") -> int:
    """Bytes of one polygon's input record (our golden layout, float32): per vertex x, y, z in object
    space and the mode's vertex attributes (colour r, g, b, a; mapping um, vm, ui, vi, a)."""
    if channels not in CHANNELS:
        raise RasterhwError(f"mode must be one of {tuple(CHANNELS)}, not {channels!r}")
    return 3 * (3 + CHANNELS[channels] - 1) * 4


def polygon_cache(polygons: int, *, channels: str = "colour", edge_pairs: int = 2,
                  cache: DataCache | None = None) -> dict:
    """The data cache over one run of ``polygons`` polygons processed one at a time (table 2's
    5,760 / N): each polygon's input record read from a contiguous array (the records' layout,
    :func:`record_bytes`), every stage's intermediate values stored to and loaded from one per-polygon
    scratch area (transformed and projected vertices, gradients: the same addresses for every
    polygon), the edge pairs' words stored to a contiguous output array. Returns the cache's counts
    and ``stall_clocks`` (line fills and write-backs at the cache's miss cost) in all and per polygon."""
    if isinstance(polygons, bool) or not isinstance(polygons, int) or polygons < 1:
        raise RasterhwError(f"polygons must be a positive integer, not {polygons!r}")
    c = cache or DataCache()
    rec = record_bytes(channels)
    nch = CHANNELS[channels]
    scratch = 1 << 30   # far from the records and the output
    out = 2 << 30
    ep_bytes = (9 + (nch - 5)) * 4
    s_words = 3 * 4 + 3 * 4 + 2 * nch + 4   # transformed (x y z w), projected, gradients, edge slopes
    for k in range(polygons):
        for b in range(0, rec, 4):
            c.access(k * rec + b)
        for w in range(s_words):              # stored by one stage ...
            c.access(scratch + 4 * w, store=True)
        for w in range(s_words):              # ... loaded by the next
            c.access(scratch + 4 * w)
        for b in range(0, edge_pairs * ep_bytes, 4):
            c.access(out + (k * edge_pairs) * ep_bytes + b, store=True)
    return {"polygons": polygons, "record_bytes": rec, "hits": c.hits, "misses": c.misses,
            "writebacks": c.writebacks, "store_misses": c.store_misses, "stall_clocks": c.stall_clocks,
            "stall_clocks_per_polygon": c.stall_clocks / polygons, "miss_clocks": c.miss_clocks}
