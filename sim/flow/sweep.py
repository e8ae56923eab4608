"""Design-space sweeps: ``rasterhw sweep TARGET --param NAME=V1,V2 ...``.

``TARGET`` is a sim block (``rasterhw sim``'s names: the block's HDL against its golden model) or
``render:ARCH`` (a golden arch). Each ``--param`` names one of the target's registered options
(``registry.Option``: its type and choices check every value before anything runs); the sweep is
the cross product of the values, parameters in the order given, the first one varying slowest,
and scenes (``--scene``, several allowed) innermost. Every point is one task of
:mod:`rasterhw.sim.flow.tasks`, so the points run on any scheduler, come back in this order,
are kept in the store as they finish and are not run again.

:func:`write_outputs` writes ``points.csv`` (one row per point, nested results flattened to
``key.sub``) and one plot per swept parameter: every numeric result against that parameter, a
line per combination of the other parameters.
"""

from __future__ import annotations

import csv
import itertools
import json
import sys
from collections.abc import Callable
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.flow.tasks import Runner, Task, task_modules

__all__ = ["parse_param", "plan", "run_sweep", "write_outputs"]

#: point keys that are not results to plot (who ran it, identifiers)
_NOT_PLOTTED = {"pid", "worker", "width", "height", "clock_hz"}


def _target(target: str):
    """``"render:ARCH"`` -> ("render", arch, options); a sim block -> ("sim", block, options)."""
    if target.startswith("render:"):
        arch = target.split(":", 1)[1]
        archs = registry.archs()
        if arch not in archs:
            raise RasterhwError(f"unknown arch {arch!r}; archs: {', '.join(archs)}")
        return "render", arch, archs[arch][1].options
    blocks = registry.sim_blocks()
    if target not in blocks:
        raise RasterhwError(f"unknown sweep target {target!r}; sim blocks: {', '.join(blocks)}; "
                            f"golden archs: {', '.join('render:' + a for a in registry.archs())}")
    return "sim", target, blocks[target][1].options


def _convert(o: registry.Option, text: str, who: str):
    t = text.strip()
    try:
        if o.type is bool:
            low = t.lower()
            if low not in ("1", "0", "true", "false", "yes", "no", "on", "off"):
                raise ValueError(t)
            v = low in ("1", "true", "yes", "on")
        elif o.type is int:
            v = int(t, 10)
        elif o.type is float:
            v = float(t)
        else:
            v = t
    except ValueError:
        kind = {int: "an integer", float: "a number", bool: "true or false"}.get(o.type, "a string")
        raise RasterhwError(f"{who}: --param {o.name}: {text!r} is not {kind}") from None
    if o.choices and v not in o.choices:
        raise RasterhwError(f"{who}: --param {o.name}: must be one of {', '.join(o.choices)}, not {text!r}")
    return v


def parse_param(text: str, options, who: str) -> tuple[str, list]:
    """``"NAME=V1,V2"`` -> (name, typed values), checked against the target's options."""
    name, eq, vals = text.partition("=")
    name = name.strip().replace("-", "_")
    byname = {o.name: o for o in options}
    if not eq or not name:
        raise RasterhwError(f"--param must look like NAME=V1,V2,..., not {text!r}")
    if name not in byname:
        raise RasterhwError(f"{who} has no parameter {name!r}; it takes: {', '.join(byname) or 'none'}")
    items = [v for v in vals.split(",")]
    if not vals.strip() or any(not v.strip() for v in items):
        raise RasterhwError(f"--param {name}: an empty value in {text!r}")
    values = [_convert(byname[name], v, who) for v in items]
    if len(set(map(repr, values))) != len(values):
        raise RasterhwError(f"--param {name}: a value is given twice in {text!r}")
    return name, values


def plan(target: str, params: list[str], *, scenes: list[str] | None = None, size: tuple[int, int] | None = None,
         engine: str | None = None) -> tuple[list[Task], list[dict]]:
    """The sweep's tasks and each point's swept parameters, in order; every input is checked
    here (one-line errors), before any scheduler starts."""
    kind, name, options = _target(target)
    who = target if kind == "sim" else f"render:{name}"
    axes: dict[str, list] = {}
    for p in params:
        k, vals = parse_param(p, options, who)
        if k in axes:
            raise RasterhwError(f"--param {k} given twice")
        axes[k] = vals
    if kind == "render" and engine is not None:
        raise RasterhwError(f"{who} is a golden model: --engine does not apply")
    if kind == "sim" and engine is None:
        engine = "verilator"
    from rasterhw.golden_model.scenes import SCENES

    scene_list = list(scenes) if scenes else [None]
    for s in scene_list:
        if s is not None and s not in SCENES and not Path(s).is_file():
            raise RasterhwError(f"unknown scene {s!r} (a built-in name from `rasterhw scenes`, or an .obj/.ply file)")
    tasks, points = [], []
    for combo in itertools.product(*axes.values()):
        for s in scene_list:
            pv = dict(zip(axes, combo, strict=True))
            tasks.append(Task(kind, name, pv, scene=s, size=size, engine=engine))
            points.append(pv)
    return tasks, points


def run_sweep(target: str, params: list[str], *, scenes: list[str] | None = None,
              size: tuple[int, int] | None = None, engine: str | None = None, scheduler: str = "local",
              store: str | Path | None = None, fresh: bool = False, progress: bool = False,
              on_point: Callable[[int, dict], None] | None = None) -> dict:
    """Run the sweep; ``{"scheduler", "target", "computed", "reused", "points": [{"params", ...result}]}``
    in cross-product order. ``progress``: a bar over all points on stderr (on a terminal);
    ``on_point(i, result)`` after each point finishes (tests)."""
    tasks, pvals = plan(target, params, scenes=scenes, size=size, engine=engine)
    from tqdm import tqdm

    bar = tqdm(total=len(tasks), desc=f"sweep {target}", unit="point", disable=None if progress else True,
               file=sys.stderr)
    try:
        with Runner(scheduler, store=store, fresh=fresh, preload=task_modules(tasks)) as run:
            def done(i, h):
                bar.update(1)
                if on_point is not None:
                    on_point(i, run.result(h))

            results = run.map(tasks, progress=done)
            where = run.address()
            computed, reused = run.computed, run.reused
    finally:
        bar.close()
    return {"scheduler": where, "target": target, "computed": computed, "reused": reused,
            "points": [{"params": p, **r} for p, r in zip(pvals, results, strict=True)]}


def _flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flat(v, key + "."))
        elif isinstance(v, list):
            out[key] = json.dumps(v)
        else:
            out[key] = v
    return out


def write_outputs(result: dict, out_dir: str | Path) -> list[Path]:
    """``points.csv`` and ``NAME.png`` per swept parameter under ``out_dir``; the paths written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    points = result["points"]
    swept = list(points[0]["params"]) if points else []
    rows = [{**{f"param.{k}": v for k, v in p["params"].items()}, **_flat({k: v for k, v in p.items() if k != "params"})}
            for p in points]
    cols = list(dict.fromkeys(c for r in rows for c in r))
    written = [out / "points.csv"]
    with open(written[0], "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    numeric = [c for c in cols if not c.startswith("param.") and c.split(".")[0] not in _NOT_PLOTTED and c not in swept
               and all(isinstance(r.get(c), (int, float)) and not isinstance(r.get(c), bool) for r in rows)]
    if not swept or not numeric:
        return written
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for p in swept:
        others = [q for q in swept if q != p]
        ncol = min(4, len(numeric))
        nrow = -(-len(numeric) // ncol)
        fig, axs = plt.subplots(nrow, ncol, figsize=(4 * ncol, 3 * nrow), squeeze=False)
        groups: dict[tuple, list[dict]] = {}
        for r in rows:
            groups.setdefault(tuple(r[f"param.{q}"] for q in others) + (r.get("scene"),), []).append(r)
        for ax, m in zip(axs.flat, numeric, strict=False):
            for g, rs in groups.items():
                xs = [r[f"param.{p}"] for r in rs]
                label = ", ".join(f"{q}={v}" for q, v in zip([*others, "scene"], g, strict=True) if v is not None)
                ax.plot(xs, [r[m] for r in rs], marker="o", label=label or None)
            ax.set_xlabel(p)
            ax.set_title(m, fontsize=9)
            if isinstance(rows[0][f"param.{p}"], (int, float)) and len({r[f'param.{p}'] for r in rows}) > 1:
                vals = sorted({r[f"param.{p}"] for r in rows})
                if vals[0] > 0 and vals[-1] / vals[0] >= 8:
                    ax.set_xscale("log", base=2)
        for ax in list(axs.flat)[len(numeric):]:
            ax.axis("off")
        if len(groups) > 1:
            axs.flat[0].legend(fontsize=7)
        fig.suptitle(f"{result['target']}: every numeric result against {p}")
        fig.tight_layout()
        path = out / f"{p}.png"
        fig.savefig(path, dpi=80)
        plt.close(fig)
        written.append(path)
    return written
