"""Report rows for the SNU graphics system (seed 004).

* Table 1 — operations and i860 clocks per triangle per stage, ``measured`` from the
  instrumented golden geometry pipeline (:func:`~rasterhw.golden_model.opcount.ops_per_triangle`),
  clocks through the per-operation cost model of :mod:`~rasterhw.golden_model.snu.balance`.
* Section 4.1 — traversal bandwidth from the records the PHIGS traversal model really emits.
* Section 4.3 — Gouraud inner-loop operations per pixel, from the loop the golden model runs.
* Section 3.2 — pixel-bus rate for scan-line, vertical and random patterns, ``measured`` from
  HDL cycle counts (``source`` ``hdl:<engine>``), and the polygons/s of ``snu-100px`` through the
  pixel bus.
"""

from __future__ import annotations

from pathlib import Path

from rasterhw.sim.report import make_row

PAPER_BUS_RATE = 12.5e6  # 1 / 80 ns; the paper's text rounds it to "12 Mpixel/sec"
PAPER_POLYS_PER_S = 100_000  # abstract and conclusion: 100-pixel Gouraud polygons
PATTERN_PIXELS = 2000  # writes per access pattern; enough for a steady state
PATTERN_SIZE = (40, 25)  # a small frame whose width is a multiple of 5, as the paper's 1280


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path,
         snu_100px: tuple | None = None) -> tuple[list[dict], list[str]]:
    """All SNU rows. ``snu_100px``: ``(triangles, pixel stream, simulate_pixelbus result)`` of the
    snu-100px frame if the caller has already run it in HDL (the demo), else it is run here."""
    out = golden_rows() + pixelbus_rows(engine=engine, progress=progress, snu_100px=snu_100px)
    return out, _plot_table1(out, out_dir)


def golden_rows() -> list[dict]:
    """Table 1, traversal and inner-loop rows: measured by running the golden models."""
    from rasterhw.golden_model.opcount import ops_per_triangle
    from rasterhw.golden_model.snu import i860, recipe
    from rasterhw.golden_model.snu.balance import table1_rows
    from rasterhw.golden_model.snu.gouraud import inner_loop_ops
    from rasterhw.golden_model.snu.traversal import RECORD_BYTES, traversal_bandwidth

    out = table1_rows(recipe.ops_per_triangle(), ops_per_triangle(), i860.table1_model())
    out.append(make_row("snu", "text 4.1", "traversal record per triangle (3 x 9 float32)", paper=108,
                        formula=3 * 9 * 4, measured=3 * RECORD_BYTES, unit="bytes", source="golden"))
    out.append(make_row("snu", "text 4.1", "traversal bandwidth at 100 K polygons/s", paper=10e6,
                        formula=108 * 100_000, measured=traversal_bandwidth(100_000), unit="bytes/s",
                        source="golden"))
    loop = inner_loop_ops()
    out.append(make_row("snu", "text 4.3", "Gouraud inner loop, integer operations per pixel", paper=8,
                        formula=6 + 1 + 1, measured=loop["total"], unit="ops", source="golden"))
    return out


def pixelbus_rows(*, engine: str, progress: bool, snu_100px: tuple | None = None) -> list[dict]:
    """Bus rates measured from HDL cycles on synthetic patterns and on snu-100px."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.snu.gouraud import scan_convert
    from rasterhw.golden_model.snu.pixelbus import CLOCK_HZ, pattern_stream, pixels_per_second
    from rasterhw.sim.snu.pixelbus import simulate_pixelbus

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
        # formula: the paper's only timing facts are 80 ns per slot and a 400 ns memory cycle.
        # Scan line: every slot used, 1 / 80 ns. Vertical: each pipeline stays on one bank, so
        # each gets one write per 400 ns memory cycle. Random: no closed form from the paper.
        paper = PAPER_BUS_RATE if pattern == "scanline" else None
        formula = {"scanline": PAPER_BUS_RATE, "vertical": 2 / 400e-9, "random": None}[pattern]
        out.append(make_row("snu", "text 3.2", f"pixel-bus rate, {note}", paper=paper, formula=formula,
                            measured=rate, unit="pixels/s", source=src))
    if snu_100px is None:
        tris = run_geometry(build_scene("snu-100px"), 1280, 1024, z_bits=24, z_far_is_zero=True)
        stream = scan_convert(tris)
        res = simulate_pixelbus(stream, engine=engine if engine != "pysim" else "verilator", progress=progress)
    else:
        tris, stream, res = snu_100px
    if res["mismatches"]:
        raise RuntimeError("pixel bus HDL differs from the golden model on snu-100px")
    seconds = res["cycles"] / CLOCK_HZ
    src_scene = f"hdl:{res['engine']}"
    out.append(make_row("snu", "abstract", "snu-100px: ~100-pixel Gouraud polygons/s through the pixel bus",
                        paper=PAPER_POLYS_PER_S, formula=PAPER_BUS_RATE / 100, measured=tris.n_triangles / seconds,
                        unit="polygons/s", source=src_scene))
    out.append(make_row("snu", "abstract", "snu-100px: pixel writes/s through the pixel bus", paper=None,
                        formula=PAPER_BUS_RATE, measured=len(stream) / seconds, unit="pixels/s",
                        source=src_scene))
    return out


def _plot_table1(rows: list[dict], out_dir: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    clk = [r for r in rows if r["figure"] == "table 1" and r["quantity"].endswith("i860 clocks per triangle")]
    names = [r["quantity"].split(":")[0] for r in clk]
    x = range(len(names))
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.bar([i - 0.2 for i in x], [r["paper"] for r in clk], width=0.4, label="paper (table 1)")
    ax.bar([i + 0.2 for i in x], [r["measured"] for r in clk], width=0.4, label="measured (golden pipeline)")
    ax.set_xticks(list(x), [n.replace("_", "\n") for n in names], fontsize=8)
    ax.set_ylabel("i860 clocks per triangle")
    ax.set_title("SNU table 1: clocks per triangle by stage")
    ax.legend()
    fig.tight_layout()
    path = out_dir / "snu_table1.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return ["## Plots", "", f"![table 1 clocks]({path.name})", "",
            "Clocks come from counted operations times per-operation i860 costs derived from the paper's own "
            "columns (see `docs/snu_geometry.md`); where a measured count differs from the paper's, "
            "`docs/pipeline.md` says why, stage by stage."]
