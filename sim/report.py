"""Report framework: every reproduced paper figure as a row, paper beside measured.

A row is a dict with the keys of :data:`ROW_KEYS`:

``system``    which machine (``snu``, ``zbm``, ...)
``figure``    where the paper gives it (``table 1``, ``fig. 4.1``, ``text 3.2``)
``quantity``  what it is, in words
``paper``     the paper's value (``None`` where the paper gives none)
``formula``   our closed-form value from the paper's own formula (``None`` if there is none)
``measured``  the value our model produced when this report ran — never typed in
``unit``      unit of the three values
``source``    what produced ``measured`` in this run: ``golden`` (a golden model ran), ``model`` (a cost
              or timing model ran, e.g. on counted operations), ``formula`` (arithmetic on other
              values), ``hdl:pysim``, ``hdl:verilator``, ``hdl:icarus`` (the HDL was simulated),
              ``hdl:yosys`` / ``hdl:nextpnr`` (the generated Verilog was synthesised / placed)

Each machine names a function ``rows(engine, progress, out_dir, **known) -> (rows, sections)``
in its registry entry (``Machine.report``); :func:`run_report` runs it, writes ``docs/reproduction/SYSTEM.md`` with the
table (plus a ratio column) and whatever plots the system drew.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

ROW_KEYS = ("system", "figure", "quantity", "paper", "formula", "measured", "unit", "source")
SOURCES = ("golden", "model", "formula", "hdl:pysim", "hdl:verilator", "hdl:icarus", "hdl:yosys",
           "hdl:nextpnr")

def make_row(system: str, figure: str, quantity: str, *, paper, formula, measured, unit: str,
             source: str) -> dict:
    """Build one row, checking the source label."""
    if source not in SOURCES:
        raise ValueError(f"source must be one of {SOURCES}, not {source!r}")
    return {"system": system, "figure": figure, "quantity": quantity, "paper": paper,
            "formula": formula, "measured": measured, "unit": unit, "source": source}


def ratio(row: dict) -> float | None:
    """measured / paper, when both are numbers and paper is not zero."""
    p, m = row.get("paper"), row.get("measured")
    if isinstance(p, (int, float)) and isinstance(m, (int, float)) and p:
        return m / p
    return None


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if v != 0 and (abs(v) >= 1e6 or abs(v) < 1e-3):
            return f"{v:.4g}"
        return f"{v:,.4g}" if abs(v) >= 1000 else f"{v:.4g}"
    if isinstance(v, int):
        return f"{v:,}"
    return str(v)


def format_table(rows: list[dict], *, markdown: bool = False) -> str:
    """Rows as a plain-text (or Markdown) table with a ratio column."""
    head = ["system", "figure", "quantity", "paper", "formula", "measured", "ratio", "unit", "source"]
    body = []
    for r in rows:
        q = ratio(r)
        body.append([r["system"], r["figure"], r["quantity"], _fmt(r["paper"]), _fmt(r["formula"]),
                     _fmt(r["measured"]), "—" if q is None else f"{q:.3f}", r["unit"], r["source"]])
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in body]
        return "\n".join(lines)
    widths = [max(len(h), *(len(row[i]) for row in body)) if body else len(h) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return "\n".join([fmt.format(*head), fmt.format(*("-" * w for w in widths))] +
                     [fmt.format(*row) for row in body])


def systems() -> list[str]:
    """Every machine with a report (the registry's order)."""
    from rasterhw.sim.registry import machines

    return [m.name for m in machines().values() if m.report]


def _load(system: str) -> Callable:
    from rasterhw.sim.registry import load, machine

    m = machine(system)
    if not m.report:
        from rasterhw.golden_model.errors import RasterhwError

        raise RasterhwError(f"machine {system!r} has no report; reports: {', '.join(systems())}")
    return load(m.report)


def run_report(system: str, *, out_dir: Path = Path("docs/reproduction"), engine: str = "pysim",
               progress: bool = False, **known) -> list[dict]:
    """Measure every row of SYSTEM, write ``out_dir/SYSTEM.md`` and its plots, return the rows.

    Keyword arguments beyond these are passed to the system's rows function (see its docstring).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    # ``known``: results the caller already measured in this run (e.g. the demo's snu-100px
    # simulation), handed to the system's rows function so the work is not done twice
    rows, sections = _load(system)(engine=engine, progress=progress, out_dir=out_dir, **known)
    for r in rows:
        missing = [k for k in ROW_KEYS if k not in r]
        if missing:
            raise ValueError(f"report row lacks {missing}: {r}")
    ran = sorted({r["source"] for r in rows if str(r["source"]).startswith("hdl:")})
    md = [f"# Reproduction: {system}", "",
          f"Generated by `rasterhw report {system}` (simulator requested for HDL rows: `{engine}`; "
          f"HDL rows in this run came from: {', '.join(f'`{s}`' for s in ran) or 'none'}; "
          "each row's `source` names the model that measured it). "
          "`paper` is the paper's value, `formula` our value from the paper's own formula, "
          "`measured` what our model produced in this run (`source` says which model). "
          "Do not edit by hand: run the command again.", "",
          format_table(rows, markdown=True), ""]
    md += sections
    (out_dir / f"{system}.md").write_text("\n".join(md) + "\n")
    return rows
