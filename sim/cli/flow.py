"""``rasterhw synth``, ``rasterhw fpga``, ``rasterhw prove`` and ``rasterhw mutate``: the hardware flow's commands.

Kept apart from ``sim/cli/main.py`` (which adds them with :func:`add_commands`); every tool comes
from PyPI (``sim/flow/tools.py``). Errors are ``RasterhwError``: one line ``error: ...``, exit 2.
"""

from __future__ import annotations

import sys

import click
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.cli.jsonout import emit_json


def block_params(block: str | None, params: tuple[str, ...]) -> dict:
    """The ``-p NAME=VALUE`` parameters of Verilog block ``block``, typed; an unknown block or a
    bad value is one line."""
    from rasterhw.sim.engines.verilog import block_names, parse_params

    if block not in block_names():
        what = f"unknown block {block!r}" if block else "name a block"
        near = [b for b in block_names() if block and b.endswith(f"-{block}")]
        if near:  # e.g. `rasterhw verilog pxp`: the sim block's name, not the Verilog block's
            what += f" (did you mean {' or '.join(near)}?)"
        raise RasterhwError(f"{what}; blocks: {', '.join(block_names())}")
    try:
        return parse_params(params, registry.load(registry.blocks()[block]))
    except (OverflowError, ValueError) as e:
        raise RasterhwError(f"{block}: {e}") from None


def _scheduler_file(ctx, _param, value):
    if value is not None:
        ctx.meta["rasterhw.scheduler_file"] = value
    return value


def _scheduler(ctx, _param, value):
    """--scheduler, or the address in --scheduler-file (read when it is given; never both)."""
    path = ctx.meta.get("rasterhw.scheduler_file")
    if path is None:
        return value
    if ctx.get_parameter_source("scheduler") is not click.core.ParameterSource.DEFAULT:
        raise RasterhwError("give --scheduler or --scheduler-file, not both")
    from rasterhw.sim.flow.tasks import scheduler_from_file

    return scheduler_from_file(path)


def _store(_ctx, _param, value):
    from rasterhw.sim.flow.tasks import default_store

    return default_store() if value is None else value


def scheduler_options(default: str = "local", scope: str = ""):
    """``--scheduler`` (or ``--scheduler-file``), ``--store``, ``--fresh``: where a command's tasks
    run and where their results are kept (sim/flow/tasks.py, docs/scale.md); ``scope`` ends each
    help (`` (with --all)``). The command gets ``store`` as a folder, never None."""
    def deco(f):
        f = click.option("--fresh", is_flag=True, help=f"Recompute every task, even those in the store{scope}.")(f)
        f = click.option("--store", type=click.Path(file_okay=False), default=None, callback=_store,
                         help=f"Folder keeping every finished task's result (default: build/tasks){scope}.")(f)
        f = click.option("--scheduler-file", type=click.Path(dir_okay=False), default=None, expose_value=False,
                         is_eager=True, callback=_scheduler_file,
                         help=f"The Dask scheduler named in this file (dask scheduler --scheduler-file FILE){scope}.")(f)
        return click.option("--scheduler", default=default, show_default=True, callback=_scheduler,
                            metavar="serial|local[:N]|tcp://HOST:PORT",
                            help="Where the tasks run: in this process, a local Dask cluster of N single-threaded "
                                 f"workers (default: one per core), or an existing Dask scheduler{scope}.")(f)
    return deco


@click.command()
@click.argument("block", required=False)
@click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Block parameter, e.g. -p interleave=8 (repeatable).")
@click.option("--memory", type=click.Choice(["keep", "map"]), default="keep", show_default=True,
              help="keep: memories as RAM blocks (counted as RAM bits); map: memories to flip-flops.")
@click.option("--all", "all_blocks", is_flag=True, help="Every registered block, one after the other.")
@click.option("--small", is_flag=True, help="With --all: the small test sizes (each block's Flow.small in its machine.py).")
@click.option("--json", "as_json", is_flag=True, help="Print the results as JSON.")
@scheduler_options(scope=" (with --all)")
def synth(block: str | None, params: tuple[str, ...], memory: str, all_blocks: bool, small: bool,
          as_json: bool, scheduler: str, store: str, fresh: bool) -> None:
    """Synthesise BLOCK (or --all) with Yosys: gate equivalents, flip-flops, RAM bits."""
    from rasterhw.sim.flow.synth import summary_row, synth_all, synth_report, synthesise
    from rasterhw.sim.flow.tasks import check_scheduler

    if all_blocks:
        check_scheduler(scheduler)
        if block or params:
            raise RasterhwError("--all takes no BLOCK or -p")
        check_cache()
        rows = synth_all(small=small, memory=memory, progress=not as_json, scheduler=scheduler,
                         store=store, fresh=fresh)
        if as_json:
            emit_json([summary_row(r) for r in rows])
            return
        click.echo(f"{'block':<18} {'gate eq.':>10} {'flip-flops':>10} {'RAM bits':>10} {'s':>7}  params")
        for r in rows:
            shown = ", ".join(f"{k}={v}" for k, v in r["params"].items())
            click.echo(f"{r['block']:<18} {r['gate_equivalent']:>10.0f} {r['flipflops']:>10} "
                       f"{r['ram_bits']:>10} {r['wall_s']:>7.1f}  {shown}")
        return
    if small:
        raise RasterhwError("--small applies only with --all (a named block takes its sizes from -p)")
    ctx = click.get_current_context()
    given = [f"--{n}" for n in ("scheduler", "store", "fresh")
             if ctx.get_parameter_source(n) is not click.core.ParameterSource.DEFAULT]
    given += ["--scheduler-file"] * ("rasterhw.scheduler_file" in ctx.meta)
    if given:   # they would be accepted and change nothing
        raise RasterhwError(f"{' and '.join(given)} appl{'ies' if len(given) == 1 else 'y'} only with --all "
                            "(one named block is synthesised here, not as a task)")
    if block is None:
        raise RasterhwError("name a block (rasterhw verilog --list) or give --all")
    kw = block_params(block, params)
    check_cache()
    if as_json:
        emit_json(summary_row(synthesise(block, memory=memory, **kw)))
    else:
        click.echo(synth_report(block, memory=memory, **kw))


@click.command()
@click.argument("block")
@click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE", help="Block parameter (repeatable).")
@click.option("--family", type=click.Choice(["ecp5", "ice40"]), default="ecp5", show_default=True,
              help="FPGA family: Lattice ECP5 (nextpnr-ecp5) or iCE40 (nextpnr-ice40).")
@click.option("--device", default=None, help="ecp5: 85k (default) or 25k; ice40: hx8k (default) or up5k.")
@click.option("--json", "as_json", is_flag=True,
              help="Print the place-and-route result as JSON on stdout (LUT4s, flip-flops, block RAMs, Fmax per clock).")
def fpga(block: str, params: tuple[str, ...], family: str, device: str | None, as_json: bool) -> None:
    """Place and route BLOCK with nextpnr: LUTs, flip-flops, block RAMs, Fmax beside the paper's clock.

    Routes with router2, and again with router1 on the same netlist when router2 does not finish
    in the time limit; results are cached in build/pnr-* and docs/reproduction/fpga_runs.json."""
    from rasterhw.sim.flow.fpga import DEVICES, fpga_summary, place_and_route

    if device is not None and device not in DEVICES[family]:   # '' too: never the default in its place
        raise RasterhwError(f"--device for {family} must be one of {', '.join(DEVICES[family])}, not {device!r}")
    kw = block_params(block, params)
    check_cache()
    r = place_and_route(block, family=family, device=device, **kw)
    if as_json:
        emit_json({k: v for k, v in r.items() if k != "build_dir"})
    else:
        click.echo(fpga_summary(r))


@click.command()
@click.argument("block", required=False)
@click.option("--all", "all_blocks", is_flag=True,
              help="Every block of `rasterhw verilog --list`: its stream rules (sim/flow/stream_proof.py) and "
                   "its own proof where it has one; kind, depth, passed per block.")
@click.option("--scheduler", default="serial", show_default=True, metavar="serial|local[:N]|tcp://HOST:PORT",
              help="--all: where the blocks' proofs run (a task each).")
@click.option("--depth", type=int, default=None, help="Steps (BMC) or induction length (default: the proof's own).")
@click.option("--fresh", is_flag=True, help="Prove again even if build/ holds this exact proof's result.")
@click.option("--json", "as_json", is_flag=True,
              help="Print the proof's result as JSON on stdout (block, kind, depth, passed, trace).")
def prove(block: str | None, all_blocks: bool, scheduler: str, depth: int | None, fresh: bool, as_json: bool) -> None:
    """Prove BLOCK's stream rules and pixel order formally (SymbiYosys); exit 1 with a VCD trace if one fails.

    A proof whose harness, script and tool versions are unchanged is read back from build/ (said
    in the output); --fresh runs SymbiYosys again. --all: every block (docs/mutation.md)."""
    from rasterhw.sim.flow.prove import prove as run

    if depth is not None and not 1 <= depth <= MAX_DEPTH:
        raise RasterhwError(f"--depth must be a whole number of steps from 1 to {MAX_DEPTH}, not {depth}")
    if all_blocks:
        if block or depth is not None or fresh:
            raise RasterhwError("--all proves every block at its own depth: no BLOCK, --depth or --fresh")
        from rasterhw.sim.flow.stream_proof import prove_all
        from rasterhw.sim.flow.tasks import check_scheduler

        check_cache()
        check_scheduler(scheduler)
        r = prove_all(scheduler=scheduler)
        _emit_blocks(r, as_json, _prove_line, f"{r['proved']} proved (k-induction), {r['bounded']} to a bound (BMC), "
                                              f"{r['failed']} failed, {r['unproven']} unproven")
        if r["failed"] or any(b["own"] and b["own"]["passed"] is False for b in r["blocks"]):
            sys.exit(1)
        return
    if block is None:
        raise RasterhwError("name a block (or --all)")
    check_cache()
    r = run(block, depth=depth, fresh=fresh)
    if as_json:
        emit_json(r)
    else:
        bound = f"k-induction, {r['depth']} steps" if r["mode"] == "prove" else f"all inputs up to {r['depth']} steps"
        when = f"cached, proved in {r['wall_s']:.1f} s" if r["cached"] else f"{r['wall_s']:.1f} s"
        click.echo(f"{r['block']}: {r['status']} ({r['engine']}, {bound}, {when})")
        click.echo(f"  {r['what']}")
        click.echo(f"  parameters: {', '.join(f'{k}={v}' for k, v in r['params'].items())}; files in {r['workdir']}")
        if r["trace"]:
            click.echo(f"  counterexample: {r['trace']}")
    if r["status"] != "PASS":
        sys.exit(1)


def _emit_blocks(r: dict, as_json: bool, line, total: str) -> None:
    """An ``--all`` result: its JSON, or a line per block (``line(block)``) and the ``total`` line."""
    if as_json:
        emit_json(r)
        return
    for b in r["blocks"]:
        click.echo(line(b))
    click.echo(total)


def _prove_line(b: dict) -> str:
    """One block of ``prove --all`` in one line."""
    shown = ", ".join(f"{k}={v}" for k, v in b["params"].items())
    if b["passed"] is None:
        head = f"unproven: {b['reason']}"
        f = b.get("fits_result")
        head += (f"; fits at {', '.join(f'{k}={v}' for k, v in b['fits'].items())}: {f['kind']}, depth {f['depth']}, "
                 f"{'passed' if f['passed'] else 'FAILED'}" if f else "; no configuration tried fits")
    else:
        head = f"{b['kind']}, depth {b['depth']} (latency {b['latency']}): {'passed' if b['passed'] else 'FAILED'}"
        if b["reason"] and b["passed"]:
            head += f" ({b['reason']})"
    own = ""
    if b["own"]:
        o = b["own"]
        own = (f"; own proof: {o['kind']}, depth {o['depth']}, {'passed' if o['passed'] else 'FAILED'}"
               if o["passed"] is not None else f"; own proof unproven: {o['reason']}")
    return f"{b['block']} ({shown}): stream rules {head}{own}"


#: the longest proof ``prove --depth`` runs: SymbiYosys's unrolling grows with the depth (the ZB/M
#: merger's proof at depth 400 keeps two solvers busy for minutes); a depth of 10^20 ran without end
MAX_DEPTH = 10_000


def check_cache() -> None:
    """The build cache can be written: said before any work, not when the first entry is stored
    (sim/cachefile.py)."""
    from rasterhw.sim.cachefile import check_writable

    check_writable()


@click.command()
@click.argument("block", required=False)
@click.option("--all", "all_blocks", is_flag=True,
              help="Every block of `rasterhw verilog --list` in one campaign, each at its machine's small "
                   "configuration (the hardware flow's Flow.small, named in each result).")
@click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Block parameter, e.g. -p depth=64 (repeatable; default: the testbench's defaults).")
@click.option("--mutants", type=int, default=40, show_default=True, help="Mutations Yosys samples (mutate -list N).")
@click.option("--seed", type=int, default=1, show_default=True,
              help="Seed of Yosys's sampling and of the testbench's stimulus (same seed: same mutants, same runs).")
@scheduler_options("serial")
@click.option("--budget", "budget_s", type=float, default=None, metavar="SECONDS",
              help="--all: wait for no block's build after this many seconds (those blocks are listed as not run; "
                   "the mutants of the blocks built by then all run).")
@click.option("--json", "as_json", is_flag=True,
              help="Print the campaign as JSON (mutants, baseline_passed, killed, equivalent, survived, score, survivors).")
def mutate(block: str | None, all_blocks: bool, params: tuple[str, ...], mutants: int, seed: int, scheduler: str,
           store: str, fresh: bool, budget_s: float | None, as_json: bool) -> None:
    """Mutation coverage of BLOCK: N faults planted by Yosys (mutate) behind one control input,
    one Verilator build, the block's testbench run once per mutant; killed / survived, score.

    Exit 1 if mutant 0 (no mutation) fails its testbench (the campaign is void; with --all: any
    block's). docs/mutation.md."""
    from rasterhw.sim.flow.mutate import campaign, campaign_all, mutation_blocks
    from rasterhw.sim.flow.tasks import check_scheduler

    if all_blocks and (block or params):
        raise RasterhwError("--all runs every block at its stated small configuration: no BLOCK, no -p")
    if budget_s is not None and not all_blocks:
        raise RasterhwError("--budget applies to --all only")
    if not all_blocks and block not in mutation_blocks():
        what = f"no testbench for block {block!r}" if block else "name a block (or --all)"
        raise RasterhwError(f"{what}; blocks: {', '.join(mutation_blocks())}")
    check_cache()
    check_scheduler(scheduler)   # what answers at its address too, before anything runs
    if all_blocks:
        r = campaign_all(mutants=mutants, seed=seed, scheduler=scheduler, store=store,
                         fresh=fresh, progress=not as_json, budget_s=budget_s)
        _emit_blocks(r, as_json, _mutate_line, f"{len(r['blocks'])} blocks in {r['wall_s']:.0f} s "
                                               f"({r['computed']} tasks run, {r['reused']} from the store)")
        if not all(b.get("baseline_passed", True) for b in r["blocks"]):
            sys.exit(1)
        return
    r = campaign(block, block_params(block, params), mutants=mutants, seed=seed, scheduler=scheduler,
                 store=store, fresh=fresh, progress=not as_json)
    if as_json:
        emit_json(r)
    else:
        click.echo(_mutate_line(r))
        click.echo(f"  Yosys {r['yosys_s']:.1f} s, build {r['build_s']:.1f} s, runs {r['runs_s']:.1f} s "
                   f"({r['computed']} run, {r['reused']} from the store); files in {r['dir']}")
        for s in r["survivors"]:
            click.echo(f"  survivor {s['mutant']}: {', '.join(s['src']) or '(no Amaranth src)'}: {s['mutation']}")
    if not r["baseline_passed"]:
        sys.exit(1)


def _mutate_line(r: dict) -> str:
    """One block's campaign in one line."""
    shown = ", ".join(f"{k}={v}" for k, v in r["params"].items())
    if "error" in r:
        return f"{r['block']} ({shown}): not run: {r['error']}"
    score = "void (mutant 0 fails: " + r["baseline_why"] + ")" if r["score"] is None else f"{r['score']:.3f}"
    return (f"{r['block']} ({shown}): {r['mutants']} mutants, {r['killed']} killed, {r['equivalent']} equivalent, "
            f"{r['survived']} survived; score {score}")


def add_commands(group: click.Group) -> None:
    """Add ``synth``, ``fpga``, ``prove`` and ``mutate`` to the ``rasterhw`` group."""
    for cmd in (synth, fpga, prove, mutate):
        group.add_command(cmd)
