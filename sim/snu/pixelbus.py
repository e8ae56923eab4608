"""Driver: play a :class:`PixelStream` into the SNU pixel-bus HDL and check it.

``engine="pysim"`` runs ``hdl.pixelbus.PixelBus`` in the Amaranth simulator, the
streams fed by two testbenches; ``engine="verilator"|"icarus"`` runs the generated
Verilog under cocotb through :mod:`rasterhw.sim.engines.runner`: the stimulus goes to hex files
that the bench wrapper (``cocotb_tests/snu/pixelbus/tb_pixelbus.v``) loads into its own
memories with ``$readmemh`` and plays out at full speed on a Verilog-side clock; the
wrapper then reads the whole draw buffer and Z back through the read port into a file.
Either way the frame and the cycle count are compared with ``golden_model.pixelbus``.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu import pixelbus as golden
from rasterhw.golden_model.snu.formats import RGB_BITS
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.golden_model.snu.words import payload_words
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put
from rasterhw.sim.outfile import write_if_changed
from rasterhw.sim.engines.runner import HARNESS_V, REPO_ROOT, build_dir_for, get_sim, run_cocotb
from rasterhw.sim.workdirs import keep as keep_run_folder
from rasterhw.sim.workdirs import temp_run_folder

__all__ = ["ENGINES", "GAP_BITS", "simulate_pixelbus", "run_pysim", "write_stimulus", "read_frame_dump"]

ENGINES = ("pysim", "verilator", "icarus")
GAP_BITS = 16  # idle clocks before a write, per stimulus word in the Verilog bench
BENCH_DIR = REPO_ROOT / "cocotb_tests" / "snu" / "pixelbus"


def run_pysim(
    stream: PixelStream,
    *,
    gaps: np.ndarray | None = None,
    readback: bool = True,
    mem_cycle: int = 5,
    n_banks: int = 5,
    checker_logs: list | None = None,
) -> dict:
    """Run ``stream`` through ``PixelBus`` in pysim.

    Returns ``{"cycles", "accept": (N,) cycle of each write's transfer, "rgb", "z"}``
    (``rgb``/``z`` (H, W) int64 read back through the read port, draw buffer, if
    ``readback``).  ``checker_logs``, if a list, receives two lists of the payloads each
    pipeline stream transferred, from :func:`stream_protocol_checker`.
    """
    from amaranth.sim import Simulator
    from rasterhw.hdl.snu.pixelbus import PixelBus

    dut = PixelBus(width=stream.width, height=stream.height, z_bits=stream.z_bits,
                   n_banks=n_banks, mem_cycle=mem_cycle)
    n = len(stream)
    gap = np.zeros(n, dtype=np.int64) if gaps is None else np.asarray(gaps, dtype=np.int64)
    accept = np.full(n, -1, dtype=np.int64)
    ports = [dut.i_pipe0, dut.i_pipe1]
    idx = [np.flatnonzero(stream.pipe == p) for p in range(2)]
    addr, rgb, z = stream.addr.tolist(), stream.rgb.tolist(), stream.z.tolist()
    done = [False, False]
    out: dict = {}

    def driver(p):
        async def tb(ctx):
            for k in idx[p].tolist():
                await stream_put(ctx, ports[p], {"addr": addr[k], "rgb": rgb[k], "z": z[k]}, gap=int(gap[k]))
                # stream_put returns one clock after the transfer
                accept[k] = ctx.get(dut.cycle) - 1
            done[p] = True

        return tb

    async def main(ctx):
        while not all(done):
            await ctx.tick()
        while ctx.get(dut.busy):
            await ctx.tick()
        out["cycles"] = int(ctx.get(dut.cycle))
        if readback:
            size = stream.width * stream.height
            rb_rgb = np.zeros(size, dtype=np.int64)
            rb_z = np.zeros(size, dtype=np.int64)
            ctx.set(dut.rd_buf, 0)
            for a in range(size):
                ctx.set(dut.rd_addr, a)
                await ctx.tick()  # synchronous read: data for `a` in the next clock
                rb_rgb[a] = ctx.get(dut.rd_rgb)
                rb_z[a] = ctx.get(dut.rd_z)
            out["rgb"] = rb_rgb.reshape(stream.height, stream.width)
            out["z"] = rb_z.reshape(stream.height, stream.width)

    sim = Simulator(dut)
    sim.add_clock(80e-9)
    for p in range(2):
        sim.add_testbench(driver(p))
        if checker_logs is not None:
            log: list = []
            checker_logs.append(log)
            sim.add_testbench(stream_protocol_checker(ports[p], f"i_pipe{p}", log), background=True)
    sim.add_testbench(main)
    sim.run()
    out["accept"] = accept
    return out


def write_stimulus(stream: PixelStream, gaps: np.ndarray | None, folder: Path, aw: int) -> tuple[list[Path], list[int]]:
    """Write ``stim0.hex``/``stim1.hex`` for tb_pixelbus.v; return the paths and counts."""
    n = len(stream)
    gap = np.zeros(n, dtype=np.int64) if gaps is None else np.asarray(gaps, dtype=np.int64)
    if n and gap.max() >= (1 << GAP_BITS):
        raise RasterhwError(f"gap {int(gap.max())} does not fit the bench's {GAP_BITS}-bit gap field")
    pw = stream.z_bits + RGB_BITS + aw
    paths, counts = [], []
    for p in range(2):
        idx = np.flatnonzero(stream.pipe == p)
        words = [(int(g) << pw) | w for g, w in zip(gap[idx].tolist(), payload_words(stream, idx, aw), strict=True)]
        path = Path(folder) / f"stim{p}.hex"
        # one dummy word keeps $readmemh happy on an empty pipeline
        path.write_text("\n".join(f"{w:x}" for w in (words or [0])) + "\n")
        paths.append(path)
        counts.append(len(words))
    return paths, counts


def read_frame_dump(path: Path, width: int, height: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Parse the wrapper's dump: (rgb (H, W), z (H, W), cycles)."""
    text = Path(path).read_text().split("\n")
    cyc = [ln for ln in text if ln.startswith("cycles")]
    if not cyc:
        raise RasterhwError(f"{path}: the bench did not finish (no cycles line)")
    rows = [ln for ln in text if ln and not ln.startswith("cycles")]
    if len(rows) != width * height:
        raise RasterhwError(f"{path}: {len(rows)} pixels, expected {width * height}")
    arr = np.array([int(x, 16) for ln in rows for x in ln.split()], dtype=np.int64).reshape(-1, 2)
    return arr[:, 0].reshape(height, width), arr[:, 1].reshape(height, width), int(cyc[0].split()[1])


def _ram_for(width: int, height: int) -> str:
    # the block's own choice (ram="auto"): Amaranth Memory for test frames, the equivalent
    # Verilog RAM for big ones
    from rasterhw.hdl.snu.pixelbus_bank import resolve_ram

    return resolve_ram("auto", -(-width * height // golden.N_BANKS))


def run_cocotb_bench(
    stream: PixelStream,
    *,
    sim: str | None = None,
    gaps: np.ndarray | None = None,
    check_protocol: bool = False,
    ram: str | None = None,
    expect: dict | None = None,
) -> dict:
    """Run ``stream`` on the generated Verilog under cocotb; return cycles, frame, timings."""
    from amaranth.utils import ceil_log2
    from rasterhw.sim.engines.verilog_cache import generate_cached

    sim = get_sim(sim)
    w, h = stream.width, stream.height
    aw = max(1, ceil_log2(w * h))
    ram = ram or _ram_for(w, h)
    n0 = int(np.count_nonzero(stream.pipe == 0))
    n1 = len(stream) - n0
    sdepth = max(1024, 1 << ceil_log2(max(n0, n1) + 2))
    params = {"width": w, "height": h, "z_bits": stream.z_bits, "ram": ram}
    bdir = build_dir_for("pixelbus", sim, sources=[HARNESS_V, BENCH_DIR / "tb_pixelbus.v"], sdepth=sdepth,
                         **params)
    bdir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    vpath = bdir / "pixelbus.v"
    text = generate_cached("pixelbus", **params)
    write_if_changed(vpath, text)  # whole or not at all: a concurrent run may read it
    if expect is None:
        acc = golden.pixelbus_accept_cycles(stream, gaps=gaps)
        rgb, z = golden.pixelbus_frame(stream, accept=acc)
        expect = {"rgb": rgb, "z": z, "cycles": int(acc.max()) + golden.MEM_CYCLE if len(stream) else 0}
    run_dir = temp_run_folder(bdir)
    (stim0, stim1), (c0, c1) = write_stimulus(stream, gaps, run_dir, aw)
    exp_path = run_dir / "expect.npz"
    # payload words are up to 69 bits: stored as hex strings
    payloads = {
        f"payload{p}": np.array([f"{w:x}" for w in payload_words(stream, np.flatnonzero(stream.pipe == p), aw)], dtype=str)
        if check_protocol else np.zeros(0, dtype=str)
        for p in range(2)
    }
    np.savez(exp_path, rgb=expect["rgb"], z=expect["z"], cycles=expect["cycles"], n0=n0, n1=n1, **payloads)
    out_path = run_dir / "frame.txt"
    timeout_ns = (int(expect["cycles"]) + w * h + 1000) * 10 * 4
    t1 = time.perf_counter()
    timings: dict = {}
    run_cocotb(
        sources=[vpath, HARNESS_V, BENCH_DIR / "tb_pixelbus.v"],
        toplevel="tb_pixelbus",
        test_module="cocotb_tests.snu.pixelbus.test_pixelbus",
        build_dir=bdir,
        test_dir=run_dir,
        sim=sim,
        parameters={"AW": aw, "ZW": stream.z_bits, "GW": GAP_BITS, "NPIX": w * h, "SDEPTH": sdepth},
        plusargs=[f"+stim0={stim0}", f"+stim1={stim1}", f"+n0={c0}", f"+n1={c1}", f"+out={out_path}"],
        extra_env={
            "PIXELBUS_OUT": str(out_path),
            "PIXELBUS_EXPECT": str(exp_path),
            "PIXELBUS_TIMEOUT_NS": str(timeout_ns),
            "PIXELBUS_CHECK_PROTOCOL": "1" if check_protocol else "0",
        },
        timings=timings,
    )
    t2 = time.perf_counter()
    rgb, z, cycles = read_frame_dump(out_path, w, h)
    if os.environ.get("PIXELBUS_KEEP") == "1":
        keep_run_folder(run_dir)
    else:  # full-frame dumps are ~20 MB each
        shutil.rmtree(run_dir, ignore_errors=True)
        run_dir = None
    return {"cycles": cycles, "rgb": rgb, "z": z, "prepare_s": t1 - t0, "build_s": timings["build_s"],
            "run_s": timings["test_s"], "total_s": t2 - t0, "run_dir": run_dir}


def simulate_pixelbus(stream: PixelStream, *, engine: str = "pysim", progress: bool = False) -> dict:
    """Run ``stream`` through the pixel-bus HDL, compare with the golden model.

    Returns ``{"block": "pixelbus", "engine", "cycles", "clock_hz": 12.5e6,
    "pixels_compared", "mismatches", "wall_s", "cycles_per_s", "frame_rgb"}`` plus
    ``"golden_cycles"``, ``"writes"`` and ``"build_s"`` (Verilog generation + simulator
    build, 0 for pysim).  ``wall_s`` is the whole call.  ``mismatches`` counts pixels whose RGB or Z
    differs from the golden frame, plus one if the cycle count differs from the golden
    cycle model.  ``frame_rgb`` is the HDL's draw buffer, (H, W, 3) uint8.
    ``cycles_per_s`` is simulated clocks (pixel phase + read-back) per second of the
    simulation run (Verilog build excluded, it is cached per parameter set under build/).
    """
    if engine not in ENGINES:
        raise RasterhwError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if not isinstance(stream, PixelStream):
        raise RasterhwError(f"expected a PixelStream, not {type(stream).__name__}")
    stream.validate(n_pipes=golden.N_PIPES)
    if stream.z_bits != 24:
        raise RasterhwError(f"the SNU pixel bus has 24-bit Z, not z_bits={stream.z_bits}")
    t0 = time.perf_counter()
    acc = golden.pixelbus_accept_cycles(stream)
    g_rgb, g_z = golden.pixelbus_frame(stream, accept=acc)
    g_cycles = int(acc.max()) + golden.MEM_CYCLE if len(stream) else 0
    if progress:
        print(f"pixelbus: {len(stream)} writes, {stream.width}x{stream.height}, golden {g_cycles} cycles; running {engine}", file=sys.stderr)
    t1 = time.perf_counter()
    if engine == "pysim":
        r = run_pysim(stream)
        run_s = time.perf_counter() - t1
        build_s = 0.0
    else:
        r = run_cocotb_bench(stream, sim=engine, expect={"rgb": g_rgb, "z": g_z, "cycles": g_cycles})
        run_s = r["run_s"]
        build_s = r["prepare_s"] + r["build_s"]
    wall = time.perf_counter() - t0
    bad = int(np.count_nonzero((r["rgb"] != g_rgb) | (r["z"] != g_z))) + int(r["cycles"] != g_cycles)
    size = stream.width * stream.height
    sim_cycles = r["cycles"] + size  # pixel phase + one read-back clock per pixel
    if progress:
        print(f"pixelbus: {engine} {r['cycles']} cycles, {bad} mismatches, {wall:.1f} s", file=sys.stderr)
    return {
        "block": "pixelbus",
        "engine": engine,
        "cycles": int(r["cycles"]),
        "golden_cycles": g_cycles,
        "writes": len(stream),
        "clock_hz": golden.CLOCK_HZ,
        "pixels_compared": size,
        "mismatches": bad,
        "wall_s": wall,
        "build_s": build_s,
        "cycles_per_s": sim_cycles / run_s if run_s > 0 else float("inf"),
        "frame_rgb": golden.rgb_image(r["rgb"]),
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
                "golden_cycles": r["golden_cycles"], "mismatches": r["mismatches"],
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


if __name__ == "__main__":
    raise SystemExit(main())


def simulate_scene(scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False) -> dict:
    """``rasterhw sim pixelbus``: the scene's frame through the pixel-bus HDL.

    ``engine="verilator"``: the whole frame as the machine draws it (``sim/snu/frame.py``): clear,
    the two pipelines' Gouraud streams with the producers' timing from the i860 model, swap, on
    plain Verilator; ``frame`` in the result holds the frame time and each stage's share.
    ``pysim``/``icarus``: the pixel stream alone (no clear, no swap, no producer gaps) through
    :func:`simulate_pixelbus`.
    """
    if engine == "verilator":
        from rasterhw.sim.snu.frame import frame_run

        return frame_run(scene, width, height, progress=progress)
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.snu.formats import Z_BITS
    from rasterhw.golden_model.snu.gouraud import scan_convert

    tris = run_geometry(scene, width, height, z_bits=Z_BITS, z_far_is_zero=True)
    return simulate_pixelbus(scan_convert(tris), engine=engine, progress=progress)
