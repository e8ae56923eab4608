"""Play a :class:`PixelStream` into the SNU pixel-bus HDL and check it against the golden model.

:func:`simulate_pixelbus` runs the block's testbench (``sim/snu/testbench.py: BusBench``, the
frame memory streamed out by the engines' ``ReadOut``, ``sim/engines/readout.py``) on the generic engines
(``sim/engines/``: Amaranth pysim, plain Verilator) and compares the frame and the cycle count
with ``golden_model/snu/pixelbus.py`` (every write's acceptance clock against the golden cycle
model is a test's own pysim loop: ``tests/snu/snu_pixelbus_pysim.py``). ``rasterhw sim pixelbus --engine verilator`` runs the whole frame instead (clear, the
producers' timing, swap: ``sim/snu/frame.py``).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.snu import pixelbus as golden
from rasterhw.golden_model.snu.formats import Z_BITS
from rasterhw.golden_model.snu.gouraud import scan_convert
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.sim import engines
from rasterhw.sim.snu.frame import frame_run
from rasterhw.sim.snu.testbench import frame_of
from rasterhw.sim.testbench import compare, find_testbench

__all__ = ["ENGINES", "measure_rates", "simulate_pixelbus", "simulate_scene"]

ENGINES = (*engines.ENGINES, *engines.ALIASES)   # pysim, verilator, cocotb-verilator, cocotb-icarus, icarus


def simulate_pixelbus(stream: PixelStream, *, engine: str = "pysim", gaps: np.ndarray | None = None,
                      progress: bool = False) -> dict:
    """Run ``stream`` through the pixel-bus HDL, compare with the golden model.

    The block's testbench (``BusBench``) on ``engine`` (``sim/engines/``), ``gaps`` idle clocks
    before each write. Returns ``{"block": "pixelbus", "engine", "cycles", "clock_hz": 12.5e6,
    "pixels_compared", "mismatches", "wall_s", "cycles_per_s", "frame_rgb"}`` plus
    ``"cycles_golden"``, ``"cycle_mismatches"`` (0 or 1, also counted in ``mismatches``), ``"writes"`` and ``"build_s"`` (simulator build, 0 for pysim and for a
    build already made).  ``cycles``: the clock the read-out started in, the first clock after the
    last write's memory cycle (the golden model's cycle count).  ``wall_s`` is the whole call.
    ``mismatches`` counts read-out words (pixels) whose RGB or Z differs from the golden frame,
    plus one if the cycle count differs from the golden cycle model.  ``frame_rgb`` is the HDL's
    draw buffer, (H, W, 3) uint8.  ``cycles_per_s`` is simulated clocks (pixel phase + read-out)
    per second of the simulation run.
    """
    if engine not in ENGINES:
        raise RasterhwError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if not isinstance(stream, PixelStream):
        raise RasterhwError(f"expected a PixelStream, not {type(stream).__name__}")
    stream.validate(n_pipes=golden.N_PIPES)
    if stream.z_bits != 24:
        raise RasterhwError(f"the SNU pixel bus has 24-bit Z, not z_bits={stream.z_bits}")
    t0 = time.perf_counter()
    tb = find_testbench("pixelbus")
    params = tb.params(width=stream.width, height=stream.height, z_bits=stream.z_bits)
    stim = tb.stimulus_of(params, stream, gaps)
    exp = tb.expect(params, stim)
    # the golden cycle count without the read-out (BusBench.expect: bus idle + read-out + 1); not
    # pixelbus_cycles, which would run the golden acceptance model a second time (20 s at snu-100k)
    g_cycles = exp.cycles - (stream.width * stream.height + 1) if exp.cycles is not None else 0
    if progress:
        print(f"pixelbus: {len(stream)} writes, {stream.width}x{stream.height}, golden {g_cycles} cycles; running {engine}",
              file=sys.stderr)
    r = engines.run(tb, params, stim, engine=engine, expect_words={"o": len(exp.words["o"])})
    wall = time.perf_counter() - t0
    cmp = compare(exp, r)
    rgb, _ = frame_of(r, stream.z_bits, (stream.height, stream.width))
    # the read-out starts in the first clock after the last write's memory cycle (ReadOut)
    cycles = r.stamps["o"][0] - 1 if r.stamps["o"] else 0
    bad = cmp["mismatches"] + (cmp["cycle_mismatches"] or 0)
    if progress:
        print(f"pixelbus: {engine} {cycles} cycles, {bad} mismatches, {wall:.1f} s", file=sys.stderr)
    return {
        "block": "pixelbus",
        "engine": engine,
        "cycles": int(cycles),
        "cycles_golden": g_cycles,
        "cycle_mismatches": cmp["cycle_mismatches"],
        "writes": len(stream),
        "clock_hz": golden.CLOCK_HZ,
        "pixels_compared": stream.width * stream.height,
        "mismatches": bad,
        "wall_s": wall,
        "build_s": r.build_s,
        "run_s": r.run_s,
        "cycles_per_s": r.cycles / r.run_s if r.run_s > 0 else float("inf"),
        "frame_rgb": golden.rgb_image(rgb),
    }


def measure_rates(*, engine: str = "verilator", width: int = 1280, height: int = 1024,
                  n_pixels: int = 20_000, seed: int = 0) -> list[dict]:
    """Bus rate per access pattern, from HDL cycles (checked against the golden model).

    One row per (pattern, pipelines): ``pattern``, ``pipes``, ``writes``, ``cycles`` (HDL),
    ``golden_cycles``, ``mismatches``, ``mpixel_s`` (writes x 12.5 MHz / HDL cycles).
    """
    rows = []
    for pattern in golden.PATTERNS:
        for pipes in (1, 2):
            s = golden.pattern_stream(pattern, width, height, n_pixels, pipes=pipes, seed=seed)
            r = simulate_pixelbus(s, engine=engine)
            rows.append({
                "pattern": pattern, "pipes": pipes, "writes": len(s), "cycles": r["cycles"],
                "golden_cycles": r["cycles_golden"], "mismatches": r["mismatches"],
                "mpixel_s": golden.pixels_per_second(len(s), r["cycles"]) / 1e6,
            })
    return rows


def main(argv: list[str] | None = None) -> int:
    """``python -m rasterhw.sim.snu.pixelbus [--engine E] [--n N]``: print the rate table."""
    import argparse

    ap = argparse.ArgumentParser(description="SNU pixel-bus rates from HDL cycles")
    ap.add_argument("--engine", default="verilator", choices=ENGINES)
    ap.add_argument("--n", type=int, default=20_000, help="pixel writes per pattern")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=1024)
    a = ap.parse_args(argv)
    rows = measure_rates(engine=a.engine, width=a.width, height=a.height, n_pixels=a.n)
    print("| pattern | pipelines | writes | HDL cycles | golden cycles | mismatches | Mpixel/s at 12.5 MHz |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['pattern']} | {r['pipes']} | {r['writes']} | {r['cycles']} | {r['golden_cycles']} "
              f"| {r['mismatches']} | {r['mpixel_s']:.2f} |")
    return 0 if all(r["mismatches"] == 0 for r in rows) else 1



def simulate_scene(scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False) -> dict:
    """``rasterhw sim pixelbus``: the scene's frame through the pixel-bus HDL.

    ``engine="verilator"``: the whole frame as the machine draws it (``sim/snu/frame.py``): clear,
    the two pipelines' Gouraud streams with the producers' timing from the i860 model, swap, on
    plain Verilator; ``frame`` in the result holds the frame time and each stage's share.
    ``pysim``: the pixel stream alone (no clear, no swap, no producer gaps) through
    :func:`simulate_pixelbus`.
    """
    if engine == "verilator":
        return frame_run(scene, width, height, progress=progress)
    tris = run_geometry(scene, width, height, z_bits=Z_BITS, z_far_is_zero=True)
    return simulate_pixelbus(scan_convert(tris), engine=engine, progress=progress)


if __name__ == "__main__":
    raise SystemExit(main())
