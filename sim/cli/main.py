"""``rasterhw`` — the command line.

Every command turns a :class:`~rasterhw.golden_model.errors.RasterhwError` (bad input, an
unsupported parameter) into one line ``error: ...`` on stderr and exit status 2, with no
traceback. ``--json`` puts a machine-readable result on stdout; progress goes to stderr.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from pathlib import Path

import click
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.cli.cache import cache as _cache_group
from rasterhw.sim.cli.flow import add_commands, block_params, check_cache, scheduler_options
from rasterhw.sim.cli.jsonout import emit_json, sim_json
from rasterhw.sim.report.rows import systems as _report_systems

#: the float reference rasteriser is shared by every machine; the rest come from the registry
REFERENCE = "reference"
ARCHS = (REFERENCE, *registry.archs())
SIM_BLOCKS = tuple(registry.sim_blocks())
ENGINES = registry.ENGINES   # the one list (sim/registry.py)


def _union_options(decls) -> list[registry.Option]:
    """Every distinct option the given archs / sim blocks declare (one flag, one meaning)."""
    seen: dict[str, registry.Option] = {}
    for o in (o for d in decls for o in d.options):
        if o.name in seen and seen[o.name] != o:
            prev = seen[o.name]
            if (prev.type, prev.choices is None) != (o.type, o.choices is None):
                raise RuntimeError(f"option {o.flag} declared twice with different types")
            choices = tuple(dict.fromkeys((*(prev.choices or ()), *(o.choices or ())))) or None
            seen[o.name] = registry.Option(o.name, prev.help, prev.default, choices, prev.type)
        else:
            seen.setdefault(o.name, o)
    return list(seen.values())


def _click_options(opts: list[registry.Option]):
    """Click decorators for registry options; every value defaults to None (= not given)."""
    def deco(f):
        for o in reversed(opts):
            if o.type is bool:
                f = click.option(f"{o.flag}/--no-{o.flag[2:]}", o.name, default=None, help=o.help)(f)
            else:
                kind = click.Choice(o.choices) if o.choices else o.type
                shown = "" if o.default is None else f" (default: {o.default})"
                f = click.option(o.flag, o.name, type=kind, default=None, help=o.help + shown)(f)
        return f
    return deco


def _take_options(given: dict, declared: tuple[registry.Option, ...], who: str) -> dict:
    """The values for one arch / block: its declared options (defaults filled in); an option
    given on the command line that it does not take is an error, not silently ignored."""
    _ascii_values(given)
    names = {o.name for o in declared}
    for k, v in given.items():
        if v is not None and k not in names:
            raise RasterhwError(f"--{k.replace('_', '-')} does not apply to {who}")
    out = {}
    for o in declared:
        v = given.get(o.name)
        if v is not None and o.choices and v not in o.choices:
            raise RasterhwError(f"{who}: {o.flag} must be one of {', '.join(o.choices)}, not {v!r}")
        out[o.name] = o.default if v is None else v
    return out


_RENDER_OPTIONS = _union_options(a for _, a in registry.archs().values())
_SIM_OPTIONS = _union_options(b for _, b in registry.sim_blocks().values())


def parse_size(text: str | None) -> tuple[int, int] | None:
    """``"512x512"`` -> (512, 512); raises RasterhwError on anything else (digits only: no
    signs, no ``5_0``)."""
    import re

    if text is None:
        return None
    m = re.fullmatch(r"\s*([0-9]{1,9})\s*[xX*]\s*([0-9]{1,9})\s*", str(text))
    if m is None:
        raise RasterhwError(f"--size must look like 512x512, not {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise RasterhwError(f"--size {w}x{h}: width and height must be between 1 and 16384")
    return w, h


def info(msg: str) -> None:
    click.echo(msg, err=True)


def check_engine(engine: str | None) -> None:
    """An HDL engine that is not installed here is one line before any work (``--engine icarus``
    without ``iverilog`` was refused after 32 s of golden-model work, and the demo printed three
    Dask tracebacks first); ``pysim`` needs nothing."""
    if engine in ("verilator", "icarus"):
        from rasterhw.sim.engines.runner import get_sim
        from rasterhw.sim.paths import SimulatorUnavailable

        try:
            get_sim(engine)
        except SimulatorUnavailable as e:
            raise RasterhwError(f"--engine {engine}: {e} (install it, or use --engine "
                                f"{'verilator' if engine == 'icarus' else 'pysim'})") from None


def _ascii_values(given: dict) -> None:
    """Text option values whose digits are not ASCII (``--matrix ２x２``) are refused, as
    ``--size`` refuses them (the number they mean is not what a reader sees)."""
    for k, v in given.items():
        if isinstance(v, str) and any(ch.isdigit() and not ch.isascii() for ch in v):
            raise RasterhwError(f"--{k.replace('_', '-')} {v!r}: write its digits as ASCII 0-9")


def _print_version(ctx, _param, value) -> None:
    if value and not ctx.resilient_parsing:
        from rasterhw.sim.version import version

        click.echo(f"rasterhw, version {version()}")   # the commit too, in a checkout (sim/version.py)
        ctx.exit()


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--version", is_flag=True, expose_value=False, is_eager=True, callback=_print_version,
              help="Show the version (in a checkout: with the commit) and exit.")
def cli() -> None:
    """RTL models (Amaranth) of parallel 3-D rendering machines of the 1980s-90s, checked
    against a NumPy golden model. Machines: see `rasterhw machines`.

    \b
    Start with:
      rasterhw scenes                      list the built-in scenes
      rasterhw render c300 -o c300.png     float reference image
      rasterhw demo                        golden model + hardware, images and a report
      rasterhw report snu                  paper figures beside measured ones
    """
    from rasterhw.sim.flow.tasks import one_cluster

    ctx = click.get_current_context()
    if os.environ.get("RASTERHW_CACHE_MAX", "").strip():   # cacheinfo.CAP_ENV, imported only when set
        from rasterhw.sim.cacheinfo import apply_cap, cap_from_env

        if cap_from_env() is not None:   # checked now, applied when the command ends
            ctx.call_on_close(apply_cap)
    ctx.with_resource(one_cluster())   # one local Dask cluster per command (sim/flow/tasks.py)


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


def load_scene_and_size(scene: str, size: str | None, *, bytes_per_pixel: int = 0, what: str = ""):
    """The scene and frame size; the size is checked first (before a big mesh loads), and if
    ``bytes_per_pixel`` is given, so is the memory the frame will need."""
    from rasterhw.golden_model.scenes import SCENES, build_scene

    wh = parse_size(size)
    if wh is None:
        info_ = SCENES.get(scene)
        wh = (info_.default_width, info_.default_height) if info_ is not None else (512, 512)
    if bytes_per_pixel:
        from rasterhw.golden_model.memcheck import check_memory

        check_memory(bytes_per_pixel * wh[0] * wh[1], f"{what} {wh[0]}x{wh[1]}".strip())
    p = Path(scene)
    big = scene not in SCENES and p.is_file() and p.stat().st_size > _BIG_MESH_BYTES
    if big and sys.stderr.isatty():   # a big mesh takes seconds to minutes to read: say so first
        info(f"loading {p.name} ({p.stat().st_size / 1e6:.0f} MB) ...")
    if scene in SCENES:
        sc = build_scene(scene)
    else:   # a mesh file (meshio.load_scene: a built-in name first, as here)
        from rasterhw.golden_model.meshio import load_scene

        sc = load_scene(scene)
    if sc.n_polygons > _BIG_SCENE_POLYGONS and sys.stderr.isatty():
        info(f"{sc.name}: {sc.n_polygons:,} polygons; transforming and rendering ...")
    return sc, wh


#: a mesh file (bytes) or scene (polygons) big enough that a person waiting is told what is going on
_BIG_MESH_BYTES = 5_000_000
_BIG_SCENE_POLYGONS = 200_000


def render_reference(scene: str, size: str | None, z_bits: int = 24, *, progress: bool = False):
    """Scene -> (Scene, ScreenTriangles, (rgb8, counts), seconds in geometry, seconds in raster).

    The frame is rendered in tiles (``reference.rasterise_rgb8``: exactly ``rasterise``'s
    pixels, ~6 bytes per pixel kept); its memory is checked before anything is allocated."""
    from rasterhw.golden_model.memcheck import check_memory
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import rasterise_rgb8, rasterise_rgb8_memory

    sc, (w, h) = load_scene_and_size(scene, size)
    check_memory(rasterise_rgb8_memory(w, h, sc.n_polygons), f"render {w}x{h} (reference)")
    t0 = time.perf_counter()
    tris = run_geometry(sc, w, h, z_bits=z_bits)
    t1 = time.perf_counter()
    bar = _progress_bar(h, "raster", "rows") if progress else None
    try:
        frame = rasterise_rgb8(tris, progress=bar.update if bar is not None else None)
    finally:
        if bar is not None:
            bar.close()
    t2 = time.perf_counter()
    return sc, tris, frame, t1 - t0, t2 - t1


def _progress_bar(total: int, desc: str, unit: str):
    """A tqdm bar on stderr, shown only on a terminal (never in pipes, logs or tests)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=None, file=sys.stderr, leave=False)


_GEOMETRY: dict = {}


def _geometry(sc, w: int, h: int):
    """The reference geometry of ``sc`` at ``w`` x ``h`` (kept for the one scene of this command)."""
    from rasterhw.golden_model.pipeline import run_geometry

    key = (id(sc), w, h)
    if key not in _GEOMETRY:
        _GEOMETRY.clear()
        _GEOMETRY[key] = run_geometry(sc, w, h)
    return _GEOMETRY[key]


def _nothing_to_draw(sc, w: int, h: int):
    """The reference's background frame if no polygon of ``sc`` survives culling and clipping
    (all back-facing, or all outside the view), else None. A machine's renderer or simulation is
    not run on an empty triangle list (some ended in an IndexError): the command warns, as the
    reference does, and writes the blank frame."""
    tris = _geometry(sc, w, h)
    if tris.n_triangles:
        return None
    # imported here: a frame with triangles never needs the reference rasteriser
    from rasterhw.golden_model.reference import rasterise_rgb8

    rgb8, _counts = rasterise_rgb8(tris)
    return rgb8


def _warn_if_empty(tris, pixels_written: int) -> None:
    """A frame with nothing drawn is almost always a surprise: say why."""
    st = tris.stats
    if pixels_written == 0 and int(st.get("polygons_in", 0)) > 0:
        culled, clipped = int(st.get("polygons_culled", 0)), int(st.get("polygons_clipped_away", 0))
        info(f"warning: nothing drawn: {st.get('polygons_in')} polygons in, {culled} back-facing (culled), "
             f"{clipped} outside the view; the frame is background only")


@cli.command()
@click.option("--json", "as_json", is_flag=True, help="Print the machines as JSON: archs, blocks (each with its "
              "testbench and the engines that run it), sim blocks, report, soak rounds, proofs.")
def machines(as_json: bool) -> None:
    """List the machines with their archs, HDL blocks and sim blocks."""
    if as_json:
        from rasterhw.sim.engines import ENGINES

        emit_json([{"name": m.name, "title": m.title, "seed": m.seed, "status": m.status,
                    "archs": [a.name for a in m.archs],
                    "blocks": {b: {"factory": ref, "testbench": m.testbenches.get(b),
                                   "engines": list(ENGINES) if b in m.testbenches else []}
                               for b, ref in m.blocks.items()},
                    "sims": [s.name for s in m.sims], "report": m.report, "soak": m.soak, "proofs": m.proofs}
                   for m in registry.machines().values()])
        return
    for m in registry.machines().values():
        click.echo(f"{m.name:<9}{m.title}  (seed {m.seed})")
        if m.status:
            click.echo(f"{'':9}{m.status}")
        for label, names in (("archs", [a.name for a in m.archs]), ("blocks", list(m.blocks)),
                             ("sim", [b.name for b in m.sims])):
            if names:
                click.echo(f"{'':9}{label}: {', '.join(names)}")


@cli.command()
@click.argument("scene")
@click.option("--arch", type=click.Choice(ARCHS), default=REFERENCE, show_default=True,
              help="Which renderer: the float reference, or a machine's golden model (rasterhw machines).")
@click.option("--size", default=None, metavar="WxH", help="Frame size (default: the scene's own, e.g. 512x512).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="PNG file to write (default: out/SCENE-ARCH.png).")
@click.option("--z-bits", type=int, default=None, hidden=True,
              help="Refused: no renderer's image depends on it (the reference's depth test uses float Z).")
@_click_options(_RENDER_OPTIONS)
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON on stdout.")
def render(scene: str, arch: str, size: str | None, output: str | None, z_bits: int | None, as_json: bool,
           **arch_options) -> None:
    """Render SCENE (a built-in name or an .obj/.ply file) and write a PNG."""
    from rasterhw.sim.outfile import check_image_output, write_image

    if z_bits is not None:
        # it only ever set the width of the screen triangles' quantised Z, which no renderer behind
        # `render` reads (the reference compares float Z; each machine has its own Z width): an
        # option that changes nothing is refused rather than silently ignored (issue 33)
        raise RasterhwError("--z-bits changes no image of `render` (the reference's depth test uses float Z; "
                            "each machine's Z width is its own); leave it out")
    out = check_image_output(output) or Path("out") / f"{Path(scene).stem}-{arch}.png"
    t0 = time.perf_counter()
    if arch == REFERENCE:
        _take_options(arch_options, (), "--arch reference")
        sc, tris, (rgb8, counts), _, _ = render_reference(scene, size, progress=not as_json)
        pixels_written = counts["pixels_written"]
        extra = {"fragments": counts["fragments"], "pixels_covered": counts["pixels_covered"]}
    else:
        _machine, a = registry.archs()[arch]
        opts = _take_options(arch_options, a.options, f"--arch {arch}")
        sc, (w, h) = load_scene_and_size(scene, size, bytes_per_pixel=a.bytes_per_pixel, what=f"render --arch {arch}")
        empty = _nothing_to_draw(sc, w, h)
        if empty is not None:   # every arch gives the reference's blank frame, none a traceback
            rgb8, tris, pixels_written, extra = empty, _geometry(sc, w, h), 0, {**opts, "ran": False}
        else:
            res = registry.load(a.render)(sc, w, h, arch=arch, **opts)
            rgb8, tris, pixels_written = res.rgb8, res.tris, int(res.pixels_written)
            extra = {**opts, **res.stats}
    wall = time.perf_counter() - t0
    write_image(out, rgb8)
    _warn_if_empty(tris, pixels_written)
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
@click.option("--json", "as_json", is_flag=True,
              help="Print the comparison as JSON on stdout (differing pixels, largest difference).")
def compare(a: str, b: str, output: str | None, tolerance: int, as_json: bool) -> None:
    """Compare two images pixel by pixel; exit 1 if they differ beyond --tolerance."""
    from rasterhw.golden_model.compare import compare_images, diff_image
    from rasterhw.sim.imageio import read_rgb8_pair
    from rasterhw.sim.outfile import check_image_output, write_image

    out = check_image_output(output, inputs=(a, b))   # never the diff over an input
    if tolerance < 0:
        raise RasterhwError(f"--tolerance must be 0 or more, not {tolerance}")
    ia, ib = read_rgb8_pair(a, b, extra_bytes_per_pixel=3 if out else 0)
    res = compare_images(ia, ib, tolerance=tolerance)
    if out:
        write_image(out, diff_image(ia, ib, tolerance=tolerance))
        res["diff_image"] = str(out)
    if as_json:
        emit_json(res)
    else:
        info(" ".join(f"{k}={v}" for k, v in res.items()))
    sys.exit(0 if res["differing_pixels"] == 0 else 1)


@cli.command()
@click.argument("system", type=click.Choice([*_report_systems(), "all"]))
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON on stdout.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Where SYSTEM.md and its plots are written. Default: the checkout's docs/reproduction/ when "
                   "rasterhw runs from a checkout (from any folder); for an installed package, reports/ in the "
                   "cache folder ($RASTERHW_CACHE, else the user's cache folder), never the current folder.")
@click.option("--engine", type=click.Choice(ENGINES), default="verilator",
              show_default=True, help="HDL simulator for rows measured from HDL cycles (full frames always "
              "run on a compiled simulator).")
@click.option("--fast", is_flag=True, help="Keep slow rows (synthesis, place and route) unmeasured.")
@click.option("--rerun", is_flag=True, help="fpga: check every recorded run against the design as it is now "
              "and run synthesis and place and route for what changed (minutes to an hour per block); without it "
              "the fpga rows come from the recorded runs alone (fpga_runs.json in --out, else the checkout's "
              "docs/reproduction/fpga_runs.json): no Verilog, no Yosys, no nextpnr. "
              "mutation: run the campaign and the proofs again (docs/reproduction/mutation_runs.json).")
@scheduler_options()
def report(system: str, as_json: bool, out_dir: str, engine: str, fast: bool, rerun: bool, scheduler: str,
           store: str, fresh: bool) -> None:
    """Reproduce a paper's figures: paper value, formula value, measured value, ratio.

    A report's independent runs (ZB/M Table 1, pixel rate, skew and chains; EXPERTS balance;
    fpga place and route; the sparse FIFO-depth sweep) run as tasks on --scheduler (docs/scale.md)."""
    from rasterhw.sim.flow.tasks import check_scheduler, parse_scheduler
    from rasterhw.sim.report.rows import run_report, systems

    parse_scheduler(scheduler)
    names = systems() if system == "all" else [system]
    if rerun and not {"fpga", "mutation"} & set(names):
        raise RasterhwError("--rerun applies to the fpga and mutation reports only")
    if rerun and fast:
        raise RasterhwError("--rerun and --fast contradict each other")
    check_engine(engine)
    check_cache()
    check_scheduler(scheduler)   # what answers at its address too, before anything runs
    from rasterhw.sim.report.rows import default_report_dir

    out_dir = out_dir or str(default_report_dir())
    rows = []
    for name in names:
        extra = {}
        if name == "fpga" and not fast:
            # synthesis and place and route take minutes to an hour per block: never started
            # unasked; without --rerun the rows are the record's
            extra["records_only"] = not rerun
            if rerun:
                info("fpga: running place and route for every configuration (minutes to an hour per block)")
        if name == "mutation":
            extra["rerun"] = rerun
        rows += run_report(name, out_dir=Path(out_dir), engine=engine, progress=not as_json, fast=fast,
                           scheduler=scheduler, store=store, fresh=fresh, **extra)
    if as_json:
        emit_json(rows)
    else:
        from rasterhw.sim.report.rows import format_table

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
    from rasterhw.sim.engines.verilog import block_names
    from rasterhw.sim.engines.verilog_cache import write_verilog
    from rasterhw.sim.outfile import check_output

    if list_blocks:
        click.echo("\n".join(block_names()))
        return
    kw = block_params(block, params)
    if output is None:
        raise RasterhwError("say where to write the Verilog: -o FILE")
    check_output(output)   # a folder name is refused before the (slow) generation
    if interleave is not None:
        if "interleave" in kw and kw["interleave"] != interleave:
            raise RasterhwError(f"--interleave {interleave} contradicts -p interleave={kw['interleave']}")
        kw["interleave"] = interleave
    _limit_memory()   # explicit parameters can ask for any size: a MemoryError (one line), not an OOM kill
    check_cache()
    if sys.stderr.isatty():  # progress for a person waiting; logs and pipes get only the result
        info(f"generating Verilog for {block} ...")
    try:
        with _memory_estimate(block):
            write_verilog(block, output, **kw)
    except RasterhwError:
        raise
    except (TypeError, ValueError, OverflowError) as e:
        raise RasterhwError(f"{block}: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    except MemoryError:
        raise RasterhwError(f"{block}: these parameters need more memory than there is") from None
    info(f"wrote {'standard output' if output == '-' else output}")


#: memory one word of an Amaranth ``Memory`` takes to elaborate and convert (measured: the SNU
#: pixel bus with ``ram=memory``, 256x256 -> 512x512 frame, 150 -> 237 MB peak for 196,608 more
#: words: ~450 B a word; rounded up)
_ELAB_BYTES_PER_WORD = 500


@contextlib.contextmanager
def _memory_estimate(block: str):
    """``with _memory_estimate(block):`` every Amaranth memory the block makes is sized before its
    contents are allocated (``MemoryData``: shape and depth are known first): one that would need
    more memory than there is (:data:`_ELAB_BYTES_PER_WORD` a word) is one line at once, before
    the elaboration grows to the memory cap (``verilog pixelbus -p width=100000 -p height=100000
    -p ram=memory`` grew to 15.6 GB). Amaranth's ``MemoryData`` is wrapped only inside the block;
    a different Amaranth without it leaves the cap (:func:`_limit_memory`) to say it."""
    try:
        from amaranth.hdl import _mem
    except ImportError:   # pragma: no cover - another Amaranth
        yield
        return
    cls, orig = _mem.MemoryData, _mem.MemoryData.__init__
    words = [0]   # every memory of the block so far

    def sized(obj, *args, shape=None, depth=None, **kw):
        from rasterhw.golden_model.memcheck import HEADROOM, available_bytes, format_bytes

        if isinstance(depth, int) and depth > 0:
            words[0] += depth
            need, avail = words[0] * _ELAB_BYTES_PER_WORD, available_bytes()
            if need > HEADROOM * avail:
                raise RasterhwError(f"{block}: its memories hold {words[0]:,} words so far; elaborating them "
                                    f"needs about {format_bytes(need)}, more memory than there is "
                                    f"({format_bytes(avail)} available; use smaller -p sizes, or a RAM kind "
                                    "the block writes as Verilog)")
        orig(obj, *args, shape=shape, depth=depth, **kw)

    cls.__init__ = sized
    try:
        yield
    finally:
        cls.__init__ = orig


def _limit_memory() -> None:
    """Cap this process's data memory at what :mod:`~rasterhw.golden_model.memcheck` says may
    be used (85 % of the available memory, or ``RASTERHW_MEMORY_LIMIT``), so an elaboration
    too big for the machine (``verilog pixelbus -p width=100000 -p height=100000 -p ram=memory``
    was OOM-killed at 24 GB with no message) ends in a MemoryError, reported as one line. The
    WebAssembly Yosys reserves address space, not data, so it is not affected."""
    import resource

    from rasterhw.golden_model.memcheck import HEADROOM, available_bytes

    try:
        soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
        cap = int(HEADROOM * available_bytes())
        if hard != resource.RLIM_INFINITY:
            cap = min(cap, hard)
        if soft == resource.RLIM_INFINITY or cap < soft:
            resource.setrlimit(resource.RLIMIT_DATA, (cap, hard))
    except (ValueError, OSError):   # a platform without the limit: keep going as before
        pass


def sim_image_name(scene: str, block: str, engine: str, options: dict) -> Path:
    """The default image of ``rasterhw sim``: the options given on the command line are in the
    name, so runs of one scene in two configurations (``--schedule paper`` / ``overlap``) do not
    overwrite each other."""
    given = "".join(f"-{k}-{v}" for k, v in sorted(options.items()) if v is not None)
    return Path("out") / f"{Path(scene).stem}-{block}-{engine}{given}.png"


class _SimCommand(click.Command):
    """``rasterhw sim``: ``rasterhw sim BLOCK --help`` lists only BLOCK's own options (every block's
    are still parsed, so one given to a block that does not take it is refused by name)."""

    def parse_args(self, ctx, args):
        ctx.meta["sim_block"] = next((a for a in args if a in SIM_BLOCKS), None)
        return super().parse_args(ctx, args)

    def format_options(self, ctx, formatter):
        block = ctx.meta.get("sim_block")
        own = None if block is None else {o.name for o in registry.sim_blocks()[block][1].options}
        shared = {o.name for o in _SIM_OPTIONS}
        rows = [rec for p in self.get_params(ctx)
                if (own is None or p.name not in shared or p.name in own) and (rec := p.get_help_record(ctx))]
        if rows:
            with formatter.section(f"Options ({block}'s)" if block else "Options"):
                formatter.write_dl(rows)


@cli.command("sim", cls=_SimCommand)
@click.argument("block", type=click.Choice(SIM_BLOCKS))
@click.option("--scene", default=None, help="Built-in scene or .obj/.ply (default: the block's own, "
              + ", ".join(f"{n}: {b.default_scene}" for n, (_, b) in registry.sim_blocks().items()) + ").")
@click.option("--size", default=None, metavar="WxH", help="Frame size (default: the scene's own).")
@click.option("--engine", type=click.Choice(ENGINES), default="verilator", show_default=True,
              help="Simulator: pysim (Amaranth's, no build), verilator (compiled once per design) or icarus (cocotb on Icarus Verilog, where installed; sim sparse: pysim or verilator).")
@_click_options(_SIM_OPTIONS)
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None, help="PNG of the HDL frame.")
@click.option("--waves", type=click.Path(dir_okay=False), default=None,
              help="Write a trace of the run to this .vcd (.fst where Verilator can write FST); several simulators: "
                   "NAME.1.vcd, ... Off by default. Open it with Surfer (surfer FILE, or app.surfer-project.org) "
                   "or GTKWave (gtkwave FILE, or the NAME.gtkw save file written beside a .vcd: the block's "
                   "stream ports, one group each).")
@click.option("--trace-start", type=int, default=None, metavar="N",
              help="With --waves: record from clock edge N (counted from 0 at the first rising edge).")
@click.option("--trace-end", type=int, default=None, metavar="N",
              help="With --waves: record up to edge N, not included (must be after --trace-start).")
@click.option("--json", "as_json", is_flag=True,
              help="Print the run's result as JSON on stdout: one key set for every block (schema rasterhw.sim/1: "
                   "cycles, sim_cycles, sim_cpu_s, mismatches, pixels compared, timings; the block's own figures in "
                   "extra).")
def sim_cmd(block, scene, size, engine, output, waves, trace_start, trace_end, as_json, **block_options) -> None:
    """Run a scene through a block's HDL, compare with the golden model, write the frame.
    `rasterhw sim BLOCK --help` lists BLOCK's options only."""
    from rasterhw.sim.engines.waves import check_window, recording
    from rasterhw.sim.outfile import check_image_output, write_image

    check_window(trace_start, trace_end, waves=waves)   # before any work
    _machine, b = registry.sim_blocks()[block]
    opts = _take_options(block_options, b.options, f"sim {block}")
    if output is not None and any(opts.get(k) == v for k, v in b.no_image.items()):
        given = " ".join(f"--{'' if v else 'no-'}{k.replace('_', '-')}" if isinstance(v, bool)
                         else f"--{k.replace('_', '-')} {v}" for k, v in b.no_image.items())
        raise RasterhwError(f"sim {block} {given} gives no frame image; -o {output} cannot be written "
                            "(leave -o out)")
    check_engine(engine)
    if engine != "pysim":
        check_cache()
    scene = scene or b.default_scene
    out = check_image_output(output) or sim_image_name(scene, block, engine, block_options)
    sc, (w, h) = load_scene_and_size(scene, size, bytes_per_pixel=b.bytes_per_pixel, what=f"sim {block}")
    from rasterhw.sim.engines import tally

    t0 = time.perf_counter()
    empty = _nothing_to_draw(sc, w, h)
    if empty is not None:
        _warn_if_empty(_geometry(sc, w, h), 0)
        write_image(out, empty)
        with tally() as nothing:
            pass
        res = sim_json(block, sc.name, {"engine": engine, "cycles": 0, "clock_hz": None, "pixels_compared": 0,
                                        "mismatches": 0, "simulated": False, "image": str(out)},
                       nothing, time.perf_counter() - t0)
        emit_json(res) if as_json else info(" ".join(f"{k}={v}" for k, v in res.items()))
        return
    try:
        with recording(waves, engine, start=trace_start, end=trace_end) as traces, tally() as runs:
            res = registry.load(b.simulate)(sc, w, h, engine=engine, progress=not as_json, **opts)
    except RasterhwError:
        raise                                  # already one line that names what is wrong
    except (ValueError, OverflowError) as e:   # a block's own parameter check (e.g. a frame smaller than its banks)
        raise RasterhwError(f"sim {block}: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    if traces:
        res["waves"] = [str(t) for t in traces]
        res["gtkw"] = [str(t.with_suffix(".gtkw")) for t in traces if t.with_suffix(".gtkw").exists()]
    frame = res.pop("frame_rgb", None)
    if frame is not None:
        write_image(out, frame)
        res["image"] = str(out)
    elif output is not None:
        raise RasterhwError(f"sim {block} gives no frame image; -o {output} cannot be written (leave -o out)")
    res = sim_json(block, sc.name, res, runs, time.perf_counter() - t0, b.aliases)
    if as_json:
        emit_json(res)
    else:
        info(" ".join(f"{k}={v}" for k, v in res.items()))
    if res.get("mismatches", 0):
        sys.exit(1)


@cli.command()
@click.option("--json", "as_json", is_flag=True,
              help="Print the timings as JSON on stdout.")
@click.option("--repeat", type=int, default=11, show_default=True, help="Runs per measurement (median reported).")
@click.option("--hdl/--no-hdl", default=True, show_default=True, help="Also time HDL simulations (Verilator).")
def bench(as_json: bool, repeat: int, hdl: bool) -> None:
    """Print speed and memory figures (a benchmark, not a test)."""
    from rasterhw.sim.report.bench import run_bench

    if repeat < 1:
        raise RasterhwError(f"--repeat must be 1 or more, not {repeat}")
    rows = run_bench(repeat=repeat, hdl=hdl, progress=not as_json)
    if as_json:
        emit_json(rows)
    else:
        for r in rows:
            value = "-" if r["value"] is None else f"{r['value']:>12.4g}"
            click.echo(f"{r['name']:<52} {value:>12} {r['unit']:<10} {r.get('note', '')}")


@cli.command()
@click.option("--pixels", type=int, default=1_000_000, show_default=True,
              help="Output pixels to compare per block (the soak: 100000000).")
@click.option("--seed", type=int, default=None, help="Seed of every round (default: a fresh one, printed).")
@click.option("--block", "blocks", multiple=True, help="Only these blocks (repeatable; default: every block).")
@scheduler_options()
@click.option("--json", "as_json", is_flag=True,
              help="Print one JSON row per block on stdout (rounds, pixels, mismatches, seed).")
def soak(pixels: int, seed: int | None, blocks: tuple[str, ...], scheduler: str, store: str, fresh: bool,
         as_json: bool) -> None:
    """Random differential runs of every HDL block against its golden model on Verilator
    (random scenes and stimulus, idle and back-pressure patterns, ZB/M clock ratios); a block
    stops at its first mismatching round; exit 1 on any mismatch. The seed is printed; --seed
    reruns the same rounds (on any --scheduler: the same rounds, the same result)."""
    import secrets

    from rasterhw.sim.flow.soak import run_soak
    from rasterhw.sim.flow.tasks import check_scheduler

    if seed is not None and not 0 <= seed < 1 << 32:
        raise RasterhwError(f"--seed must be between 0 and {(1 << 32) - 1}, not {seed}")
    if pixels < 1:
        raise RasterhwError(f"--pixels must be 1 or more, not {pixels}")
    check_cache()
    check_scheduler(scheduler)   # a bad one (or one that does not answer as Dask) is an error before anything starts
    seed = secrets.randbelow(1 << 31) if seed is None else seed
    info(f"soak: seed {seed} (rerun: rasterhw soak --seed {seed} --pixels {pixels})")
    rows = run_soak(pixels=pixels, seed=seed, blocks=list(blocks) or None, progress=not as_json,
                    scheduler=scheduler, store=store, fresh=fresh)
    if as_json:
        emit_json(rows)
    else:
        for r in rows:
            click.echo(f"{r['block']:<10} {r['rounds']:>5} rounds {r['pixels_compared']:>12,} pixels "
                       f"{r['mismatches']:>6} mismatches {r['wall_s']:>8.1f} s")
            for fl in r["failures"]:
                click.echo(f"{'':10} round {fl['round']}: {fl['mismatches']} mismatches ({fl['settings']})")
    if any(r["mismatches"] for r in rows):
        sys.exit(1)


@cli.command()
@click.argument("target")
@click.option("--param", "params", multiple=True, metavar="NAME=V1,V2,...",
              help="A parameter of TARGET and the values it takes (repeatable; the sweep is the cross product).")
@click.option("--scene", "scenes", multiple=True, help="Scene(s) to run (repeatable; default: the target's own).")
@click.option("--size", default=None, metavar="WxH", help="Frame size (default: the scene's own).")
@click.option("--engine", type=click.Choice(ENGINES), default=None,
              help="HDL simulator for a sim block (default: verilator); a golden arch takes none.")
@scheduler_options()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Also write DIR/points.csv and a plot of every numeric result against each swept parameter.")
@click.option("--json", "as_json", is_flag=True, help="Print {scheduler, points: [{params, ...result}]} on stdout.")
def sweep(target: str, params: tuple[str, ...], scenes: tuple[str, ...], size: str | None, engine: str | None,
          scheduler: str, store: str, fresh: bool, out_dir: str | None, as_json: bool) -> None:
    """Run TARGET (a sim block, or render:ARCH for a golden arch) at every combination of the
    --param values, on --scheduler; exit 1 if a point mismatches its golden model.

    \b
      rasterhw sweep zbm --param interleave=1,2,4 --scene c50 --size 64x64
      rasterhw sweep render:experts --param sn=1,2,4,8 --param pn=1,2,4,8 --out out/sweep
    """
    from rasterhw.sim.cachefile import check_writable
    from rasterhw.sim.flow.sweep import plan, run_sweep, write_outputs
    from rasterhw.sim.flow.tasks import check_scheduler, parse_scheduler

    wh = parse_size(size)
    parse_scheduler(scheduler)
    if not params:
        raise RasterhwError("say what to sweep: --param NAME=V1,V2,...")
    plan(target, list(params), scenes=list(scenes), size=wh, engine=engine)   # every check before a cluster starts
    check_engine(engine)
    check_writable(store)   # where the results go, before any run
    check_scheduler(scheduler)   # then what answers at its address, before any run
    res = run_sweep(target, list(params), scenes=list(scenes) or None, size=wh, engine=engine, scheduler=scheduler,
                    store=store, fresh=fresh, progress=not as_json)
    if out_dir is not None:
        for p in write_outputs(res, out_dir):
            info(f"wrote {p}")
    if as_json:
        emit_json(res)
    else:
        for pt in res["points"]:
            given = " ".join(f"{k}={v}" for k, v in pt["params"].items())
            extra = "".join(f" {k}={pt[k]}" for k in ("cycles", "mismatches", "pixels_written") if k in pt)
            click.echo(f"{given} {pt.get('scene', '')}{extra} {pt['wall_s']:.2f} s [{pt['worker']}]")
        info(f"{len(res['points'])} points on {res['scheduler']}: {res['computed']} run, {res['reused']} from the store")
    if any(pt.get("mismatches") for pt in res["points"]):
        sys.exit(1)


@cli.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="out", show_default=True,
              help="Folder for the images, summary.json, report.md and index.html.")
@click.option("--scene", default="c300", show_default=True, help="Scene for the reference render.")
@click.option("--engine", type=click.Choice(ENGINES), default="verilator",
              show_default=True, help="HDL simulator for the hardware runs.")
@scheduler_options()
def demo(out_dir: str, scene: str, engine: str, scheduler: str, store: str, fresh: bool) -> None:
    """Render a default scene through the golden model and the hardware; write images and a report.
    The HDL runs are tasks on --scheduler (docs/scale.md)."""
    from rasterhw.sim.flow.tasks import check_scheduler
    from rasterhw.sim.report.demo import run_demo

    check_engine(engine)
    check_cache()
    check_scheduler(scheduler)
    out = Path(out_dir)
    existed = out.exists()
    try:
        run_demo(out, scene=scene, engine=engine, scheduler=scheduler, store=store, fresh=fresh)
    except BaseException:
        if not existed and out.is_dir() and not any(out.iterdir()):
            out.rmdir()   # a failed demo leaves no empty folder it made
        raise


add_commands(cli)   # synth, fpga, prove: the hardware flow (sim/cli/flow.py)
cli.add_command(_cache_group)   # rasterhw cache info|clean (sim/cli/cache.py)


def _terminate(signum, _frame):
    """SIGTERM/SIGHUP -> SystemExit, so ``finally`` blocks run (run folders removed,
    simulator children killed) instead of the process vanishing."""
    raise SystemExit(128 + signum)


def main(argv: list[str] | None = None) -> None:
    import signal

    from rasterhw.sim import workdirs

    for sig in (signal.SIGTERM, signal.SIGHUP):
        try:
            signal.signal(sig, _terminate)
        except (ValueError, OSError):  # not the main thread
            pass
    workdirs.become_subreaper()   # a tool whose parent is killed comes to us, not to PID 1
    try:
        _main(argv)
    finally:
        workdirs.cleanup()
        # no external tool outlives its command (sim/workdirs.py): whatever is still below us
        # (a tool a killed Dask worker left, solvers SymbiYosys left), then its work folders
        workdirs.end_descendants()
        workdirs.remove_dead_work_folders()


def _close_progress_bars() -> None:
    """End every progress bar still shown, so an error line starts on a line of its own."""
    try:
        from tqdm import tqdm
    except ImportError:
        return
    for bar in list(getattr(tqdm, "_instances", ())):
        bar.close()


def _main(argv: list[str] | None) -> None:
    try:
        rc = cli.main(args=argv, prog_name="rasterhw", standalone_mode=False)
    except BaseException:
        _close_progress_bars()
        _quiet_exit()
        _dispatch_error()
    if isinstance(rc, int) and rc:
        sys.exit(rc)


def _quiet_exit() -> None:
    """After an error or Ctrl-C, nothing more after the one line: the half-built Amaranth objects
    it left are collected at exit without UnusedElaboratable warnings, and a simulation's
    coroutines closed mid-step at exit print no "Exception ignored" tracebacks."""
    sys.unraisablehook = lambda _unraisable: None
    if "amaranth" in sys.modules:
        import warnings

        from amaranth.hdl import UnusedElaboratable

        warnings.simplefilter("ignore", UnusedElaboratable)


def _dispatch_error() -> None:
    """The exception being handled as the CLI reports it (one line, exit status)."""
    try:
        raise
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


if __name__ == "__main__":
    main()
