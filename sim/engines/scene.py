"""One scene run, declared as data by a block and run by one generic path (``rasterhw sim``).

A block that ``rasterhw sim`` runs declares its scene level once, beside its testbench, as a
:class:`SceneRun` (in its machine's ``sim/NAME/scene.py``): :meth:`SceneRun.check` (option checks
beyond the registry's types and choices), :meth:`SceneRun.golden` (the golden result, computed
once, from which every expected word derives), :meth:`SceneRun.jobs` (the engine runs: testbench,
block parameters, stimulus and expected words, each a :class:`Job`; a block whose later runs take an
earlier run's words, as EXPERTS' SLP then PXP, gives them from :meth:`SceneRun.more`) and
:meth:`SceneRun.result` (the frame from the words, the machine's own figures). :meth:`SceneRun.simulate` runs it for every
machine the same way: engine names from the registry, one progress bar, ``engines.run``,
``testbench.compare``, the clock from the block's flow, the registry's sim keys
(``registry.SIM_KEYS``; ``rasterhw sim --json`` puts them in one key set: ``sim/cli/jsonout.py``).
It knows no machine.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.engines import run as run_engine
from rasterhw.sim.testbench import Expected, Run, Stimulus, Testbench, compare

__all__ = ["Done", "Job", "SceneRun", "run_job"]


@dataclass
class Job:
    """One engine run of a scene: the testbench with its block parameters, the stimulus, the
    expected words, ``engines.run``'s other keywords (``build``, ``max_cycles``, ``stall``, ``idle``,
    ``seed``, ``clocks``), whether the golden cycle count must be met exactly and ``collect``: other
    output ports to collect, not compared (port -> words; e.g. a line log the block checks itself)."""

    tb: Testbench
    params: dict
    stim: Stimulus
    expect: Expected
    run: dict = field(default_factory=dict)
    cycle_exact: bool = True
    name: str = ""                        # for the progress line (e.g. "processor (1, 0)")
    collect: dict = field(default_factory=dict)


@dataclass
class Done:
    """A job after its run: what the engine saw and ``testbench.compare``'s verdict."""

    job: Job
    got: Run
    cmp: dict


class SceneRun:
    """Base of every block's scene level; a subclass sets :attr:`block` and the three methods.

    ``block``: the ``rasterhw sim`` name; ``engines``: the engines it takes (the registry's by
    default); ``workers``: jobs run at once on Verilator (the first alone: it builds the bench);
    ``steps``: the progress bar's names of golden, HDL and result.
    """

    block: str = ""
    engines: tuple[str, ...] = registry.ENGINES
    workers: int = 1
    steps: tuple[str, str, str] = ("golden model", "HDL simulation", "frame")

    # ------------------------------------------------------------------ what differs per block
    def check(self, engine: str, **options) -> None:
        """Refuse bad option values (one-line ``RasterhwError``) before any work; default none."""

    def golden(self, scene, width: int, height: int, *, engine: str, **options) -> object:   # pragma: no cover
        raise NotImplementedError

    def jobs(self, gold, *, engine: str, **options) -> list[Job]:   # pragma: no cover - abstract
        raise NotImplementedError

    def more(self, gold, done: list[Done], *, engine: str, **options) -> list[Job]:
        """Jobs that take the words of those ``done`` so far (run after them); default none."""
        return []

    def result(self, gold, done: list[Done], *, engine: str, **options) -> dict:
        """The machine's own keys: at least ``pixels_compared``; ``cycles``, ``mismatches`` and
        ``cycle_mismatches`` where the defaults (the longest run's cycles; the words that differ,
        every job summed; cycle counts that differ) are not the machine's; ``frame_rgb``."""
        return {}

    # ------------------------------------------------------------------ the one generic path
    def clock_hz(self, done: list[Done]) -> float | None:
        """The block's clock: its flow's first named clock (None: the paper gives none)."""
        clocks = registry.flow(done[0].job.tb.block).clocks if done else ()
        return clocks[0].hz if clocks else None

    def simulate(self, scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False,
                 workers: int | None = None, **options) -> dict:
        """The registry's sim-block contract (``registry.SimBlock``): ``scene`` a Scene or a built-in
        name; the keys of ``registry.SIM_KEYS``, ``cycle_mismatches``, ``run_s``, ``build_s``,
        ``sim_cycles``, ``cycles_per_s``, ``wall_s`` (the simulations, for callers other than ``rasterhw sim``, whose
        JSON measures them once for every machine), ``golden_wall_s`` (the golden model and the jobs'
        stimulus), ``hdl_wall_s`` (the simulations, builds included) and the block's :meth:`result`.
        ``workers``: jobs at once on Verilator (default :attr:`workers`)."""
        t0 = time.perf_counter()
        if engine not in self.engines:
            raise RasterhwError(f"sim {self.block}: engine must be one of {', '.join(self.engines)}, not {engine!r}")
        self.check(engine, **options)
        if isinstance(scene, str):
            from rasterhw.golden_model.scenes import build_scene

            scene = build_scene(scene)
        bar = _Steps(f"{self.block} {engine}", self.steps) if progress else None
        gold = self.golden(scene, width, height, engine=engine, **options)
        jobs = self.jobs(gold, engine=engine, **options)
        t1 = time.perf_counter()
        if bar is not None:
            bar.next()

        def one(job: Job) -> Done:
            done = run_job(job, engine)
            if done.got.protocol_errors:
                raise RasterhwError(f"sim {self.block}{' ' + job.name if job.name else ''} on {engine}: "
                                    f"{done.got.protocol_errors} clocks broke the stream rules")
            if bar is not None and len(jobs) > 1:
                bar.note(f"{job.name}: {done.got.cycles} cycles, {done.cmp['mismatches']} mismatches")
            return done

        workers = self.workers if workers is None else workers
        done = self._run_all(one, jobs, engine, workers)
        while nxt := self.more(gold, done, engine=engine, **options):
            done += self._run_all(one, nxt, engine, workers)
        t2 = time.perf_counter()
        if bar is not None:
            bar.next()
        res = self.result(gold, done, engine=engine, **options)
        if bar is not None:
            bar.close()
        cyc = [d.cmp["cycle_mismatches"] for d in done if d.cmp["cycle_mismatches"] is not None]
        runs = [d.got for d in done]
        out = {"block": self.block, "engine": engine,
               "cycles": max((r.cycles for r in runs), default=0), "clock_hz": self.clock_hz(done),
               "mismatches": sum(d.cmp["mismatches"] for d in done), "cycle_mismatches": sum(cyc) if cyc else None,
               **res,
               "run_s": sum(r.run_s for r in runs), "build_s": sum(r.build_s for r in runs),
               "sim_cycles": sum(r.cycles for r in runs)}
        out["mismatches"] = int(out["mismatches"])
        out["cycles_per_s"] = out["sim_cycles"] / out["run_s"] if out["run_s"] > 0 else None
        out.update(golden_wall_s=t1 - t0, hdl_wall_s=t2 - t1, wall_s=time.perf_counter() - t0)
        return out

    @staticmethod
    def _run_all(one, jobs: list[Job], engine: str, workers: int) -> list[Done]:
        """Every job, in order; on Verilator ``workers`` at once after the first (which builds)."""
        workers = max(1, min(int(workers), os.cpu_count() or 1))
        if engine != "verilator" or workers == 1 or len(jobs) < 2:
            return [one(j) for j in jobs]
        first = one(jobs[0])
        with ThreadPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(one, j) for j in jobs[1:]]
            try:
                return [first, *(f.result() for f in futures)]
            except BaseException:
                for f in futures:
                    f.cancel()
                raise


def run_job(job: Job, engine: str) -> Done:
    """``job`` on ``engine`` (``engines.run``, collecting every expected word), compared word for word
    (``testbench.compare``)."""
    got = run_engine(job.tb, job.params, job.stim, engine=engine,
                     expect_words={**{k: len(v) for k, v in job.expect.words.items()}, **job.collect}, **job.run)
    return Done(job, got, compare(job.expect, got, cycle_exact=job.cycle_exact))


class _Steps:
    """One progress bar of a scene run's three steps; the bar names the step now running."""

    def __init__(self, desc: str, steps: tuple[str, ...]) -> None:
        from tqdm import tqdm

        self.steps, self.k = steps, 0
        self.bar = tqdm(total=len(steps), desc=desc, unit="step", file=sys.stderr)
        self.bar.set_postfix_str(steps[0])

    def next(self) -> None:
        self.k += 1
        self.bar.update(1)
        if self.k < len(self.steps):
            self.bar.set_postfix_str(self.steps[self.k])

    def note(self, msg: str) -> None:
        self.bar.write(msg, file=sys.stderr)

    def close(self) -> None:
        self.bar.update(len(self.steps) - self.k)
        self.bar.close()
