"""SNU graphics system: table 1 (operations and i860 clocks per triangle) and the stage balance.

Seed 004, section 4.5 (translated): "The processing times of the algorithms computed above are
summarised in table 1. The operation count is the number of real additions and real
multiplications one polygon needs, and the real processing time is the number of clocks it
takes when executed on the i860. On this basis, assuming a graphics pipeline of three i860
processors, the first processor is given vertex transform and normal-vector transform, the
second normal-vector normalisation and lighting, the last clipping, projection and screen
mapping."

This module holds the paper's table as labelled constants, the per-vertex operation mix the
paper's *text* (4.2.1-4.2.5) gives for each stage, and the arithmetic that turns counts and
clocks into the three-processor balance, the Mflops column and report rows. The counts come
from running the golden geometry (``golden_model/snu/recipe.py``, ``golden_model/opcount.py``);
the clocks from the i860 timing model (``golden_model/snu/i860.py``), which takes nothing from
the table.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu.paper import (
    PAPER_MFLOPS,
    PAPER_TABLE1,
    PAPER_TEXT_COUNTS,
    PAPER_TOTAL_CLOCKS,
    PAPER_TOTAL_OPS,
)

__all__ = [
    "CLOCK_HZ",
    "GROUPS",
    "OP_KINDS",
    "PAPER_TABLE1",
    "PAPER_TEXT_COUNTS",
    "STAGES",
    "balance",
    "extra_stages",
    "mflops",
    "per_triangle",
    "table1_rows",
]

#: Stage names, in table 1 order (``perspective_divide`` is the paper's "projection").
STAGES = ("vertex_transform", "normal_transform", "normalise", "light", "clip",
          "perspective_divide", "screen_map")
OP_KINDS = ("mul", "add", "cmp", "div", "sqrt", "lookup", "cvt")

# table 1, its totals and the text's Mflops: golden_model/snu/paper.py (quotes and locations there)

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


def table1_rows(recipe_counts: dict, full_counts: dict | None = None, model: dict | None = None, *,
                clock_hz: float = CLOCK_HZ, compiler: dict | None = None) -> list[dict]:
    """Report rows for table 1 and the three-stage balance (keys of ``sim/report/rows.py``).

    ``recipe_counts``: per-triangle counts of the paper's recipe (``recipe.ops_per_triangle()``),
    rows ``source="golden"``: ``paper`` = table 1, ``formula`` = the text's per-vertex mix x 3,
    ``measured`` = the recipe's counted operations. ``full_counts``: the same for our full
    pipeline (``opcount.ops_per_triangle()``). ``model``: ``i860.table1_model()`` (the assembler
    schedule), ``compiler``: ``i860.table1_model(mode="compiler")``; their clock rows are
    ``source="model:i860"``: ``paper`` = table 1's clocks, ``measured`` = the i860 model's clocks
    (nothing in the model is taken from the table).
    """
    _check_counts(recipe_counts)
    if full_counts is not None:
        _check_counts(full_counts)
    text = per_triangle(PAPER_TEXT_COUNTS)
    rows: list[dict] = []

    def row(quantity, paper, formula, measured, unit, figure="table 1", source="golden"):
        rows.append({"system": "snu", "figure": figure, "quantity": quantity, "paper": paper,
                     "formula": formula, "measured": measured, "unit": unit, "source": source})

    def tot(r):
        return float(r["total"]) if "total" in r else float(sum(r.get(k, 0) for k in OP_KINDS))

    for s in STAGES:
        row(f"{s}: operations per triangle, paper's recipe (formula = the text)", PAPER_TABLE1[s]["ops"],
            float(text[s]["total"]), tot(recipe_counts[s]), "ops")
    row("total operations per triangle, paper's recipe", PAPER_TOTAL_OPS,
        float(sum(text[s]["total"] for s in STAGES)), sum(tot(recipe_counts[s]) for s in STAGES), "ops")
    if full_counts is not None:
        for s in STAGES:
            row(f"{s}: operations per triangle, our full pipeline", PAPER_TABLE1[s]["ops"], None,
                tot(full_counts[s]), "ops")
        for s in extra_stages(full_counts):
            row(f"{s}: operations per triangle, our full pipeline (not in the paper)", None, None,
                tot(full_counts[s]), "ops")
        row("total operations per triangle, our full pipeline", PAPER_TOTAL_OPS, None,
            sum(tot(full_counts[s]) for s in STAGES), "ops")
    m_mf = mflops({s: tot(recipe_counts[s]) for s in STAGES})
    for s in STAGES:
        row(f"{s}: Mflops for 100 K polygons/s, paper's recipe", PAPER_MFLOPS[s],
            float(text[s]["total"]) * 0.1, m_mf[s], "Mflops", figure="text 4.2")
    if model is None:
        return rows
    src = "model:i860"
    clk = {s: float(model[s]["clocks"]) for s in STAGES}
    total = sum(clk.values())
    for s in STAGES:
        row(f"{s}: i860 clocks per triangle (i860 model, assembler schedule, one triangle)",
            PAPER_TABLE1[s]["clocks"], None, clk[s], "clocks", source=src)
        if compiler is not None:
            row(f"{s}: i860 clocks per triangle (i860 model, compiler schedule, one triangle)",
                PAPER_TABLE1[s]["clocks"], None, float(compiler[s]["clocks"]), "clocks", source=src)
        row(f"{s}: share of clocks (i860 model, assembler schedule)", PAPER_TABLE1[s]["percent"], None,
            100 * clk[s] / total, "%", source=src)
    row("total i860 clocks per triangle (i860 model, assembler schedule, scheduling window 1 triangle: each stage "
        "scheduled for one triangle, as table 1 reads 'the clocks one polygon takes on the i860'; the default)",
        PAPER_TOTAL_CLOCKS, None, total, "clocks", source=src)
    diff = {s: clk[s] - PAPER_TABLE1[s]["clocks"] for s in STAGES}
    row("per-stage absolute error, sum over the seven stages of |model - paper| (assembler schedule, scheduling "
        "window 1 triangle)", None, None, float(sum(abs(v) for v in diff.values())), "clocks", source=src)
    row("net total error, model total - paper total (assembler schedule, scheduling window 1 triangle; stage "
        "errors of both signs cancel in it)", None, None, float(sum(diff.values())), "clocks", source=src)
    if compiler is not None:
        row("total i860 clocks per triangle (i860 model, compiler schedule, one triangle per stage)",
            PAPER_TOTAL_CLOCKS, None, float(sum(compiler[s]["clocks"] for s in STAGES)), "clocks", source=src)
    if model["total"].get("stream") is not None:
        row("total i860 clocks per triangle (i860 model, assembler schedule, scheduling window 8 triangles "
            "scheduled together; the paper states no window)", PAPER_TOTAL_CLOCKS, None,
            float(model["total"]["stream"]), "clocks", source=src)
    paper_bal = balance({s: PAPER_TABLE1[s]["clocks"] for s in STAGES}, clock_hz=clock_hz)
    m_bal = balance(clk, clock_hz=clock_hz)
    for g in GROUPS:
        # The paper prints no group sums: the sum of its own table 1 clocks is a formula, derived
        row(f"{g}: clocks per triangle (formula = sum of the paper's table 1 clocks, derived; assembler schedule)",
            None, paper_bal["groups"][g], m_bal["groups"][g], "clocks", figure="text 4.5", source=src)
    row(f"polygons/s per 3-processor pipeline at {clock_hz / 1e6:g} MHz (assumed clock; formula = the paper's "
        "table 1 clocks, derived; assembler schedule)", None, paper_bal["polys_per_s_pipeline"],
        m_bal["polys_per_s_pipeline"], "polygons/s", figure="text 4.5", source=src)
    row("geometry-bound polygons/s, 2 pipelines of 3 i860s (paper: 100 K target; assembler schedule)", 100_000,
        None, m_bal["polys_per_s_system"], "polygons/s", figure="abstract", source=src)
    return rows
