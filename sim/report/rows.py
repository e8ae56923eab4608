"""Report framework: every reproduced paper figure as a row, paper beside measured.

A row is a dict with the keys of :data:`ROW_KEYS`:

``system``    which machine (``snu``, ``zbm``, ...)
``figure``    where the paper gives it (``table 1``, ``fig. 4.1``, ``text 3.2``)
``quantity``  what it is, in words
``paper``     the paper's value (``None`` where the paper gives none)
``formula``   our closed-form value from the paper's own formula (``None`` if there is none)
``measured``  the value our model produced when this report ran — never typed in
``unit``      unit of the three values
``source``    what produced ``measured`` in this run: ``golden`` (a golden model ran), ``model`` / ``model:NAME`` (a cost
              or timing model ran, e.g. on counted operations; NAME = which model or machine), ``formula`` (arithmetic on other
              values), ``fit:NAME`` (a model calibrated on NAME, e.g. ``fit:table2``: shown as a fit, never as
              agreement), ``hdl:pysim``, ``hdl:verilator``, ``hdl:icarus`` (the HDL was simulated),
              ``hdl:yosys`` / ``hdl:nextpnr`` (the generated Verilog was synthesised / placed); ``not run``
              (:data:`NOT_RUN`): this run left the row's simulation or synthesis out (``--fast``, rows-only),
              so nothing produced it; ``source_when_run`` then names what measures it in a run that does

Each machine names a function ``rows(engine, progress, out_dir, **known) -> (rows, sections)``
in its registry entry (``Machine.report``); reports not tied to one machine are named in
:data:`EXTRA_REPORTS` (``fpga``: place and route of every machine's blocks; ``mutation``: mutation coverage and proofs). :func:`run_report`
runs it, writes ``docs/reproduction/SYSTEM.md`` with the table (plus a ratio column) and
whatever plots the system drew.

Reports never shrink silently. A row that cannot be measured in this run stays, with
``measured`` ``None`` and a ``reason`` (listed under the table); a tool that is missing fails
the report with one line naming it (:class:`~rasterhw.sim.flow.tools.ToolUnavailable`). And
:func:`run_report` refuses to overwrite a committed table with one that lacks any of its rows
(:func:`row_key`: figure and quantity, numbers in the label ignored). A rows function that
takes ``fast`` returns its slow rows (synthesis, place and route) unmeasured when
``fast=True``: ``tests/test_reports_committed.py`` regenerates every report that way and
compares it with the committed tables.
"""

from __future__ import annotations

import inspect
import math
import re
from collections import Counter
from collections.abc import Callable
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError

ROW_KEYS = ("system", "figure", "quantity", "paper", "formula", "measured", "unit", "source")
SOURCES = ("golden", "model", "formula", "hdl:pysim", "hdl:verilator", "hdl:icarus", "hdl:yosys",
           "hdl:nextpnr")

#: reports not tied to one machine: name -> "module:rows"
EXTRA_REPORTS: dict[str, str] = {"fpga": "rasterhw.sim.report.fpga:rows",
                                 "mutation": "rasterhw.sim.report.mutation:rows"}

#: ``source`` of a row whose run this report left out (``make_row(..., run=False)``): nothing produced
#: ``measured``; the row's ``source_when_run`` names what does in a run that measures it
NOT_RUN = "not run"
#: ``reason`` of a row a fast run leaves unmeasured
FAST_SKIP = "slow row: not measured in a fast run (rasterhw report without --fast measures it)"
#: ``reason`` of a row a rows-only run leaves unmeasured (:func:`run_report`'s ``rows_only``)
ROWS_ONLY = ("rows-only run: nothing simulated or synthesised (a check of the row names, paper values and "
             "formulas; rasterhw report measures it)")


def make_row(system: str, figure: str, quantity: str, *, paper, formula, measured, unit: str,
             source: str, reason: str | None = None, run: bool = True) -> dict:
    """Build one row, checking the source label (one of :data:`SOURCES`, ``model:NAME``, or two of
    them joined by ``" + "`` when both produced the value; ``fit:NAME`` for a calibration).

    ``measured=None`` needs a ``reason`` (why this run could not measure it): a row is never
    dropped for lack of a tool or of time, it is kept unmeasured. ``run=False``: this run left
    out what measures the row (``--fast``, rows-only; ``measured`` must be None): its ``source`` is
    :data:`NOT_RUN` and ``source_when_run`` keeps ``source`` (what measures it in a run that does).
    """
    # a value two models produced together names both, joined by " + " (e.g. an HDL frame whose
    # producers' timing is a processor model: "hdl:verilator + model:i860")
    for part in source.split(" + "):
        if part not in SOURCES and not (part.startswith(("model:", "fit:")) and part.split(":", 1)[1]):
            raise ValueError(f"source must be one of {SOURCES}, model:NAME or fit:NAME (or two joined by "
                             f"' + '), not {source!r}")
    if measured is None and not reason:
        raise ValueError(f"row {quantity!r}: measured is None, so say why (reason=...)")
    if not run and measured is not None:
        raise ValueError(f"row {quantity!r}: not run, yet measured is {measured!r}")
    row = {"system": system, "figure": figure, "quantity": quantity, "paper": paper,
           "formula": formula, "measured": measured, "unit": unit, "source": source if run else NOT_RUN}
    if not run:
        row["source_when_run"] = source
    if reason:
        row["reason"] = reason
    return row


def row_key(row: dict) -> tuple[str, str, str]:
    """What identifies a row across runs: system, figure and quantity with its numbers masked
    (labels such as "mean segment 12.5 px" carry measured values; whole numbers such as
    "interleave 8" are kept)."""
    q = re.sub(r"\d+(?:[.,]\d+)+", "#", row["quantity"])
    return row["system"], row["figure"], q


def parse_table(text: str) -> list[dict]:
    """The first report table of a ``docs/reproduction/SYSTEM.md``, as rows of strings."""
    lines = text.splitlines()
    head = ["system", "figure", "quantity", "paper", "formula", "measured", "ratio", "unit", "source"]
    try:
        start = next(i for i, ln in enumerate(lines)
                     if [c.strip() for c in ln.strip().strip("|").split("|")] == head)
    except StopIteration:
        return []
    out = []
    for ln in lines[start + 2:]:
        if not ln.startswith("|"):
            break
        cells = [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", ln.strip())[1:-1]]
        out.append(dict(zip(head, cells, strict=True)))
    return out


def missing_rows(old: list[dict], new: list[dict]) -> list[dict]:
    """Rows of ``old`` (e.g. the committed table) that ``new`` lacks, by :func:`row_key`."""
    have = Counter(row_key(r) for r in new)
    out = []
    for r in old:
        k = row_key(r)
        if have[k]:
            have[k] -= 1
        else:
            out.append(r)
    return out


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
    """Every report: each machine with one (the registry's order), then :data:`EXTRA_REPORTS`."""
    from rasterhw.sim.registry import machines

    return [m.name for m in machines().values() if m.report] + list(EXTRA_REPORTS)


def _load(system: str) -> Callable:
    from rasterhw.sim.registry import load, machine

    if system in EXTRA_REPORTS:
        return load(EXTRA_REPORTS[system])
    m = machine(system)
    if not m.report:
        raise RasterhwError(f"machine {system!r} has no report; reports: {', '.join(systems())}")
    return load(m.report)


def default_report_dir() -> Path:
    """Where ``rasterhw report`` writes unless ``--out`` says: the checkout's
    ``docs/reproduction/`` when this package runs from a checkout (``pyproject.toml`` beside it),
    wherever the command is started; otherwise (an installed wheel) ``reports/`` in the cache
    folder (``$RASTERHW_CACHE``, else the user's cache folder: ``sim/paths.py``), never the
    current folder."""
    from rasterhw.sim.paths import BUILD_ROOT, REPO_ROOT

    if (REPO_ROOT / "pyproject.toml").is_file() and (REPO_ROOT / "docs" / "reproduction").is_dir():
        return REPO_ROOT / "docs" / "reproduction"
    return BUILD_ROOT / "reports"


def run_report(system: str, *, out_dir: Path = Path("docs/reproduction"), engine: str = "pysim",
               progress: bool = False, fast: bool = False, scheduler: str = "serial",
               store: str | Path | None = None, fresh: bool = False, rows_only: bool = False,
               **known) -> list[dict]:
    """Measure every row of SYSTEM, write ``out_dir/SYSTEM.md`` and its plots, return the rows.

    ``fast``: slow rows are kept unmeasured (for systems whose rows function takes ``fast``).
    ``rows_only``: no HDL is simulated or synthesised, every such row is kept unmeasured with
    :data:`ROWS_ONLY` (the golden, model and formula rows are computed as always), for systems
    whose rows function takes ``rows_only``; it implies ``fast``. The committed-report tests
    check row names, paper values and formulas this way.
    ``scheduler``, ``store``, ``fresh``: where a rows function that runs a list of independent
    simulations (it takes ``scheduler``) runs them, and where their results are kept
    (``sim/flow/tasks.py: run_tasks``; ``serial`` and no store unless the caller says:
    ``rasterhw report`` passes ``--scheduler``, default ``local``, and the store ``build/tasks``).
    Raises ``RasterhwError`` (and writes nothing) if ``out_dir/SYSTEM.md`` exists and has a
    row this run did not produce. Keyword arguments beyond these are passed to the system's
    rows function (see its docstring).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fn = _load(system)
    takes = inspect.signature(fn).parameters
    if (fast or rows_only) and "fast" in takes:
        known["fast"] = True
    if rows_only and "rows_only" in takes:
        known["rows_only"] = True
    if "scheduler" in takes:
        known.update(scheduler=scheduler, store=store, fresh=fresh)
    # ``known``: results the caller already measured in this run (e.g. the demo's snu-100px
    # simulation), handed to the system's rows function so the work is not done twice
    rows, sections = fn(engine=engine, progress=progress, out_dir=out_dir, **known)
    for r in rows:
        missing = [k for k in ROW_KEYS if k not in r]
        if missing:
            raise ValueError(f"report row lacks {missing}: {r}")
        if r["measured"] is None and not r.get("reason"):
            raise ValueError(f"report row {r['quantity']!r} is unmeasured and says not why")
    path = out_dir / f"{system}.md"
    if path.exists():
        lost = missing_rows(parse_table(path.read_text()), rows)
        if lost:
            raise RasterhwError(
                f"report {system} would drop {len(lost)} row(s) of {path}, first: "
                f"{lost[0]['figure']} / {lost[0]['quantity']}; a row that cannot be measured stays "
                "(measured None, with the reason); delete the file to accept a smaller table")
    unmeasured = [r for r in rows if r["measured"] is None]
    ran = sorted({r["source"] for r in rows if str(r["source"]).startswith("hdl:")})
    md = [f"# Reproduction: {system}", "",
          f"Generated by `rasterhw report {system}` (simulator requested for HDL rows: `{engine}`; "
          f"HDL rows in this run came from: {', '.join(f'`{s}`' for s in ran) or 'none'}; "
          "each row's `source` names the model that measured it). "
          "`paper` is the paper's value, `formula` our value from the paper's own formula, "
          "`measured` what our model produced in this run (`source` says which model). "
          "Do not edit by hand: run the command again.", "",
          format_table(rows, markdown=True), ""]
    if unmeasured:
        md += ["Not measured in this run (the rows stay, `measured` is empty):", ""]
        md += [f"- {r['figure']} / {r['quantity']}: {r['reason']}" for r in unmeasured]
        md += [""]
    md += sections
    path.write_text("\n".join(md) + "\n")
    return rows
