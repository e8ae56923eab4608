"""Random differential runs: every HDL block against its golden model, on Verilator.

``rasterhw soak --pixels N --seed S`` runs rounds of random stimulus through each block until
``N`` output pixels of that block have been compared bit for bit with the golden model (the
last round may overshoot). Every round draws its own settings from ``numpy.random`` seeded by
``(S, block, round)``: the same seed gives the same rounds, so a failure printed as
``seed S`` reproduces with ``--seed S --block NAME``. A block stops at its first round with a
mismatch. Rounds are tasks of :mod:`rasterhw.sim.flow.tasks` (``--scheduler``: in this process,
a local Dask cluster, or any Dask scheduler); whichever runs them, each block stops at the same
round with the same row.

A machine declares its rounds in its registry entry (``Machine.soak``: block name ->
``"module:round"``, a ``round(rng, k) -> {"pixels", "mismatches", "run_s", "settings"}`` for
round number ``k``); each round's module says what it randomises (e.g. ``sim/zbm/soak.py``).
This module knows no machine. A machine without HDL (the vector Z-buffer) declares no round.
"""

from __future__ import annotations

import sys
import time
from collections import deque
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.flow.tasks import Runner, Task
from tqdm import tqdm

__all__ = ["run_soak", "soak_blocks", "soak_round"]


def _rng(seed: int, block: str, k: int) -> np.random.Generator:
    return np.random.default_rng([seed, sum(block.encode()) * 7919 + len(block), k])


def soak_blocks() -> dict[str, str]:
    """Every block with a soak round -> its ``"module:round"``, in block-name order."""
    return dict(sorted(registry.entries("soak").items()))


def soak_round(block: str, seed: int, k: int, ref: str | None = None) -> dict:
    """Round ``k`` of ``block`` for seed ``seed`` (one task of :mod:`rasterhw.sim.flow.tasks`):
    ``ref`` is its ``"module:round"`` (default: the block's registered round)."""
    fn = registry.load(ref or soak_blocks()[block])
    r = fn(_rng(seed, block, k), k)
    return {"block": block, "round": k, "pixels": int(r["pixels"]), "mismatches": int(r["mismatches"]),
            "settings": r["settings"]}


def _round_task(block: str, seed: int, k: int, ref: str | None) -> Task:
    params = {"block": block, "seed": seed, "k": k, **({"ref": ref} if ref else {})}
    return Task("call", "rasterhw.sim.flow.soak:soak_round", params)


def run_soak(*, pixels: int, seed: int, blocks: list[str] | None = None, progress: bool = True,
             max_rounds: int = 100_000, scheduler: str = "serial", store: str | Path | None = None,
             fresh: bool = False, rounds: dict[str, str] | None = None) -> list[dict]:
    """Random rounds per block until ``pixels`` output pixels were compared or a round
    mismatches (the block stops there: its seed reproduces it); one row per block: ``block,
    seed, rounds, pixels_compared, mismatches, wall_s`` (from the soak's start until the block
    stopped: the blocks' rounds run side by side), ``failures`` (the failing round: number and
    settings), ``scheduler``.

    The rounds run on ``scheduler`` (:class:`~rasterhw.sim.flow.tasks.Runner`: ``serial``,
    ``local[:N]``, a Dask address), a few rounds ahead of the one being checked; each block's
    rounds are taken in round order, so every scheduler stops at the same round with the same
    row (apart from ``wall_s`` and ``scheduler``); rounds started past the stopping one are
    cancelled and their results ignored. ``store``: keep every finished round there (a rerun
    of the same seed reuses them; ``fresh`` recomputes). ``rounds``: block -> ``"module:round"``
    instead of the registry's (tests)."""
    table = dict(rounds) if rounds is not None else soak_blocks()
    names = list(table) if not blocks else list(dict.fromkeys(blocks))
    for b in names:
        if b not in table:
            raise RasterhwError(f"no soak for block {b!r}; blocks: {', '.join(table)}")
    if not isinstance(pixels, int) or pixels < 1:
        raise RasterhwError(f"--pixels must be a positive integer, not {pixels!r}")
    refs = {b: (table[b] if rounds is not None else None) for b in names}
    # one bar over every block's pixels, with rate and ETA (the full soak is hours); the per-round
    # lines go above it
    bar = tqdm(total=pixels * len(names), unit="px", unit_scale=True, desc="soak", disable=not progress,
               file=sys.stderr, dynamic_ncols=True)
    preload = ["rasterhw.sim.flow.soak", *sorted({table[b].split(":", 1)[0] for b in names})]
    with bar, Runner(scheduler, store=store, fresh=fresh, preload=preload) as run:
        ahead = max(1, run.nworkers) if run.client is not None else 1
        t0 = time.perf_counter()
        st = {b: {"next": 0, "k": 0, "done": 0, "bad": 0, "failures": [], "queue": deque(), "wall": None}
              for b in names}
        active = list(names)
        try:
            while active:
                for b in active:            # keep up to `ahead` rounds of every block in flight
                    s = st[b]
                    # one round until the block's first result says how many pixels a round
                    # gives (a pixel-bus round can hold them all); then up to `ahead`, unless the
                    # rounds in flight will very likely finish the block. A round started in vain
                    # is cancelled, but one already running on a worker runs to its end.
                    while len(s["queue"]) < (ahead if s["k"] else 1) and s["next"] < max_rounds:
                        if s["k"] and s["done"] + len(s["queue"]) * s["done"] / s["k"] >= pixels:
                            break
                        s["queue"].append(run.submit(_round_task(b, seed, s["next"], refs[b])))
                        s["next"] += 1
                for b in list(active):
                    s = st[b]
                    if not s["queue"]:
                        s["queue"].append(run.submit(_round_task(b, seed, s["next"], refs[b])))
                        s["next"] += 1
                    h = s["queue"].popleft()
                    r = run.result(h)
                    k = s["k"]
                    s["done"] += r["pixels"]
                    s["bad"] += r["mismatches"]
                    s["k"] += 1
                    bar.update(max(0, min(r["pixels"], pixels - (s["done"] - r["pixels"]))))
                    bar.set_postfix_str(f"{b} round {k}", refresh=False)
                    if progress:
                        bar.write(f"soak {b} round {k}: {r['pixels']} pixels, {r['mismatches']} mismatches "
                                  f"({r['settings']}) [{r['worker']}]", file=sys.stderr)
                    if r["mismatches"]:
                        s["failures"].append({"round": k, "mismatches": r["mismatches"], "settings": r["settings"]})
                        print(f"soak {b}: round {k} mismatches; reproduce: rasterhw soak --seed {seed} --block {b} "
                              f"--pixels {pixels}", file=sys.stderr, flush=True)
                    if r["mismatches"] or s["done"] >= pixels or s["k"] >= max_rounds:
                        for rest in s["queue"]:
                            run.cancel(rest)
                        s["queue"].clear()
                        s["wall"] = time.perf_counter() - t0
                        bar.update(max(0, pixels - s["done"]))   # a block that stopped early: its rest counts as done
                        active.remove(b)
        finally:
            for s in st.values():
                for rest in s["queue"]:
                    run.cancel(rest)
        where = run.address()
    return [{"block": b, "seed": seed, "rounds": st[b]["k"], "pixels_compared": st[b]["done"],
             "mismatches": st[b]["bad"], "wall_s": round(st[b]["wall"], 1), "failures": st[b]["failures"],
             "scheduler": where} for b in names]
