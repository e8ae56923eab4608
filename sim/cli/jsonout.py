"""Every ``--json`` output of the command line, in one style (``docs/architecture.md``, "JSON
output"): one line on stdout, keys in snake_case with the unit last (``_s``, ``_ms``, ``_hz``,
``_per_s``), a golden model's value of a measured key ``K`` named ``K_golden``, NumPy numbers
as JSON numbers and paths as strings; every ``rasterhw sim`` result in one key set (:func:`sim_json`).
``tests/test_json_style.py`` walks every command's output."""

from __future__ import annotations

import json
from pathlib import Path

import click

__all__ = ["SIM_SCHEMA", "SIM_JSON_KEYS", "emit_json", "sim_json"]

#: the schema of every ``rasterhw sim --json`` object
SIM_SCHEMA = "rasterhw.sim/1"
#: the top-level keys of every ``rasterhw sim --json`` object, on every machine and engine, in order
#: (``image``, ``waves``, ``gtkw`` follow when written); the machine's own figures are in ``extra``
SIM_JSON_KEYS = ("schema", "block", "scene", "engine", "cycles", "clock_hz", "sim_cycles", "sim_cpu_s",
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
    out = {"schema": SIM_SCHEMA, "block": block, "scene": scene, "engine": res["engine"], "cycles": res["cycles"],
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


def emit_json(obj) -> None:
    """Print ``obj`` as one line of JSON on stdout."""
    click.echo(json.dumps(obj, indent=None, sort_keys=False, default=_default))
