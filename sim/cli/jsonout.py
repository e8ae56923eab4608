"""Every ``--json`` output of the command line, in one style (``docs/architecture.md``, "JSON
output"): one line on stdout, keys in snake_case with the unit last (``_s``, ``_ms``, ``_hz``,
``_per_s``), a golden model's value of a measured key ``K`` named ``K_golden``, NumPy numbers
as JSON numbers and paths as strings; every ``rasterhw sim`` result in one key set (:func:`sim_json`).
``tests/test_json_style.py`` walks every command's output.

Every document is an object that starts with ``"schema": "rasterhw.COMMAND/N"`` (:data:`SCHEMAS`:
``N`` goes up when a key is renamed or removed, or a value changes meaning; added keys keep it)
and ``"version"`` (``sim/version.py``: the release and the commit). A command whose output is a
list of rows (``scenes``, ``machines``, ``report``, ``bench``, ``soak``, ``synth --all``) puts
them under ``"rows"``."""

from __future__ import annotations

import json
from pathlib import Path

import click

__all__ = ["SCHEMAS", "SIM_SCHEMA", "SIM_JSON_KEYS", "document", "emit_json", "schema", "sim_json"]

#: every command's ``--json`` document: command (a subcommand as ``GROUP-SUB``) -> its schema's number
SCHEMAS = {"scenes": 1, "machines": 1, "render": 1, "compare": 1, "sim": 1, "report": 1, "bench": 1,
           "soak": 1, "sweep": 1, "synth": 1, "fpga": 1, "prove": 1, "mutate": 1, "cache-info": 1,
           "cache-clean": 1}


def schema(command: str) -> str:
    """``"rasterhw.COMMAND/N"`` of ``command`` (:data:`SCHEMAS`)."""
    if command not in SCHEMAS:
        raise RuntimeError(f"--json of {command!r}: no schema in sim/cli/jsonout.py SCHEMAS")
    return f"rasterhw.{command}/{SCHEMAS[command]}"


#: the schema of every ``rasterhw sim --json`` object
SIM_SCHEMA = schema("sim")
#: the top-level keys of every ``rasterhw sim --json`` object, on every machine and engine, in order
#: (``image``, ``waves``, ``gtkw`` follow when written); the machine's own figures are in ``extra``
SIM_JSON_KEYS = ("schema", "version", "block", "scene", "engine", "cycles", "clock_hz", "sim_cycles", "sim_cpu_s",
                 "cycles_per_cpu_s", "run_s", "build_s", "wall_s", "cycles_per_s", "mismatches", "cycle_mismatches",
                 "pixels_compared", "extra")
#: keys a block's driver gives that the common keys replace (measured once, here, for every machine)
_REPLACED = ("run_s", "build_s", "wall_s", "cycles_per_s", "sim_cycles", "sim_s")


def sim_json(block: str, scene: str, res: dict, tally, wall_s: float, aliases: tuple[str, ...] = ()) -> dict:
    """One ``rasterhw sim`` result in the common key set (:data:`SIM_JSON_KEYS`): from the block's
    driver ``res`` (the registry's sim contract, ``registry.SIM_KEYS``) its ``engine``, ``cycles``
    (the machine's own cycle count), ``clock_hz``, ``mismatches`` (words or pixels that differ
    from the golden model, an integer), ``cycle_mismatches`` (cycle counts that differ from the
    golden cycle model; None where the run compares none) and ``pixels_compared``; from every
    engine run of the command (``tally``: ``engines.tally``) ``sim_cycles`` (the simulators'
    clocks, summed), ``sim_cpu_s`` (their CPU: the Verilator child's own, pysim's in this process;
    None on cocotb), ``run_s``, ``build_s``; ``wall_s`` (the whole run); every other key of ``res``
    in ``extra``, but ``aliases`` (the block's ``SimBlock.aliases``: its driver's second names of a
    common key)."""
    for k in ("engine", "cycles", "clock_hz", "mismatches", "pixels_compared"):
        if k not in res:
            raise RuntimeError(f"sim {block}: the driver gave no {k!r} (registry.SIM_KEYS)")
    cpu, sim_cycles, run_s = tally.cpu_s, tally.sim_cycles, tally.run_s
    from rasterhw.sim.version import version

    out = {"schema": SIM_SCHEMA, "version": version(), "block": block, "scene": scene, "engine": res["engine"], "cycles": res["cycles"],
           "clock_hz": res["clock_hz"], "sim_cycles": sim_cycles, "sim_cpu_s": cpu,
           "cycles_per_cpu_s": sim_cycles / cpu if cpu else None, "run_s": run_s, "build_s": tally.build_s,
           "wall_s": wall_s, "cycles_per_s": sim_cycles / run_s if run_s > 0 else None,
           "mismatches": int(res["mismatches"]), "cycle_mismatches": res.get("cycle_mismatches"),
           "pixels_compared": res["pixels_compared"]}
    taken = {*out, *_REPLACED, *aliases, "waves", "gtkw", "image"}
    out["extra"] = {k: v for k, v in res.items() if k not in taken}
    out.update({k: res[k] for k in ("image", "waves", "gtkw") if k in res})
    return out


def _default(o):
    import numpy as np

    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    return str(o)


def _command() -> str:
    """The running command's name (``sim``; a subcommand as ``cache-info``), from click's context."""
    ctx = click.get_current_context(silent=True)
    names = []
    while ctx is not None and ctx.parent is not None:
        names.append(ctx.info_name)
        ctx = ctx.parent
    if not names:
        raise RuntimeError("emit_json outside a command: say its command")
    return "-".join(reversed(names))


def document(obj, command: str) -> dict:
    """``obj`` as the ``--json`` document of ``command``: ``schema`` and ``version`` first, then
    the object's own keys, or a list under ``rows``."""
    from rasterhw.sim.version import version

    head = {"schema": schema(command), "version": version()}
    if isinstance(obj, dict):
        return {**head, **{k: v for k, v in obj.items() if k not in head}}
    return {**head, "rows": list(obj)}


def emit_json(obj, command: str | None = None) -> None:
    """Print ``obj`` as the ``--json`` document (:func:`document`) of ``command`` (default: the
    running click command) on stdout, one line."""
    doc = document(obj, command or _command())
    click.echo(json.dumps(doc, indent=None, sort_keys=False, default=_default))
