"""``rasterhw report fpga``: the table ``docs/reproduction/fpga.md`` from place and route
(:mod:`rasterhw.sim.flow.fpga`) of every block at its paper's size, labelled reduced sizes and
each machine's parameter sweeps. A report not tied to one machine (``EXTRA_REPORTS`` in
:mod:`rasterhw.sim.report.rows`); the runs are the flow's, the rows and plots are this module's.
"""

from __future__ import annotations

from pathlib import Path

from rasterhw.sim import registry
from rasterhw.sim.flow.fpga import (
    DEVICE_NAMES,
    FALLBACK_ROUTER,
    ROUTER,
    RUN_RECORD,
    fpga_configs,
    fpga_sweeps,
    not_measured_reason,
    paper_clock,
    place_and_route,
    recorded_config,
    synth_demand,
    write_run_record,
)
from rasterhw.sim.registry import FpgaSweep
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import FAST_SKIP, make_row

__all__ = ["ICE40_CONFIGS", "REPORT_TIMEOUT_S", "rows", "sweep_plot"]


#: what the report also places on an iCE40 HX8K: nothing. nextpnr-ice40 has no out-of-context
#: mode, so every port bit of a block takes an I/O pin, and the blocks have more port bits than the
#: HX8K's largest package has pins (the EXPERTS DMM alone: 397 SB_IO against 206 on the CT256);
#: a pin-light wrapper (ports through shift registers) would measure the wrapper, not the block.
#: ``rasterhw fpga BLOCK --family ice40`` still runs one block that way.
ICE40_CONFIGS: tuple[tuple[str, dict, str], ...] = ()


#: nextpnr time limit per run of the report (a run that takes longer stays unmeasured, with why)
REPORT_TIMEOUT_S = 2400.0


#: parameters left out of a row's label (not sizes)
_UNLABELLED = {"ram", "schedule", "head", "index", "chip", "aj", "alpha", "beta", "mem_cycle",
               "intensity_bits", "z_bits", "colour_bits", "colour", "kp", "ke"}


def _cfg(block: str, params: dict, kind: str) -> str:
    """Row label: ``full``/``reduced`` and the block's size parameters (defaults filled in), each
    value in the words its machine gives it (``Flow.labels``, e.g. which datapath) or as ``name value``;
    a parameter that is not a size (``_UNLABELLED``) is shown only where ``Flow.labels`` names it
    (the EXPERTS span PXP's anti-jagging)."""
    import inspect

    from rasterhw.sim.engines.verilog import blocks, load

    sig = inspect.signature(load(blocks()[block]))
    eff = {k: v.default for k, v in sig.parameters.items() if v.default is not inspect.Parameter.empty}
    eff.update(params)
    words = registry.flow(block).labels   # a parameter the machine names is shown, even one of _UNLABELLED
    shown = ", ".join(words.get(k, {}).get(v, f"{k} {v}") for k, v in eff.items() if k not in _UNLABELLED or k in words)
    return f"{kind}: {shown}"


_NOT_RUN = "not run in the session that made this table (time): `rasterhw fpga {block}{args}`"
_NOT_RECORDED = "no recorded run (`{record}`): `rasterhw report fpga --rerun` runs it, or `rasterhw fpga {block}{args}`"
_NOT_RECORDED_DEMAND = ("no recorded synthesis demand (`{record}`): `rasterhw report fpga --rerun` runs it, or "
                        "`rasterhw synth {block}`")


def _recorded(block, params, *, family="ecp5", record=None):
    """One configuration from the record alone (:func:`rasterhw.sim.flow.fpga.recorded_config`):
    no Verilog, no Yosys, no nextpnr; unmeasured with why where nothing is recorded."""
    from rasterhw.sim.paths import REPO_ROOT

    rec = Path(record) if record is not None else RUN_RECORD
    where = str(rec.relative_to(REPO_ROOT)) if rec.is_relative_to(REPO_ROOT) else str(rec)
    args = "".join(f" -p {k}={v}" for k, v in params.items()) + ("" if family == "ecp5" else f" --family {family}")
    if registry.flow(block).demand_from_synth and not params and family == "ecp5":
        d = recorded_config(block, {}, demand=True, record=record)
        if d is None:
            return {"block": block, "params": params, "finished": False, "luts": None, "ffs": None, "brams": None,
                    "fmax_mhz": {}, "reason": _NOT_RECORDED_DEMAND.format(record=where, block=block)}
        if d.get("finished") is False:   # a demand recorded for an earlier design
            return d
        if not d["fits"]:
            return {**d, "finished": True, "luts": None, "ffs": None, "brams": None, "fmax_mhz": {}}
    r = recorded_config(block, params, family=family, record=record)
    if r is None:
        return {"block": block, "params": params, "finished": False, "luts": None, "ffs": None, "brams": None,
                "fmax_mhz": {}, "reason": _NOT_RECORDED.format(record=where, block=block, args=args)}
    if r.pop("fallback_pending", False):
        r["display_reason"] = f"{_reason(r)}; {FALLBACK_ROUTER} " + _NOT_RUN.format(block=block, args=args)
    return r


def _measure(block, params, *, fast, progress, timeout, family="ecp5", cached_only=False):
    """One configuration: a place_and_route / synth_demand result, or None in a fast run."""
    import sys

    if fast:
        return None
    if progress:
        print(f"fpga: {block} ({params or 'defaults'}) on {family} ...", file=sys.stderr, flush=True)
    if registry.flow(block).demand_from_synth and not params and family == "ecp5":
        d = synth_demand(block)
        if d.get("finished") is False:   # a demand recorded for an earlier design
            return d
        if not d["fits"]:
            return {**d, "finished": True, "luts": None, "ffs": None, "brams": None, "fmax_mhz": {}}
    r = place_and_route(block, family=family, timeout=timeout, cached_only=cached_only, **params)
    args = "".join(f" -p {k}={v}" for k, v in params.items()) + ("" if family == "ecp5" else f" --family {family}")
    if r is None:  # cached_only and never run
        return {"block": block, "params": params, "finished": False, "reason": _NOT_RUN.format(block=block, args=args),
                "luts": None, "ffs": None, "brams": None, "fmax_mhz": {}}
    if r.pop("fallback_pending", False):
        # shown in the table; the record keeps the run's own reason
        r["display_reason"] = f"{_reason(r)}; {FALLBACK_ROUTER} " + _NOT_RUN.format(block=block, args=args)
    return r


def measure_task(block: str, *, family: str = "ecp5", timeout: float = REPORT_TIMEOUT_S, cached_only: bool = False,
                 **params) -> dict:
    """One configuration of the report as a task (``sim/flow/tasks.py``, on any worker):
    ``{"run": _measure(...)}`` (nested, so the run's own ``synth_s`` / ``pnr_s`` and build folder
    come back as the flow gave them)."""
    return {"run": _measure(block, params, fast=False, progress=False, timeout=timeout, family=family,
                            cached_only=cached_only)}


def _measure_all(configs: list[tuple[str, dict, str]], *, fast: bool, progress: bool, timeout: float,
                 cached_only: bool, scheduler: str, store, fresh: bool, record=None) -> list[dict | None]:
    """:func:`_measure` of every (block, params, family), as tasks on ``scheduler``, in order;
    ``record`` (a run record's path): every configuration from that record alone, here."""
    from rasterhw.sim.flow.tasks import call, run_tasks

    if fast:
        return [None] * len(configs)
    if record is not None:
        return [_recorded(b, params, family=fam, record=record) for b, params, fam in configs]
    tasks = [call("rasterhw.sim.report.fpga:measure_task", block=b, family=fam, timeout=timeout,
                  cached_only=cached_only, **params) for b, params, fam in configs]
    got = run_tasks(tasks, scheduler=scheduler, store=store, fresh=fresh, progress=progress,
                    desc=f"fpga: place and route ({scheduler})")
    return [g["run"] for g in got]


def _reason(r) -> str | None:
    """Why a configuration has no measurement: a fast run's skip, or the flow's reason."""
    return FAST_SKIP if r is None else not_measured_reason(r)


def _ran(r) -> bool:
    """Whether a tool produced this configuration's row in this run (a measurement, or a finding such
    as "does not fit" or a stop in the time limit); a fast run's skip or a configuration not run
    or not recorded is ``rows.NOT_RUN`` (issue 46: the row's source says what produced it)."""
    return r is not None and not (r.get("finished") is False and not r.get("stage"))


def sweep_plot(sw: FpgaSweep, points: list[tuple[object, dict]], path, missing: dict | None = None) -> None:
    """Fmax of every clock of ``sw.block`` against ``sw.param``, with the clocks the paper names;
    ``missing``: value -> why it has no point (written at the bottom of the plot)."""
    clocks = registry.flow(sw.block).clocks
    with saved_figure(path, figsize=(6, 3.6), metadata={"Software": None}) as ax:
        for c, mark in zip(clocks, ("o-", "s--", "^-.", "v:"), strict=False):
            got = [(v, r["fmax_mhz"][c.domain]) for v, r in points
                   if r.get("fmax_mhz", {}).get(c.domain) is not None]
            if got:
                ax.plot([v for v, _ in got], [f for _, f in got], mark, label=f"{c.name} (nextpnr)")
        for c in clocks:
            if c.hz is not None:
                ax.axhline(c.hz / 1e6, color="grey", lw=1, ls=":", label=f"paper: {c.name} {c.hz / 1e6:g} MHz")
        if all(isinstance(v, int) and v > 0 and v & (v - 1) == 0 for v in sw.values):
            ax.set_xscale("log", base=2)
            ax.set_xlim(min(sw.values) * 0.8, max(sw.values) * 1.25)
        ax.set_xticks(list(sw.values), [str(v) for v in sw.values])
        ax.set_xlabel(sw.xlabel)
        ax.set_ylabel("Fmax (MHz)")
        ax.set_ylim(bottom=0)
        for v, why in (missing or {}).items():
            ax.annotate(why, (v, 0), xytext=(0, 4), textcoords="offset points", rotation=90, fontsize=7,
                        ha="center", va="bottom", color="firebrick")
        ax.set_title(sw.title, fontsize=9)
        ax.legend(fontsize=8)


def _sweep_label(sw: FpgaSweep) -> str:
    """``width 512``: the fixed parameters of a sweep, for its row group."""
    return ", ".join(f"{k} {v}" for k, v in sw.base.items())


def rows(*, engine: str = "pysim", progress: bool = False, out_dir, fast: bool = False,
         timeout: float = REPORT_TIMEOUT_S, cached_only: bool = False, records_only: bool = False,
         scheduler: str = "serial", store=None, fresh: bool = False):
    """Report rows: per configuration of :func:`fpga_configs`, ECP5 LUTs, flip-flops, block RAMs,
    multiplier blocks and Fmax per clock beside the paper's clock (``source`` ``hdl:nextpnr``; a full frame memory
    measured by synthesis: ``hdl:yosys``), and each sweep of :func:`fpga_sweeps` (the ZB/M chip's
    Fmax at each interleave) with a plot. ``fast``: the rows stay, unmeasured (place and route takes
    minutes to an hour per block). ``cached_only``: use the results cached in ``build/pnr-*`` and
    the record whose digests match the design as it is now (its Verilog is generated, the tools
    asked their versions; a demand measured by synthesis runs Yosys) and place nothing.
    ``records_only`` (``rasterhw report fpga`` without ``--rerun``): every configuration from the
    run record alone (``out_dir/fpga_runs.json`` if there is one, else the checkout's): no Verilog,
    no tool runs; a configuration not recorded stays unmeasured, saying so. Every configuration is
    one task on ``scheduler`` (``rasterhw report fpga --scheduler``: the place-and-route queue on a
    Dask cluster; ``sim/flow/tasks.py``), results in this order."""
    from pathlib import Path

    configs = [(b, p, "ecp5") for b, p, _ in fpga_configs()] + [(b, p, "ice40") for b, p, _ in ICE40_CONFIGS]
    configs += [(sw.block, {sw.param: v, **sw.base}, "ecp5") for sw in fpga_sweeps() for v in sw.values]
    record = None
    if records_only and not fast:
        record = Path(out_dir) / RUN_RECORD.name if (Path(out_dir) / RUN_RECORD.name).exists() else RUN_RECORD
    measured = _measure_all(configs, fast=fast, progress=progress, timeout=timeout, cached_only=cached_only,
                            scheduler=scheduler, store=store, fresh=fresh, record=record)
    out = []
    dev = DEVICE_NAMES["ecp5"]["85k"]
    walls = []
    for block, params, kind in fpga_configs():
        r = measured.pop(0)
        why = _reason(r)
        ok = why is None
        system = registry.block_machine(block).name
        fig = f"{block} on {dev} ({_cfg(block, params, kind)})"
        src = "hdl:yosys" if (r is not None and "ram_bits" in r and "utilization" not in r) else "hdl:nextpnr"
        ran = _ran(r)

        def row(q, measured, unit, paper=None, fig=fig, system=system, why=why, src=src, ran=ran):
            return make_row(system, fig, q, paper=paper, formula=None, measured=measured, unit=unit,
                            source=src, reason=why, run=ran)

        out += [row("LUT4s", r["luts"] if ok else None, "LUT4"),
                row("flip-flops", r["ffs"] if ok else None, "flip-flops"),
                row("block RAMs (DP16KD, 18 Kbit)", r["brams"] if ok else None, "DP16KD"),
                row("multiplier blocks (MULT18X18D, 18 x 18)", r.get("dsps") if ok else None, "MULT18X18D")]
        for dom, what, hz in paper_clock(block):
            f = r["fmax_mhz"].get(dom) if ok else None
            if ok and f is None:
                continue  # the block has no such clock (e.g. the loop has no merge clock)
            out.append(row(f"Fmax, {dom} clock (paper: {what})", f, "MHz",
                           paper=None if hz is None else hz / 1e6))
        if r is not None:
            walls.append((block, params, kind, r))

    ice = DEVICE_NAMES["ice40"]["hx8k"]
    for block, params, kind in ICE40_CONFIGS:
        r = measured.pop(0)
        why = _reason(r)
        ok = why is None
        system = registry.block_machine(block).name
        fig = f"{block} on {ice} ({_cfg(block, params, kind)})"
        ran = _ran(r)

        def row(q, measured, unit, paper=None, fig=fig, system=system, why=why, ran=ran):
            return make_row(system, fig, q, paper=paper, formula=None, measured=measured, unit=unit,
                            source="hdl:nextpnr", reason=why, run=ran)

        out += [row("logic cells (ICESTORM_LC)", r["luts"] if ok else None, "LC"),
                row("flip-flops", r["ffs"] if ok else None, "flip-flops"),
                row("block RAMs (4 Kbit)", r["brams"] if ok else None, "ICESTORM_RAM")]
        for dom, what, hz in paper_clock(block):
            f = r["fmax_mhz"].get(dom) if ok else None
            if ok and f is None:
                continue
            out.append(row(f"Fmax, {dom} clock (paper: {what})", f, "MHz",
                           paper=None if hz is None else hz / 1e6))
        if r is not None:
            walls.append((block, params, kind + ", iCE40 HX8K", r))

    sweep, plots = [], []
    for sw in fpga_sweeps():
        clocks = registry.flow(sw.block).clocks
        figure = f"{sw.block} Fmax against {sw.param} on {dev} ({_sweep_label(sw)})"
        points, missing = [], {}
        for v in sw.values:
            r = measured.pop(0)
            why = _reason(r)
            if r is not None:
                sweep.append(r)
            if why is None:
                points.append((v, r))
            elif r is not None:
                missing[v] = ("did not finish" if r.get("finished") is False and r.get("stage") else
                              "not run" if r.get("finished") is False else "does not fit")
                if r.get("stage"):
                    missing[v] += f" in {r['timeout_s'] / 60:.0f} min"
            for c in clocks:
                f = r["fmax_mhz"].get(c.domain) if why is None else None
                out.append(make_row(registry.block_machine(sw.block).name, figure, f"Fmax, {c.name}, {sw.param} {v}",
                                    paper=None if c.hz is None else c.hz / 1e6, formula=None, measured=f,
                                    unit="MHz", source="hdl:nextpnr", reason=why, run=_ran(r)))
        plots.append((sw, figure, points, missing))
    sections = ["", "## Place and route", "",
                "Made by `rasterhw report fpga` (slow: one nextpnr run per row group, minutes to an hour each; "
                "results are cached in `build/pnr-*`, so a second run takes seconds); one block: "
                "`rasterhw fpga BLOCK -p NAME=VALUE`. Flow: Yosys `synth_ecp5` + `nextpnr-ecp5 --85k` "
                "(router2, seed 1; router1 on the same netlist where router2 does not finish in the time limit, "
                "named in the per-run table), from PyPI, **out of context**: no I/O buffers and no global clock network, "
                "so Fmax is nextpnr's estimate on general routing, a lower bound. `full` rows are the block at "
                "its paper's size, `reduced` rows a smaller configuration named in the row (never the full "
                "block). A block that does not fit keeps `measured` empty with its demand: nextpnr's packed "
                "cells against the device's (`nextpnr --pack-only`), or, for a frame memory that lies outside "
                "the block (`Flow.demand_from_synth`), the RAM bits from synthesis. `paper` is the clock the paper "
                "names: " + " ".join(m.fpga_note for m in registry.machines().values() if m.fpga_note)]
    if record is not None:
        sections += ["", "This table was made from the recorded runs alone (`rasterhw report fpga`, no `--rerun`: "
                     "`fpga_runs.json` beside it; no Verilog generated, no tool run): each row is the run of the "
                     "design as it was on the date in the per-run table, named by its digest (the block's Verilog, "
                     "the scripts and the tools' versions). `rasterhw report fpga --rerun` checks every digest "
                     "against the design as it is now and places what changed."]
    elif cached_only:
        sections += ["", "This table was made from the cached runs (`build/pnr-*`, `fpga_runs.json`) of a "
                     "place-and-route queue, one run at a time under `nice -n 10`, each with a time limit: "
                     "`python -c \"from rasterhw.sim.report.rows import run_report; run_report('fpga', cached_only=True)\"`; "
                     "`rasterhw report fpga` runs the missing ones."]
    if not fast:
        for sw, figure, points, missing in plots:
            plot = f"fpga_{sw.block.replace('-', '_')}_fmax.png"
            sweep_plot(sw, points, Path(out_dir) / plot, missing)
            what = f"{sw.block} Fmax against {sw.param}"
            sections += ["", f"![{what}]({plot})", "", f"{what} (rows `{figure}`): {sw.note}"]
        sections += ["", "Per run (cached and recorded runs show the date and times of the run that made them; "
                     "the results are kept in `fpga_runs.json` beside this table, keyed by a digest of the "
                     "block's Verilog, the scripts and the tools' versions, so a later report on any machine "
                     "re-runs only what changed):", "",
                     "| block | configuration | ran | synthesis s | nextpnr s | result |", "|---|---|---|---|---|---|"]
        for block, params, kind, r in walls:
            res = r.get("reason") or "placed and routed"
            if r.get("display_reason"):
                res += f"; {FALLBACK_ROUTER} not run yet"
            if r.get("first_try") and r.get("finished"):
                res += (f" by {r.get('router')} ({ROUTER} did not finish in "
                        f"{r['first_try'].get('timeout_s', 0) / 60:.0f} min: {_reason(r['first_try'])})")
            ss = "—" if r.get("synth_s") is None else f"{r['synth_s']:.0f}"
            ps = "—" if r.get("pnr_s") is None else f"{r['pnr_s']:.0f}"
            sections.append(f"| {block} | {_cfg(block, params, kind)} | {r.get('ran') or '—'} | {ss} | {ps} | {res} |")
        if record is None:   # checked against the design by digest in this run: stamped with its sources
            write_run_record([r for *_, r in walls] + sweep, Path(out_dir) / RUN_RECORD.name, stamp=True)
        elif Path(record).resolve() != (Path(out_dir) / RUN_RECORD.name).resolve():
            import shutil  # the record this table was read from goes beside it, as it is

            shutil.copyfile(record, Path(out_dir) / RUN_RECORD.name)
    return out, sections
