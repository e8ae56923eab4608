"""Report rows for the SNU graphics system (seed 004).

* Table 1 — operations per triangle per stage counted by running the paper's recipe
  (``golden_model/snu/recipe.py``) and our full pipeline (``golden_model/opcount.py``); i860
  clocks from the timing model ``golden_model/snu/i860.py`` (``source`` ``model``).
* Section 4.1 — traversal bytes and bandwidth from posting snu-100k's structure store.
* Section 4.3 — Gouraud inner-loop operations per pixel, counted as the scan converter ran.
* Section 3.2 — pixel-bus rate for scan-line, vertical and random patterns from HDL cycles.
* Abstract — the snu-100k frame end to end (``sim/snu/scene.py``): pixel bus in HDL on plain
  Verilator with clear and swap, producers' timing from the i860 model.
"""

from __future__ import annotations

from pathlib import Path

from rasterhw.golden_model.snu.paper import (
    PAPER_BUS_RATE,
    PAPER_FRAME_S,
    PAPER_INNER_LOOP_CLOCKS,
    PAPER_INNER_LOOP_OPS,
    PAPER_POLYS_PER_S,
    PAPER_TOTAL_CLOCKS,
    PAPER_TRAVERSAL_BPS,
    PAPER_TRIANGLE_BYTES,
)
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import make_row

# every paper value with its quote and place in the seed: golden_model/snu/paper.py
FORMULA_BUS_RATE = 5 / 400e-9  # 400 ns memory cycle / 5 banks = 80 ns per pixel = 12.5 Mpixel/s
PATTERN_PIXELS = 2000  # writes per access pattern; enough for a steady state
PATTERN_SIZE = (40, 25)  # a small frame whose width is a multiple of 5, as the paper's 1280


HEADLINE = "snu-100k"  # 100,000 Gouraud triangles of 100 px at 1280x1024: the paper's one second


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path,
         frame: dict | None = None) -> tuple[list[dict], list[str]]:
    """All SNU rows. ``frame``: a ``frame.frame_run`` result of snu-100k if the caller already
    ran it (the demo), else it is run here (plain Verilator)."""
    if frame is None:
        from rasterhw.golden_model.scenes import build_scene
        from rasterhw.sim.snu.scene import frame_run

        frame = frame_run(build_scene(HEADLINE), 1280, 1024, progress=progress, bus_only_bound=True)
    out = golden_rows(HEADLINE, frame=frame) + pixelbus_rows(engine=engine, progress=progress) + frame_rows(frame)
    return out, _plot_table1(out, out_dir) + _model_section() + _i860_note()


def golden_rows(scene_name: str = HEADLINE, *, frame: dict | None = None) -> list[dict]:
    """Table 1 (counted by the golden geometry, clocked by the i860 model), the traversal of
    ``scene_name``'s structure store, the Gouraud inner loop counted as the scan converter ran it."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import SCENES, build_scene
    from rasterhw.golden_model.snu import i860, recipe
    from rasterhw.golden_model.snu.balance import PAPER_TABLE1, table1_rows
    from rasterhw.golden_model.snu.gouraud import inner_loop_ops, scan_convert
    from rasterhw.golden_model.snu.traversal import measure_traversal
    from rasterhw.golden_model.triangle_ops import ops_per_triangle

    model = i860.table1_model()
    compiler = i860.table1_model(mode="compiler", stream_triangles=0)
    out = table1_rows(recipe.ops_per_triangle(), ops_per_triangle(), model, compiler=compiler)
    to_int = i860.stage_clocks("to_integer", stream_triangles=0)["clocks"]
    out.append(make_row("snu", "table 1", "screen_map + float -> integer (outside the paper's count): i860 clocks "
                        "(model, assembler schedule)", paper=PAPER_TABLE1["screen_map"]["clocks"], formula=None,
                        measured=model["screen_map"]["clocks"] + to_int, unit="clocks", source="model:i860"))
    # projection's 39 against 18: a finding with its manual cause (PRM ch. 6, FRCP: a 2^-7 seed; single
    # precision needs 2 Newton steps, the paper's 18 fits one)
    pd = PAPER_TABLE1["perspective_divide"]["clocks"]
    pd1 = i860.stage_clocks("perspective_divide", i860.I860(newton_steps=1), stream_triangles=0)["clocks"]
    out.append(make_row("snu", "table 1", "perspective_divide (projection): model - paper clocks, finding: 1/w is an "
                        "frcp seed good to 2^-7 plus 2 Newton steps for single precision (PRM ch. 6, FRCP), 8 "
                        "dependent operations per vertex (assembler schedule, scheduling window 1 triangle)",
                        paper=None, formula=None, measured=model["perspective_divide"]["clocks"] - pd,
                        unit="clocks", source="model:i860"))
    out.append(make_row("snu", "table 1", "perspective_divide (projection): i860 clocks with one Newton step (14-bit "
                        "reciprocals; too coarse for the 1/256-px grid of a 1280-px line)", paper=pd, formula=None,
                        measured=pd1, unit="clocks", source="model:i860"))
    for label, cpu in (("without dual-operation instructions", i860.I860(dual_operation=False)),
                       ("with one Newton step (14-bit reciprocals)", i860.I860(newton_steps=1))):
        m = i860.table1_model(cpu, stream_triangles=0)
        out.append(make_row("snu", "table 1", f"total i860 clocks per triangle (model {label}; assembler schedule)",
                            paper=PAPER_TOTAL_CLOCKS, formula=None, measured=m["total"]["clocks"], unit="clocks",
                            source="model:i860"))
    sc = build_scene(scene_name)
    w, h = SCENES[scene_name].size
    tv = measure_traversal(sc)
    out.append(make_row("snu", "text 4.1", f"traversal record per triangle ({scene_name}: CSS posted, bytes emitted "
                        "/ triangles)", paper=PAPER_TRIANGLE_BYTES, formula=3 * 9 * 4, measured=tv["bytes_per_triangle"], unit="bytes",
                        source="golden"))
    out.append(make_row("snu", "text 4.1", "traversal bandwidth at 100 K polygons/s", paper=PAPER_TRAVERSAL_BPS,
                        formula=PAPER_TRIANGLE_BYTES * PAPER_POLYS_PER_S, measured=tv["bandwidth"], unit="bytes/s", source="golden"))
    out.append(make_row("snu", "text 3.1", "dual-port memory rate, 16 bits per i860 bus cycle (2 clocks at 40 MHz)",
                        paper=None, formula=None, measured=tv["dpm_rate"], unit="bytes/s", source="model"))
    out.append(make_row("snu", "text 3.1", "triangle records one 256 KB dual-port memory holds", paper=None,
                        formula=256 * 1024 // 108, measured=tv["dpm_triangles"], unit="triangles", source="golden"))
    if frame is not None and "inner_loop" in frame.get("frame", {}):
        loop = frame["frame"]["inner_loop"]
    else:
        ran: dict = {}
        scan_convert(run_geometry(sc, w, h, z_bits=24, z_far_is_zero=True), counts=ran)
        loop = inner_loop_ops(ran)
    out.append(make_row("snu", "text 4.3", f"Gouraud inner loop, integer operations per pixel (executed on {scene_name})",
                        paper=PAPER_INNER_LOOP_OPS, formula=6 + 1 + 1, measured=loop["total"], unit="ops", source="golden"))
    px = {k: loop["pixels"] for k in ("add_addr", "add_r", "add_g", "add_b", "add_z", "add_count", "store", "branch")}
    out.append(make_row("snu", "text 4.3", "Gouraud inner loop, i860 clocks per pixel (dual-instruction mode)",
                        paper=PAPER_INNER_LOOP_CLOCKS, formula=None, measured=i860.inner_loop_clocks({"pixels": loop["pixels"], **px}),
                        unit="clocks", source="model:i860"))
    return out


def pixelbus_rows(*, engine: str, progress: bool) -> list[dict]:
    """Bus rates measured from HDL cycles on synthetic patterns."""
    from rasterhw.golden_model.snu.pixelbus import CLOCK_HZ, pattern_stream, pixels_per_second
    from rasterhw.sim.snu.scene import simulate_pixelbus

    src = f"hdl:{engine}"
    out = []
    w, h = PATTERN_SIZE
    for pattern, note in (("scanline", "scan-line pattern, 2 pipelines"),
                          ("vertical", "vertical pattern, 2 pipelines (each on one bank: width multiple of 5)"),
                          ("random", "random addresses, 2 pipelines")):
        stream = pattern_stream(pattern, w, h, PATTERN_PIXELS)
        res = simulate_pixelbus(stream, engine=engine, progress=False)
        if res["mismatches"]:
            raise RuntimeError(f"pixel bus HDL differs from the golden model on the {pattern} pattern")
        rate = pixels_per_second(len(stream), res["cycles"], CLOCK_HZ)
        # paper: "12 Mpixel/sec" (3.2). formula: 400 ns memory / 5 banks = 80 ns per pixel. Scan
        # line: every slot used. Vertical: each pipeline stays on one bank, one write per 400 ns.
        paper = PAPER_BUS_RATE if pattern == "scanline" else None
        formula = {"scanline": FORMULA_BUS_RATE, "vertical": 2 / 400e-9, "random": None}[pattern]
        out.append(make_row("snu", "text 3.2", f"pixel-bus rate, {note}", paper=paper, formula=formula,
                            measured=rate, unit="pixels/s", source=src))
    return out


def frame_rows(frame: dict) -> list[dict]:
    """The snu-100k frame through the pixel-bus HDL (plain Verilator), producers on the i860 model."""
    f = frame["frame"]
    if frame["mismatches"]:
        raise RuntimeError(f"snu-100k frame: {frame['mismatches']} mismatches between the HDL and the golden model")
    # the frame's time is the HDL pixel bus's, its producers' gaps the i860 model's: both sources
    hdl = f"hdl:{frame['engine']}"
    src = f"{hdl} + model:i860"
    out = [
        make_row("snu", "abstract", "snu-100k frame time: clear + 100,000 Gouraud triangles (~100 px) + swap "
                 f"(formula = clear + the limiting resource alone: {f['limiting']})",
                 paper=PAPER_FRAME_S, formula=f["bound_s"], measured=f["frame_s"], unit="s", source=src),
        make_row("snu", "abstract", "snu-100k polygons/s (whole frame)", paper=PAPER_POLYS_PER_S,
                 formula=f["triangles"] / f["bound_s"], measured=f["polygons_per_s"], unit="polygons/s", source=src),
        make_row("snu", "abstract", "snu-100k pixel writes/s (whole frame)", paper=None, formula=FORMULA_BUS_RATE,
                 measured=f["pixels_per_s"], unit="pixels/s", source=src),
        make_row("snu", "abstract", "snu-100k share of bus slots carrying a pixel", paper=None, formula=None,
                 measured=100 * f["bus_share_of_frame"], unit="%", source=src),
        make_row("snu", "abstract", "snu-100k pixel-bus mismatches (pixels + schedule numbers) vs golden",
                 paper=None, formula=0, measured=frame["mismatches"], unit="count", source=hdl),
    ]
    for k, v in f["share_of_frame"].items():
        out.append(make_row("snu", "abstract", f"snu-100k share of the frame: {k}", paper=None, formula=None,
                            measured=100 * v, unit="%", source=_share_source(k, hdl)))
    busy = f["busy_s"]
    geo = busy["geometry (i860 model, slowest of 3 processors, busiest pipeline)"]
    trav = busy["traversal output (108 B/triangle over a 16-bit dual-port memory)"]
    scan = busy["scan conversion (i860 model, busiest pipeline)"]
    out.append(make_row("snu", "abstract", "snu-100k geometry time / traversal time (i860 model, assembler schedule; "
                        "> 1: the three geometry processors, not the traversal, bound the front end)", paper=None,
                        formula=None, measured=geo / trav, unit="x", source="model:i860"))
    out.append(make_row("snu", "abstract", "snu-100k slower front-end stage (geometry or traversal) / scan conversion "
                        "time (i860 model; > 1: the front end bounds the producers)", paper=None, formula=None,
                        measured=max(geo, trav) / scan, unit="x", source="model:i860"))
    return out


def _share_source(name: str, src: str) -> str:
    if "golden" in name:
        return "golden"
    if "i860 model" in name:
        return "model:i860"
    return src if "pixel bus" in name else "model"


def _model_section() -> list[str]:
    return ["## Where the numbers come from", "",
            "Operations: counted by running the paper's recipe (`golden_model/snu/recipe.py`) and our full "
            "pipeline (`golden_model/pipeline.py`). i860 clocks: the shared i860 model `golden_model/i860/` "
            "scheduling the stage programs of `golden_model/snu/i860.py` two ways (compiler, assembler); no "
            "parameter is taken from table 1. "
            "The snu-100k frame: `sim/snu/scene.py` (pixel bus in HDL on plain Verilator, producers' timing "
            "from the i860 model). See `docs/snu_geometry.md` and `docs/snu.md` for every gap.", ""]


def _plot_table1(rows: list[dict], out_dir: Path) -> list[str]:
    clk = [r for r in rows if r["figure"] == "table 1"
           and r["quantity"].endswith("(i860 model, assembler schedule, one triangle)")]
    names = [r["quantity"].split(":")[0] for r in clk]
    x = range(len(names))
    path = out_dir / "snu_table1.png"
    with saved_figure(path, figsize=(8, 3.6)) as ax:
        ax.bar([i - 0.2 for i in x], [r["paper"] for r in clk], width=0.4, label="paper (table 1)")
        ax.bar([i + 0.2 for i in x], [r["measured"] for r in clk], width=0.4, label="i860 model (assembler)")
        ax.set_xticks(list(x), [n.replace("_", "\n") for n in names], fontsize=8)
        ax.set_ylabel("i860 clocks per triangle")
        ax.set_title("SNU table 1: clocks per triangle by stage")
        ax.legend()
    return ["## Plots", "", f"![table 1 clocks]({path.name})", "",
            "Clocks: the i860 timing model scheduling each stage's instructions (paper's recipe); where it "
            "differs from table 1, `docs/snu_geometry.md` says why, stage by stage.", ""]


def _i860_note() -> list[str]:
    """Stage by stage: the model's clocks beside table 1 and the manual fact that decides the
    difference; then every parameter of the i860 model with its source (no cache: scheduled now)."""
    from rasterhw.golden_model.i860 import PARAMETERS
    from rasterhw.golden_model.snu import i860
    from rasterhw.golden_model.snu.balance import PAPER_TABLE1

    asm = i860.table1_model(stream_triangles=0)
    cc = i860.table1_model(mode="compiler", stream_triangles=0)
    md = ["## The i860 model against table 1, stage by stage", "",
          "| stage | paper | assembler | compiler | pushes | dual ops | peak registers (of 30) | what decides the difference |",
          "|---|---|---|---|---|---|---|---|"]
    for s in i860.STAGES:
        a = asm[s]
        md.append(f"| {s} | {PAPER_TABLE1[s]['clocks']} | {a['clocks']} | {cc[s]['clocks']} | {a['pushes']} | "
                  f"{a['dual_ops']} | {a['peak_registers']} | {i860.STAGE_NOTES[s]} |")
    md += ["", "Every parameter of the i860 model (`golden_model/i860/model.py: PARAMETERS`):", "",
           "| parameter | value | source |", "|---|---|---|"]
    md += [f"| `{k}` | {v} | {src} |" for k, (v, src) in PARAMETERS.items()]
    return md + [""]
