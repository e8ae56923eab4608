"""SNU graphics system: table 1 (operations and i860 clocks per triangle) and the stage balance.

Seed 004, section 4.5 (translated): "The processing times of the algorithms computed above are
summarised in table 1. The operation count is the number of real additions and real
multiplications one polygon needs, and the real processing time is the number of clocks it
takes when executed on the i860. On this basis, assuming a graphics pipeline of three i860
processors, the first processor is given vertex transform and normal-vector transform, the
second normal-vector normalisation and lighting, the last clipping, projection and screen
mapping."

This module holds the paper's table as labelled constants, the per-vertex operation mix the
paper's *text* (4.2.1-4.2.5) gives for each stage, a per-operation i860 clock-cost model
*derived* from those two (see :data:`I860_COST` and ``docs/snu_geometry.md``), and the
arithmetic that turns per-stage counts (the paper's, or the ones ``golden_model/opcount.py``
measures) into a clock column, the three-processor balance and the Mflops column.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = [
    "CLOCK_HZ",
    "GROUPS",
    "I860_COST",
    "OP_KINDS",
    "PAPER_TABLE1",
    "PAPER_TEXT_COUNTS",
    "STAGES",
    "balance",
    "clocks_from_ops",
    "cost_derivation",
    "extra_stages",
    "mflops",
    "per_triangle",
    "table1_rows",
]

#: Stage names, in table 1 order (``perspective_divide`` is the paper's "projection").
STAGES = ("vertex_transform", "normal_transform", "normalise", "light", "clip",
          "perspective_divide", "screen_map")
OP_KINDS = ("mul", "add", "cmp", "div", "sqrt", "lookup", "cvt")

#: Table 1 of the paper, per triangle: operations, i860 clocks, percent of clocks.
PAPER_TABLE1: dict[str, dict[str, float]] = {
    "vertex_transform": {"ops": 72, "clocks": 60, "percent": 19.4},
    "normal_transform": {"ops": 45, "clocks": 39, "percent": 12.6},
    "normalise": {"ops": 30, "clocks": 81, "percent": 26.2},
    "light": {"ops": 72, "clocks": 60, "percent": 19.4},
    "clip": {"ops": 24, "clocks": 24, "percent": 7.8},
    "perspective_divide": {"ops": 12, "clocks": 18, "percent": 5.8},
    "screen_map": {"ops": 15, "clocks": 27, "percent": 8.7},
}
PAPER_TOTAL_OPS = 270
PAPER_TOTAL_CLOCKS = 309
#: The paper's Mflops for 100,000 polygons/s (text 4.2.1-4.2.5); clip is 1.8 in the text
#: (18 compares), although table 1 has 24 operations.
PAPER_MFLOPS = {"vertex_transform": 7.2, "normal_transform": 4.5, "normalise": 3.0, "light": 7.2,
                "clip": 1.8, "perspective_divide": 1.2, "screen_map": 1.5}

#: Per-vertex operation mix the paper's text gives (x3 per triangle). ``div`` is a reciprocal.
#: The paper counts 1/sqrt as "2 real operations" (sqrt + reciprocal).
PAPER_TEXT_COUNTS: dict[str, dict[str, int]] = {
    # 4x4 matrix with w fixed at 1.0: 12 mul + 12 add
    "vertex_transform": {"mul": 12, "add": 12},
    # 3x3 matrix: 9 mul + 6 add
    "normal_transform": {"mul": 9, "add": 6},
    # sum of squares 3 mul + 2 add; 1 sqrt + 1 reciprocal; scale 3 mul
    "normalise": {"mul": 6, "add": 2, "sqrt": 1, "div": 1},
    # 12 mul, 10 add, 3 compares, 1 memory reference (exponent lookup)
    "light": {"mul": 12, "add": 10, "cmp": 3, "lookup": 1},
    # 6 compares per vertex against the view volume
    "clip": {"cmp": 6},
    # reciprocal of w, 3 multiplies
    "perspective_divide": {"div": 1, "mul": 3},
    # 3 mul (x1280, y1024, z 2^24) + 2 add (z flip, y flip)
    "screen_map": {"mul": 3, "add": 2},
}

#: i860 clock frequency assumed for polygons/s. The paper never states it (the i860 XR came
#: at 25, 33 and 40 MHz); 40 MHz is consistent with its "8 ops per pixel, 80 MOPS for
#: 10 Mpixel/s, 4 clocks per pixel" (10 Mpixel/s x 4 clocks = 40 MHz).
CLOCK_HZ = 40e6

#: The three-processor split of section 4.5.
GROUPS: dict[str, tuple[str, ...]] = {
    "P1 transform": ("vertex_transform", "normal_transform"),
    "P2 normalise+light": ("normalise", "light"),
    "P3 clip+project+map": ("clip", "perspective_divide", "screen_map"),
}


def _derive_costs() -> dict[str, Fraction]:
    """Clocks per operation implied by table 1's clock column and the text's op mixes.

    Per vertex (table clocks / 3):
      vertex transform   12 mul + 12 add              = 20
      normal transform    9 mul +  6 add              = 13   -> mul = 1, add = 2/3
      perspective divide  1 div +  3 mul              =  6   -> div = 3
      clip                6 cmp                       =  8   -> cmp = 4/3
      normalise           6 mul + 2 add + sqrt + div  = 27   -> sqrt = 50/3
    ``lookup`` appears only in lighting, whose row the solved costs already exceed without it
    (12 + 20/3 + 4 = 22.7 > 20), so it cannot be derived; it is set to 1 clock (one cached
    load) -- an assumption. ``cvt`` (float -> integer, counted by ``opcount``) never appears in
    the paper's counts; it is given the add cost (the i860's ``ftrunc`` runs in the adder
    pipeline) -- an assumption.
    """
    t = {s: Fraction(PAPER_TABLE1[s]["clocks"]) / 3 for s in STAGES}
    c = PAPER_TEXT_COUNTS
    # 12m + 12a = t_vt ; 9m + 6a = t_nt  -> solve the 2x2 system exactly
    a11, a12, b1 = c["vertex_transform"]["mul"], c["vertex_transform"]["add"], t["vertex_transform"]
    a21, a22, b2 = c["normal_transform"]["mul"], c["normal_transform"]["add"], t["normal_transform"]
    det = Fraction(a11 * a22 - a12 * a21)
    mul = (b1 * a22 - a12 * b2) / det
    add = (a11 * b2 - a21 * b1) / det
    div = t["perspective_divide"] - c["perspective_divide"]["mul"] * mul
    cmp = t["clip"] / c["clip"]["cmp"]
    n = c["normalise"]
    sqrt = t["normalise"] - n["mul"] * mul - n["add"] * add - n["div"] * div
    return {"mul": mul, "add": add, "cmp": cmp, "div": div, "sqrt": sqrt, "lookup": Fraction(1),
            "cvt": add}


#: Clocks per operation on the i860 (exact fractions), derived by :func:`_derive_costs`.
I860_COST: dict[str, Fraction] = _derive_costs()
#: Rows whose clocks the derived cost set reproduces by construction / cannot reproduce.
DERIVED_FROM = ("vertex_transform", "normal_transform", "normalise", "clip", "perspective_divide")
NOT_EXPLAINED = ("light", "screen_map")


def _check_counts(counts: dict) -> None:
    if not isinstance(counts, dict):
        raise RasterhwError(f"op counts must be a dict of stage -> counts, not {type(counts).__name__}")
    for stage in STAGES:
        if stage not in counts:
            raise RasterhwError(f"op counts lack stage {stage!r}")
        if not isinstance(counts[stage], dict):
            raise RasterhwError(f"op counts for {stage!r} must be a dict, not {type(counts[stage]).__name__}")
    for stage, row in counts.items():
        if not isinstance(row, dict):
            continue
        for k in OP_KINDS:
            v = row.get(k, 0)
            if (isinstance(v, bool) or not isinstance(v, (int, float, Fraction, np.integer, np.floating))
                    or not np.isfinite(float(v)) or v < 0):
                raise RasterhwError(f"op count {stage}.{k} must be a finite number >= 0, not {v!r}")


def per_triangle(counts_per_vertex: dict) -> dict:
    """Multiply a per-vertex op mix by 3 and add ``total`` (sum of all kinds)."""
    out = {}
    for stage, row in counts_per_vertex.items():
        r = {k: 3 * row.get(k, 0) for k in OP_KINDS}
        r["total"] = sum(r.values())
        out[stage] = r
    return out


def clocks_from_ops(counts: dict, cost: dict | None = None) -> dict:
    """i860 clocks per stage from per-triangle op counts: ``sum(count[k] * cost[k])``.

    ``counts`` maps every stage of :data:`STAGES` to a dict with any of :data:`OP_KINDS`
    (missing kinds count 0; extra keys such as ``total`` are ignored). Returns stage -> clocks
    (float) for every stage given, plus ``"total"`` over the paper's seven :data:`STAGES`
    (a stage the paper does not have, e.g. ``backface_cull``, gets its clocks but stays out
    of the total; a ``"total"`` stage in ``counts`` is skipped).
    """
    _check_counts(counts)
    cost = I860_COST if cost is None else cost
    out: dict[str, float] = {}
    for stage, row in counts.items():
        if stage == "total" or not isinstance(row, dict):
            continue
        out[stage] = float(sum(Fraction(row.get(k, 0)) * Fraction(cost[k]) for k in OP_KINDS))
    out["total"] = sum(out[s] for s in STAGES)
    return out


def extra_stages(counts: dict) -> list[str]:
    """Stages in ``counts`` that table 1 does not have (``total`` and non-dict entries excluded)."""
    return [s for s, r in counts.items() if s not in STAGES and s != "total" and isinstance(r, dict)]


def balance(clocks: dict, *, clock_hz: float = CLOCK_HZ, n_pipelines: int = 2) -> dict:
    """The three-processor balance: clocks per group, the bottleneck, polygons/s.

    Returns ``groups`` (name -> clocks), ``percent`` (name -> % of the total), ``bottleneck``
    (group name), ``polys_per_s_pipeline`` (``clock_hz / max group clocks``),
    ``polys_per_s_system`` (times ``n_pipelines``), ``polys_per_s_one_processor``
    (``clock_hz / total``: the whole geometry on one i860), and ``imbalance`` (max / mean).
    """
    if not clock_hz > 0:
        raise RasterhwError(f"clock_hz must be > 0, not {clock_hz!r}")
    if isinstance(n_pipelines, bool) or not isinstance(n_pipelines, int) or n_pipelines < 1:
        raise RasterhwError(f"n_pipelines must be a positive integer, not {n_pipelines!r}")
    for s in STAGES:
        if s not in clocks:
            raise RasterhwError(f"clocks lack stage {s!r}")
    groups = {g: float(sum(clocks[s] for s in ss)) for g, ss in GROUPS.items()}
    total = sum(groups.values())
    worst = max(groups, key=groups.get)
    if groups[worst] <= 0:
        raise RasterhwError("balance: every group has zero clocks")
    return {
        "groups": groups,
        "percent": {g: 100.0 * v / total for g, v in groups.items()},
        "bottleneck": worst,
        "polys_per_s_pipeline": clock_hz / groups[worst],
        "polys_per_s_system": n_pipelines * clock_hz / groups[worst],
        "polys_per_s_one_processor": clock_hz / total,
        "imbalance": groups[worst] / (total / len(groups)),
    }


def mflops(ops: dict, polys_per_s: float = 100_000) -> dict:
    """Mflops per stage to sustain ``polys_per_s``: ``ops * polys_per_s / 1e6``.

    ``ops`` maps stage -> operations per triangle (a number, or a dict with ``total``).
    """
    out = {}
    for s in STAGES:
        v = ops[s]["total"] if isinstance(ops[s], dict) else ops[s]
        out[s] = float(v) * polys_per_s / 1e6
    out["total"] = sum(out[s] for s in STAGES)
    return out


def cost_derivation() -> list[dict]:
    """Per stage: the paper's clocks, the clocks the derived costs give for the text's mix,
    the residual, and the paper's implied clocks per operation (table clocks / table ops)."""
    rows = []
    model = clocks_from_ops(per_triangle(PAPER_TEXT_COUNTS))
    for s in STAGES:
        p = PAPER_TABLE1[s]
        rows.append({"stage": s, "paper_clocks": p["clocks"], "model_clocks": model[s],
                     "residual": model[s] - p["clocks"],
                     "paper_clocks_per_op": p["clocks"] / p["ops"],
                     "explained": s in DERIVED_FROM})
    return rows


def table1_rows(measured_counts: dict | None = None, *, clock_hz: float = CLOCK_HZ) -> list[dict]:
    """Report rows for table 1 and the three-stage balance (keys of ``sim/report.py``).

    ``paper``: the paper's printed value; ``formula``: our arithmetic on the paper's *text*
    op mixes (ops) and the derived i860 costs (clocks); ``measured``: the same arithmetic on
    ``measured_counts`` (per-triangle counts from ``opcount.ops_per_triangle()``), or None.
    """
    if measured_counts is not None:
        _check_counts(measured_counts)
    text = per_triangle(PAPER_TEXT_COUNTS)
    f_clk = clocks_from_ops(text)
    m_clk = clocks_from_ops(measured_counts) if measured_counts is not None else None

    def m_ops(s):
        if measured_counts is None:
            return None
        r = measured_counts[s]
        return float(r["total"]) if "total" in r else float(sum(r.get(k, 0) for k in OP_KINDS))

    rows: list[dict] = []

    def row(quantity, paper, formula, measured, unit, figure="table 1"):
        rows.append({"system": "snu", "figure": figure, "quantity": quantity, "paper": paper,
                     "formula": formula, "measured": measured, "unit": unit, "source": "golden"})

    for s in STAGES:
        p = PAPER_TABLE1[s]
        row(f"{s}: operations per triangle", p["ops"], float(text[s]["total"]), m_ops(s), "ops")
        row(f"{s}: i860 clocks per triangle", p["clocks"], f_clk[s],
            None if m_clk is None else m_clk[s], "clocks")
        row(f"{s}: share of clocks", p["percent"], 100 * f_clk[s] / f_clk["total"],
            None if m_clk is None else 100 * m_clk[s] / m_clk["total"], "%")
    for s in extra_stages(measured_counts or {}):
        row(f"{s}: operations per triangle (not in the paper)", None, None, m_ops(s), "ops")
        row(f"{s}: i860 clocks per triangle (not in the paper)", None, None, m_clk[s], "clocks")
    row("total operations per triangle", PAPER_TOTAL_OPS, float(sum(text[s]["total"] for s in STAGES)),
        None if measured_counts is None else sum(m_ops(s) for s in STAGES), "ops")
    row("total i860 clocks per triangle", PAPER_TOTAL_CLOCKS, f_clk["total"],
        None if m_clk is None else m_clk["total"], "clocks")
    f_mf = mflops(text)
    m_mf = mflops({s: m_ops(s) for s in STAGES}) if measured_counts is not None else None
    for s in STAGES:
        row(f"{s}: Mflops for 100 K polygons/s", PAPER_MFLOPS[s], f_mf[s],
            None if m_mf is None else m_mf[s], "Mflops", figure="text 4.2")
    paper_bal = balance({s: PAPER_TABLE1[s]["clocks"] for s in STAGES}, clock_hz=clock_hz)
    f_bal = balance(f_clk, clock_hz=clock_hz)
    m_bal = balance(m_clk, clock_hz=clock_hz) if m_clk is not None else None
    for g in GROUPS:
        # The paper prints no group sums; "paper" is the sum of its own table 1 clocks.
        row(f"{g}: clocks per triangle (sum of table 1)", paper_bal["groups"][g], f_bal["groups"][g],
            None if m_bal is None else m_bal["groups"][g], "clocks", figure="text 4.5")
    row(f"polygons/s per 3-processor pipeline at {clock_hz / 1e6:g} MHz (assumed clock)",
        None, f_bal["polys_per_s_pipeline"], None if m_bal is None else m_bal["polys_per_s_pipeline"],
        "polygons/s", figure="text 4.5")
    row("geometry-bound polygons/s, 2 pipelines of 3 i860s (paper: 100 K target)", 100_000,
        f_bal["polys_per_s_system"],
        None if m_bal is None else m_bal["polys_per_s_system"], "polygons/s", figure="abstract")
    return rows
