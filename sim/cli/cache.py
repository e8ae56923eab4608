"""``rasterhw cache info|clean``: what the build cache holds, and pruning it (``sim/cacheinfo.py``).

Errors (a size or age that is not one) are ``RasterhwError``: one line ``error: ...``, exit 2.
"""

from __future__ import annotations

import time

import click
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cli.jsonout import emit_json

__all__ = ["cache"]


def _mb(n: int) -> str:
    return f"{n / (1 << 20):,.1f} MB"


def _ago(t: float) -> str:
    s = max(0.0, time.time() - t)
    for unit, n in (("d", 86400), ("h", 3600), ("m", 60)):
        if s >= n:
            return f"{s / n:.1f}{unit} ago"
    return f"{s:.0f}s ago"


@click.group()
def cache() -> None:
    """What the build cache holds (Verilog texts, Verilator builds, gcc profiles, runtime objects,
    the task store, synthesis, proof, place-and-route and mutation records), and pruning it.

    \b
    The cache is build/ of a checkout, else RASTERHW_CACHE, else the user's cache folder.
    RASTERHW_CACHE_MAX=SIZE prunes it to SIZE after every command (least recently used first)."""


@cache.command()
@click.option("--json", "as_json", is_flag=True,
              help="Print {root, total_bytes, kinds, entries: [{path, kind, design, size_bytes, last_use, ...}]}.")
def info(as_json: bool) -> None:
    """List the cache's entries: kind, design, size, last use (least recently used first)."""
    from rasterhw.sim.cacheinfo import entries, total_bytes
    from rasterhw.sim.paths import BUILD_ROOT

    found = entries(BUILD_ROOT)
    kinds: dict[str, dict] = {}
    for e in found:
        k = kinds.setdefault(e.kind, {"entries": 0, "size_bytes": 0})
        k["entries"] += 1
        k["size_bytes"] += e.size_bytes
    total = total_bytes(BUILD_ROOT)
    if as_json:
        emit_json({"root": str(BUILD_ROOT), "total_bytes": total, "kinds": dict(sorted(kinds.items())),
                   "entries": [e.to_json(BUILD_ROOT) for e in found]})
        return
    click.echo(f"{'kind':<20} {'design':<28} {'size':>11}  {'last use':<13} path")
    for e in found:
        busy = f"  [in use: {e.in_use}]" if e.in_use else ""
        click.echo(f"{e.kind:<20} {(e.design or '-')[:28]:<28} {_mb(e.size_bytes):>11}  {_ago(e.last_use):<13} "
                   f"{e.path.relative_to(BUILD_ROOT)}{busy}")
    click.echo("")
    for kind, k in sorted(kinds.items(), key=lambda kv: -kv[1]["size_bytes"]):
        click.echo(f"{kind:<20} {k['entries']:>5} entries {_mb(k['size_bytes']):>12}")
    click.echo(f"{'total':<20} {len(found):>5} entries {_mb(total):>12}  in {BUILD_ROOT}")


@cache.command()
@click.option("--older-than", "older_than", default=None, metavar="AGE",
              help="Remove entries last used longer ago than AGE (7d, 12h, 30m, 90s, 2w; a bare number is days).")
@click.option("--max-size", "max_size", default=None, metavar="SIZE",
              help="Then remove the least recently used entries until the cache takes at most SIZE "
                   "(100M, 2G, 500K; 1024-based).")
@click.option("--all", "everything", is_flag=True, help="Remove every entry not in use.")
@click.option("--dry-run", is_flag=True, help="Say what would be removed; remove nothing.")
@click.option("--json", "as_json", is_flag=True,
              help="Print {removed: [...], removed_bytes, kept_in_use: [...], total_bytes, max_size_bytes, over_cap}.")
def clean(older_than: str | None, max_size: str | None, everything: bool, dry_run: bool, as_json: bool) -> None:
    """Remove cache entries, least recently used first; never one in use (a build lock another
    process holds, a run or build of a running process)."""
    from rasterhw.sim.cacheinfo import clean as run_clean
    from rasterhw.sim.cacheinfo import parse_age, parse_size
    from rasterhw.sim.paths import BUILD_ROOT

    age = parse_age(older_than) if older_than is not None else None
    cap = parse_size(max_size) if max_size is not None else None
    if everything:
        if age is not None or cap is not None:
            raise RasterhwError("--all removes every entry not in use: give it without --older-than and --max-size")
        cap = 0
    if age is None and cap is None:
        raise RasterhwError("say what to remove: --older-than AGE, --max-size SIZE (or both), or --all")
    r = run_clean(BUILD_ROOT, older_than=age, max_size=cap, dry_run=dry_run)
    if as_json:
        emit_json({"root": str(BUILD_ROOT), "dry_run": dry_run, **r})
    else:
        verb = "would remove" if dry_run else "removed"
        for e in r["removed"]:
            click.echo(f"{verb} {e['kind']:<20} {_mb(e['size_bytes']):>11}  {e['path']}")
        for e in r["kept_in_use"]:
            click.echo(f"kept   {e['kind']:<20} {_mb(e['size_bytes']):>11}  {e['path']} (in use: {e['in_use']})")
        click.echo(f"{verb} {len(r['removed'])} entries, {_mb(r['removed_bytes'])}; the cache "
                   f"{'would take' if dry_run else 'takes'} {_mb(r['total_bytes'])} ({BUILD_ROOT})")
    if r["over_cap"]:
        click.echo(f"warning: entries in use keep the cache above {_mb(cap)}", err=True)
