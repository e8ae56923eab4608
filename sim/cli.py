"""``rasterhw`` — the command line.

Every command turns a :class:`~rasterhw.golden_model.errors.RasterhwError` (bad input, an
unsupported parameter) into one line ``error: ...`` on stderr and exit status 2, with no
traceback. ``--json`` puts a machine-readable result on stdout; progress goes to stderr.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click
from rasterhw.golden_model.errors import RasterhwError

ARCHS = ("reference", "snu")


def parse_size(text: str | None) -> tuple[int, int] | None:
    """``"512x512"`` -> (512, 512); raises RasterhwError on anything else."""
    if text is None:
        return None
    parts = text.lower().replace("*", "x").split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise RasterhwError(f"--size must look like 512x512, not {text!r}") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise RasterhwError(f"--size {w}x{h}: width and height must be between 1 and 16384")
    return w, h


def emit_json(obj: dict) -> None:
    click.echo(json.dumps(obj, indent=None, sort_keys=False, default=_json_default))


def _json_default(o):
    import numpy as np

    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def info(msg: str) -> None:
    click.echo(msg, err=True)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rasterhw")
def cli() -> None:
    """RTL models (Amaranth) of parallel 3-D rendering machines, checked against a NumPy
    golden model: the SNU pixel-bus Z comparator and the ZB/M scan-line Z-buffer merger
    (EXPERTS, the vector Z-buffer and the sparse-raster generator are planned).

    \b
    Start with:
      rasterhw scenes                      list the built-in scenes
      rasterhw render c300 -o c300.png     float reference image
      rasterhw demo                        golden model + hardware, images and a report
      rasterhw report snu                  paper figures beside measured ones
    """


@cli.command()
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list instead of a table.")
def scenes(as_json: bool) -> None:
    """List the built-in scenes with their polygon counts."""
    from rasterhw.golden_model.scenes import list_scenes

    rows = list_scenes()
    if as_json:
        emit_json(rows)
        return
    click.echo(f"{'name':<14}{'polygons':>9}  {'size':<10} description")
    for r in rows:
        size = f"{r['default_width']}x{r['default_height']}"
        click.echo(f"{r['name']:<14}{r['polygons']:>9}  {size:<10} {r['description']}")


def load_scene_and_size(scene: str, size: str | None):
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.scenes import SCENES

    sc = load_scene(scene)
    wh = parse_size(size)
    if wh is None:
        info_ = SCENES.get(scene)
        wh = (info_.default_width, info_.default_height) if info_ is not None else (512, 512)
    return sc, wh


def render_reference(scene: str, size: str | None, z_bits: int = 24):
    """Scene -> (Scene, ScreenTriangles, Frame, seconds in geometry, seconds in raster)."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import rasterise

    sc, (w, h) = load_scene_and_size(scene, size)
    t0 = time.perf_counter()
    tris = run_geometry(sc, w, h, z_bits=z_bits)
    t1 = time.perf_counter()
    frame = rasterise(tris)
    t2 = time.perf_counter()
    return sc, tris, frame, t1 - t0, t2 - t1


@cli.command()
@click.argument("scene")
@click.option("--arch", type=click.Choice(ARCHS), default="reference", show_default=True,
              help="Which renderer: the float reference, or an architecture's golden model.")
@click.option("--size", default=None, metavar="WxH", help="Frame size (default: the scene's own, e.g. 512x512).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="PNG file to write (default: out/SCENE-ARCH.png).")
@click.option("--z-bits", type=int, default=24, show_default=True, help="Width of the quantised Z.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON on stdout.")
def render(scene: str, arch: str, size: str | None, output: str | None, z_bits: int, as_json: bool) -> None:
    """Render SCENE (a built-in name or an .obj/.ply file) and write a PNG."""
    t0 = time.perf_counter()
    if arch == "reference":
        sc, tris, frame, _, _ = render_reference(scene, size, z_bits)
        rgb8 = frame.to_rgb8()
        pixels_written = int(frame.pixels_written)
        extra = {"fragments": int(frame.fragments), "pixels_covered": int(frame.pixels_covered)}
    else:  # snu: Gouraud scan converter (golden, bit-accurate) into the pixel-bus frame buffer model
        from rasterhw.golden_model.pipeline import run_geometry
        from rasterhw.golden_model.snu.gouraud import scan_convert
        from rasterhw.golden_model.snu.pixelbus import pixelbus_frame, rgb_image

        sc, (w, h) = load_scene_and_size(scene, size)
        tris = run_geometry(sc, w, h, z_bits=z_bits, z_far_is_zero=True)
        stream = scan_convert(tris)
        rgb8 = rgb_image(pixelbus_frame(stream)[0])
        pixels_written = len(stream)
        extra = {"pixel_writes": len(stream)}
    wall = time.perf_counter() - t0
    out = Path(output) if output else Path("out") / f"{Path(scene).stem}-{arch}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    from PIL import Image

    Image.fromarray(rgb8).save(out)
    result = {
        "scene": sc.name,
        "arch": arch,
        "width": int(tris.width),
        "height": int(tris.height),
        "polygons_in": int(tris.stats.get("polygons_in", sc.n_polygons)),
        "polygons_drawn": int(tris.stats.get("polygons_drawn", 0)),
        "triangles": int(tris.n_triangles),
        "pixels_written": pixels_written,
        **extra,
        "wall_s": round(wall, 6),
        "image": str(out),
    }
    if as_json:
        emit_json(result)
    else:
        info(f"{sc.name}: {result['polygons_in']} polygons in, {result['polygons_drawn']} drawn, "
             f"{pixels_written} pixels written, {wall * 1e3:.1f} ms -> {out}")


@cli.command()
@click.argument("a", type=click.Path(exists=True, dir_okay=False))
@click.argument("b", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None, help="Write a diff image here.")
@click.option("--tolerance", type=int, default=0, show_default=True, help="Per-channel difference allowed.")
@click.option("--json", "as_json", is_flag=True)
def compare(a: str, b: str, output: str | None, tolerance: int, as_json: bool) -> None:
    """Compare two images pixel by pixel; exit 1 if they differ beyond --tolerance."""
    import numpy as np
    from PIL import Image
    from rasterhw.golden_model.compare import compare_images, write_diff_png

    ia = np.asarray(Image.open(a).convert("RGB"))
    ib = np.asarray(Image.open(b).convert("RGB"))
    if ia.shape != ib.shape:
        raise RasterhwError(f"images differ in size: {ia.shape[1]}x{ia.shape[0]} vs {ib.shape[1]}x{ib.shape[0]}")
    res = compare_images(ia, ib, tolerance=tolerance)
    if output:
        write_diff_png(ia, ib, output)
        res["diff_image"] = output
    if as_json:
        emit_json(res)
    else:
        info(" ".join(f"{k}={v}" for k, v in res.items()))
    sys.exit(0 if res["differing_pixels"] == 0 else 1)


@cli.command()
@click.argument("system", type=click.Choice(["snu", "zbm", "all"]))
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON on stdout.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="docs/reproduction", show_default=True,
              help="Where SYSTEM.md and its plots are written.")
@click.option("--engine", type=click.Choice(["pysim", "verilator", "icarus"]), default="verilator",
              show_default=True, help="HDL simulator for rows measured from HDL cycles (full frames always "
              "run on a compiled simulator).")
def report(system: str, as_json: bool, out_dir: str, engine: str) -> None:
    """Reproduce a paper's figures: paper value, formula value, measured value, ratio."""
    from rasterhw.sim.report import SYSTEMS, run_report

    names = list(SYSTEMS) if system == "all" else [system]
    rows = []
    for name in names:
        rows += run_report(name, out_dir=Path(out_dir), engine=engine, progress=not as_json)
    if as_json:
        emit_json(rows)
    else:
        from rasterhw.sim.report import format_table

        click.echo(format_table(rows))
        info(f"wrote {', '.join(str(Path(out_dir) / (n + '.md')) for n in names)}")


@cli.command()
@click.argument("block", required=False)
@click.option("--list", "list_blocks", is_flag=True, help="List the blocks and exit.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None, help="Verilog file to write.")
@click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Block parameter, e.g. -p width=40 -p height=16 (repeatable).")
@click.option("--interleave", type=int, default=None, help="Shortcut for -p interleave=N (ZB/M blocks).")
def verilog(block: str | None, list_blocks: bool, output: str | None, params: tuple[str, ...],
            interleave: int | None) -> None:
    """Generate Verilog for BLOCK (see `rasterhw verilog --list`)."""
    from rasterhw.sim.verilog import BLOCKS, write_verilog

    if list_blocks:
        click.echo("\n".join(sorted(BLOCKS)))
        return
    if block not in BLOCKS:
        what = f"unknown block {block!r}" if block else "name a block"
        raise RasterhwError(f"{what}; blocks: {', '.join(sorted(BLOCKS))}")
    if output is None:
        raise RasterhwError("say where to write the Verilog: -o FILE")
    kw = {}
    for p in params:
        if "=" not in p:
            raise RasterhwError(f"--param must be NAME=VALUE, not {p!r}")
        k, v = p.split("=", 1)
        try:
            kw[k] = int(v)
        except ValueError:
            kw[k] = v
    if interleave is not None:
        kw["interleave"] = interleave
    try:
        write_verilog(block, output, **kw)
    except (TypeError, ValueError) as e:
        raise RasterhwError(f"{block}: {e}") from None
    info(f"wrote {output}")


@cli.command("sim")
@click.argument("block", type=click.Choice(["pixelbus", "zbm"]))
@click.option("--scene", default=None, help="Built-in scene or .obj/.ply (default: snu-100px / c300).")
@click.option("--size", default=None, metavar="WxH", help="Frame size (default: the scene's own).")
@click.option("--engine", type=click.Choice(["pysim", "verilator", "icarus"]), default="verilator", show_default=True)
@click.option("--interleave", type=int, default=8, show_default=True, help="ZB/M chips per scan line.")
@click.option("--units", type=int, default=1, show_default=True, help="ZB/M units chained by merge ports.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None, help="PNG of the HDL frame.")
@click.option("--json", "as_json", is_flag=True)
def sim_cmd(block, scene, size, engine, interleave, units, output, as_json) -> None:
    """Run a scene through a block's HDL, compare with the golden model, write the frame."""
    from PIL import Image

    if block == "pixelbus":
        from rasterhw.golden_model.pipeline import run_geometry
        from rasterhw.golden_model.snu.gouraud import scan_convert
        from rasterhw.sim.snu.pixelbus import simulate_pixelbus

        scene = scene or "snu-100px"
        sc, (w, h) = load_scene_and_size(scene, size)
        tris = run_geometry(sc, w, h, z_bits=24, z_far_is_zero=True)
        stream = scan_convert(tris)
        res = simulate_pixelbus(stream, engine=engine, progress=not as_json)
    else:
        from rasterhw.sim.zbm.driver import simulate_zbm

        scene = scene or "c300"
        sc, (w, h) = load_scene_and_size(scene, size)
        res = simulate_zbm(sc, w, h, interleave=interleave, units=units, engine=engine, progress=not as_json)
    frame = res.pop("frame_rgb", None)
    out = Path(output) if output else Path("out") / f"{Path(scene).stem}-{block}-{engine}.png"
    if frame is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(frame).save(out)
        res["image"] = str(out)
    res = {"block": block, "scene": sc.name, **res}
    if as_json:
        emit_json(res)
    else:
        info(" ".join(f"{k}={v}" for k, v in res.items()))
    if res.get("mismatches", 0):
        sys.exit(1)


@cli.command()
@click.option("--json", "as_json", is_flag=True)
@click.option("--repeat", type=int, default=11, show_default=True, help="Runs per measurement (median reported).")
@click.option("--hdl/--no-hdl", default=True, show_default=True, help="Also time HDL simulations (Verilator).")
def bench(as_json: bool, repeat: int, hdl: bool) -> None:
    """Print speed and memory figures (a benchmark, not a test)."""
    from rasterhw.sim.bench import run_bench

    rows = run_bench(repeat=repeat, hdl=hdl, progress=not as_json)
    if as_json:
        emit_json(rows)
    else:
        for r in rows:
            click.echo(f"{r['name']:<52} {r['value']:>12.4g} {r['unit']:<10} {r.get('note', '')}")


@cli.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="out", show_default=True)
@click.option("--scene", default="c300", show_default=True, help="Scene for the reference render.")
@click.option("--engine", type=click.Choice(["pysim", "verilator", "icarus"]), default="verilator",
              show_default=True, help="HDL simulator for the hardware run.")
def demo(out_dir: str, scene: str, engine: str) -> None:
    """Render a default scene through the golden model and the hardware; write images and a report."""
    from rasterhw.sim.demo import run_demo

    run_demo(Path(out_dir), scene=scene, engine=engine)


def main(argv: list[str] | None = None) -> None:
    try:
        rc = cli.main(args=argv, prog_name="rasterhw", standalone_mode=False)
    except RasterhwError as e:
        click.echo(f"error: {e}", err=True)
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("aborted", err=True)
        sys.exit(130)
    except click.ClickException as e:
        e.show()
        sys.exit(e.exit_code)
    except OSError as e:
        # a file that cannot be read or written: say which, no traceback
        click.echo(f"error: {e.strerror or e}: {e.filename or ''}".rstrip(": "), err=True)
        sys.exit(2)
    if isinstance(rc, int) and rc:
        sys.exit(rc)


if __name__ == "__main__":
    main()
