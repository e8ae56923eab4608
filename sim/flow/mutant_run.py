"""One mutant's runs (``rasterhw mutate``): the block's testbench set-up, the Verilator build of a bench
and one run of it with mutant ``k`` active, and the runs every mutant gets. Shared by the campaign
(:mod:`rasterhw.sim.flow.mutate`) and the toggle pass (:mod:`rasterhw.sim.flow.toggle`), which runs
them on the unmutated bench. Nothing here knows a machine.
"""

from __future__ import annotations

from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines import verilator, with_gaps
from rasterhw.sim.engines.runner import HARNESS_V, build_plain_verilator, run_plain_verilator
from rasterhw.sim.testbench import Run, clocks_of, find_testbench
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["CTRL", "SLOW_RUN", "build", "mutation_blocks", "run_mutant", "runs_of", "setup"]

#: the control input Yosys adds (``mutate -ctrl``), read from ``+mutsel=K``
CTRL = "mutsel"
#: the second run of every mutant: idle gaps and back-pressure, as ``tests/test_engines.py``
SLOW_RUN = {"idle": 0.3, "stall": 90, "seed": 5}

def mutation_blocks() -> list[str]:
    """Every block with a registered testbench (what ``mutate`` can run), sorted."""
    from rasterhw.sim import registry

    return sorted(registry.entries("testbenches"))


def setup(block: str, params: dict, seed: int):
    """(testbench, parameters, stimulus, expected, words to collect) of a campaign."""
    if block not in mutation_blocks():
        raise RasterhwError(f"no testbench for block {block!r}; blocks: {', '.join(mutation_blocks())}")
    tb = find_testbench(block)
    p = tb.params(**params)
    stim = tb.stimulus(p, seed)
    exp = tb.expect(p, stim)
    return tb, p, stim, exp, {k: len(v) for k, v in exp.words.items()}


def build(design, opt: str) -> tuple[Path, float]:
    name, generated, defines = design
    return build_plain_verilator(name, "rasterhw_bench", [HARNESS_V], params={}, opt=opt, defines=defines,
                                 generated=generated)


def run_mutant(exe: Path, tb, p: dict, stim, want: dict, mutant: int, *, idle: float = 0.0, stall: int = 0,
         seed: int = 1, clocks: dict | None = None, read=None) -> Run:
    """One run of the mutated bench with mutant ``mutant`` active: the engine's sources, sinks,
    gaps, back-pressure and watchdog (``sim/engines/__init__.py: run``, the plain engine's plusargs);
    ``clocks``: each domain's own :class:`Clock` (a bench built with separate clocks; none: every
    clock the same); ``read``: called with the run's folder before it is removed (what else the
    bench wrote there)."""
    ins = tb.inputs_of(p)
    if idle:
        stim = with_gaps(stim, idle, seed, ins)
    inputs, _outputs = verilator.memory_depths(tb, p, stim, want)
    words = sum(len(w) for w in stim.words.values()) + sum(want.values())
    gaps = sum(sum(int(g) for g in stim.gaps_of(n)) for n in ins)
    max_cycles = (10_000 + 64 * words + gaps) * (1 + stall // 32)   # the engine's watchdog
    if clocks:   # the watchdog counts edges of the first domain's clock: as slow as the slowest
        max_cycles *= -(-max(c.half for c in clocks.values()) // next(iter(clocks.values())).half)
    run_dir = temp_run_folder(exe.parent.parent)
    try:
        plus = verilator.stream_plusargs(run_dir, tb, p, stim, stall=stall, seed=seed, expect_words=want,
                                         inputs=inputs, clocks=clocks)
        meta = run_plain_verilator(exe, [*plus, f"+{CTRL}={mutant}"], run_dir=run_dir, maxcyc=max_cycles)
        got, stamps = verilator.collected(run_dir, tb.outputs_of(p), want)
        if read is not None:
            read(run_dir)
    finally:
        release(run_dir)
    return Run("verilator", got, stamps, run_s=meta["run_s"], protocol_errors=int(meta.get("errors", 0)))


def runs_of(tb) -> list[tuple[str, dict, bool]]:
    """The runs every mutant of ``tb``'s block gets: ``(label, keywords of run_mutant, cycle-exact)``:
    inputs back to back, outputs always ready (cycles exact); idle gaps and back-pressure; and where
    the testbench has them, its separate clocks (a clock-domain crossing) with gaps and back-pressure."""
    runs = [("back to back", {}, True), ("gaps and back-pressure", SLOW_RUN, False)]
    if tb.mutation_clocks:
        clocks = clocks_of(tb.mutation_clocks, tb.domains)
        runs.append(("separate clocks " + " : ".join(f"{d} {c.half}" for d, c in clocks.items()),
                     {**SLOW_RUN, "clocks": clocks}, False))
    return runs
