"""The SNU paper's table 1 (seed 004, "표 1") as printed, and our pipeline's counts beside it:
:func:`paper_comparison`. Kept apart from the counting code (``golden_model/opcount.py``), which
never reads it."""

from __future__ import annotations

from rasterhw.golden_model.opcount import CATEGORIES
from rasterhw.golden_model.snu.paper import PAPER_TABLE1
from rasterhw.golden_model.triangle_ops import ops_per_triangle

__all__ = ["PER_VERTEX_TEXT", "TABLE1", "paper_comparison"]

#: The paper's table 1 (seed 004, "표 1"): stage -> (operations per triangle, i860 clocks), from
#: :data:`rasterhw.golden_model.snu.paper.PAPER_TABLE1`.
TABLE1: dict[str, tuple[int, int]] = {s: (int(v["ops"]), int(v["clocks"])) for s, v in PAPER_TABLE1.items()}

#: What the paper's text (section 4.2.1-4.2.5) says each stage does per vertex.
PER_VERTEX_TEXT: dict[str, str] = {
    "vertex_transform": "4x4 matrix, w fixed at 1.0: 12 mul + 12 add",
    "normal_transform": "3x3 matrix: 9 mul + 6 add",
    "normalise": "3 mul + 2 add (sum of squares), 1 sqrt + 1 recip (counted as 2), 3 mul",
    "light": "12 mul + 10 add + 3 compares + 1 table lookup (= 26, table says 24)",
    "clip": "6 compares (= 18 per triangle, table says 24)",
    "perspective_divide": "1 recip + 3 mul",
    "screen_map": "3 mul + 2 add (one more add if y or z is flipped)",
}


def paper_comparison(
    counts: dict[str, dict[str, int]] | None = None,
) -> list[tuple[str, int | None, int, str]]:
    """Rows (stage, paper ops per triangle or None, our measured ops, our breakdown)."""
    counts = ops_per_triangle() if counts is None else counts
    rows = []
    for stage, c in counts.items():
        if stage == "total":
            continue
        paper = TABLE1.get(stage, (None, None))[0]
        parts = " + ".join(f"{c[k]} {k}" for k in CATEGORIES if c[k])
        rows.append((stage, paper, c["total"], parts or "0"))
    rows.append(("total", sum(v[0] for v in TABLE1.values()), counts["total"]["total"], ""))
    return rows
