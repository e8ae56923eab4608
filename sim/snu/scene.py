"""``rasterhw sim pixelbus``'s scene level (``sim/engines/scene.py``): the scene's frame through the SNU
pixel-bus HDL, checked against the golden model (``golden_model/snu/pixelbus.py``).

On every engine the whole frame as the machine draws it (the snu-100k headline frame end to end), so
``cycles`` is one quantity whatever the engine: the frame's length, CLEAR accepted to SWAP + 1:

1. **Geometry**: the scene through the golden geometry (``pipeline.run_geometry``, far = 0);
   triangle ``i`` goes to pipeline ``i % 2``. Its cost on the i860 model: the three-processor
   split of section 4.5 (``i860.table1_model()``; the slowest group sets the rate, the sum of
   the groups the latency of the first triangle).
2. **Scan conversion**: ``gouraud.scan_convert`` makes each pipeline's pixel writes, counting
   what its inner loop executes. The scan-converting i860's time between two pixel stores comes
   from the model (``i860.scan_clocks``: set-up per triangle, per scan line, per pixel), turned
   into idle bus clocks before each write (``gap``): the processor stalls on a store while the
   bus is not ready ("as if writing internal memory", 3.2.1) and resumes after the transfer.
3. **Pixel bus (HDL)**: the generic engine (``sim/engines/``) with the frame adapter
   ``sim/snu/frame_adapter.py`` (``FrameBench``): CLEAR, the two streams with their 16-bit gaps,
   SWAP, read-out of the displayed frame and of the schedule; cycles from the DUT's own counter.
4. **Golden**: the same schedule in ``golden_model.snu.pixelbus`` (clear length, release of
   the players, every acceptance cycle, swap) and the same frame; ``mismatches`` counts pixels
   that differ plus one per schedule number that differs.

The pixel stream alone (no clear, no swap, no producer gaps) through the block's testbench
(``BusBench``, the frame memory streamed out by the engines' ``ReadOut``) is :func:`simulate_pixelbus`,
which the soak and the report's rate rows run; ``rasterhw sim pixelbus`` does not (before, its pysim
run did, and its ``cycles`` were the pixel writes' 861 where Verilator's were the frame's 35,845: snu-100px
at 64 x 48).

Times are reported at the paper's clocks: 12.5 MHz bus (80 ns slot), i860 at
``I860.clock_hz`` (40 MHz, assumed: the paper never states it).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.snu import i860
from rasterhw.golden_model.snu import pixelbus as golden
from rasterhw.golden_model.snu.formats import CLOCK_HZ, MEM_CYCLE, N_BANKS, RGB_BITS, Z_BITS
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.sim import engines
from rasterhw.sim.engines.memh import memh_uint64
from rasterhw.sim.engines.scene import Done, Job, SceneRun, run_job
from rasterhw.sim.packed import as_ints
from rasterhw.sim.snu.frame_format import GAP_BITS, SCHEDULE
from rasterhw.sim.snu.testbench import BusBench, FrameBench, frame_of

__all__ = ["ENGINES", "PixelbusScene", "clear_cycles", "golden_schedule", "i860_clocks", "measure_rates", "producer_gaps",
           "run_frame_engine", "simulate", "simulate_pixelbus"]

ENGINES = (*engines.ENGINES, *engines.ALIASES)   # pysim, verilator, cocotb-verilator, cocotb-icarus, icarus
#: clocks from the end of the clear (``clear_cycles`` after its accept) to the first clock the
#: pipelines run: ``idle`` rises one clock after the clear's last word, the frame adapter sees it
#: and releases the pipelines in the next clock (``sim/snu/frame_adapter.py``: ``run``, then ``t_start``)
RELEASE_DELAY = 2


def clear_cycles(width: int, height: int, n_banks: int = N_BANKS) -> int:
    """Clocks a clear keeps the banks busy: one word per clock per bank, all banks at once."""
    return -(-width * height // n_banks)


def i860_clocks(cpu: i860.I860) -> tuple[dict, list[int]]:
    """``i860.scan_clocks(cpu)`` and the three geometry groups' clocks of one triangle
    (``i860.table1_model``; its 8-triangle stream schedules are not used here), kept in the build
    cache (``verilog_cache.arrays_cached``: keyed by ``cpu`` and the i860 model's sources): nine
    list schedules in Python that do not depend on the scene (~0.1 CPU-s a run)."""
    from rasterhw.sim.engines.verilog_cache import arrays_cached

    groups = [("vertex_transform", "normal_transform"), ("normalise", "light"),
              ("clip", "perspective_divide", "screen_map")]

    def compute() -> dict:
        sc = i860.scan_clocks(cpu)
        geo = i860.table1_model(cpu, stream_triangles=0)
        return {"triangle": np.int64(sc["triangle"]), "span": np.int64(sc["span"]), "pixel": np.float64(sc["pixel"]),
                "groups": np.array([sum(geo[s]["clocks"] for s in g) for g in groups], np.int64)}

    got = arrays_cached("snu-i860", Path(i860.__file__), [repr(cpu)], compute)
    return ({"triangle": int(got["triangle"]), "span": int(got["span"]), "pixel": float(got["pixel"])},
            [int(c) for c in got["groups"]])


def producer_gaps(tris, stream: PixelStream, cpu: i860.I860 | None = None, *, n_pipes: int = 2,
                  clock_hz: float = CLOCK_HZ, spans: dict | None = None) -> dict:
    """Idle bus clocks before each write, from the scan-converting i860's time on the model.

    Between two stores of one pipeline the processor spends ``pixel`` clocks (the inner loop),
    plus ``span`` clocks per scan line started since (empty lines included) and ``triangle``
    clocks per triangle started since (i860.scan_clocks). ``gap = ceil(work / ratio) - 1``
    bus clocks, ``ratio`` = i860 clocks per bus clock (the write is offered once the work is
    done, counted from the clock after the previous transfer). The first write of a pipeline
    carries the pipeline's fill: the first triangle through the three geometry processors plus
    its set-up (counted from the start of the frame; the bench releases the players after the
    clear, which is longer, so it costs nothing there).

    Returns ``gaps`` (N,), ``first_work`` (i860 clocks before each pipeline's first write),
    ``scan_s`` (each pipeline's scan-conversion compute time, no stalls), ``geometry_starves``
    (whether the geometry group, at its slowest stage's rate, would ever make a pipeline's scan
    converter wait for a triangle) and the model's per-item clocks.
    """
    from rasterhw.golden_model.snu.gouraud import setup_spans

    cpu = cpu or i860.I860()
    sc, group_clocks = i860_clocks(cpu)
    ratio = cpu.clock_hz / clock_hz
    spans = setup_spans(tris) if spans is None else spans
    n_tri = tris.n_triangles
    n = len(stream)
    # per scan line (in emission order) its triangle and pixel count; stream = lines expanded
    tri, cnt = spans["tri"], spans["n"]
    work = np.full(n, sc["pixel"], dtype=np.float64)
    first_px = np.cumsum(cnt) - cnt  # stream index of each line's first pixel (if cnt > 0)
    # scan lines and triangles started since a pipeline's previous write, charged to its next one
    gaps = np.zeros(n, dtype=np.int64)
    first_work = [0.0] * n_pipes
    scan_s = [0.0] * n_pipes
    starves = False
    fill = float(sum(group_clocks))
    # triangles reach a pipeline at the slower of its geometry group's slowest processor and the
    # traversal processor, which writes 108 bytes per triangle for both pipelines through
    # 16-bit dual-port memories, one 16-bit transfer per bus cycle
    from rasterhw.golden_model.snu.traversal import RECORD_BYTES
    trav = n_pipes * 3 * RECORD_BYTES / 2 * cpu.bus_clocks_per_cycle
    rate = float(max(max(group_clocks), trav))
    line_tri_first = np.ones(tri.size, dtype=bool)
    line_tri_first[1:] = tri[1:] != tri[:-1]
    for p in range(n_pipes):
        lines = np.flatnonzero(tri % n_pipes == p)
        tris_p = np.arange(p, n_tri, n_pipes)
        # cost of every line and triangle before each written line, cumulated per pipeline
        line_cost = np.full(lines.size, float(sc["span"]))
        line_cost[line_tri_first[lines]] += sc["triangle"]
        written = cnt[lines] > 0
        pend = np.cumsum(line_cost)
        at = np.flatnonzero(written)
        before = np.concatenate([[0.0], pend[at[:-1]]]) if at.size else np.zeros(0)
        charge = pend[at] - before  # set-up owed when the line's first pixel is stored
        idx = first_px[lines[at]]
        work[idx] += charge
        # triangles that produce no scan line at all still pay their set-up: count them
        has_line = np.zeros(n_tri, dtype=bool)
        has_line[tri[lines]] = True
        lost = np.count_nonzero(~has_line[tris_p]) * sc["triangle"]
        pix = np.flatnonzero(stream.pipe == p)
        if pix.size:
            first_work[p] = fill + work[pix[0]]
            work[pix[0]] = 0.0
            gaps[pix] = np.maximum(np.ceil(work[pix] / ratio).astype(np.int64) - 1, 0)
        total = float(pend[-1] if pend.size else 0.0) + lost + sc["pixel"] * pix.size
        scan_s[p] = total / cpu.clock_hz
        # geometry never starves the scan converter if, at every triangle, the converter's own
        # (unstalled) time to reach it is at least the geometry group's time to produce it
        if at.size:
            tri_first_line = np.flatnonzero(line_tri_first[lines])
            reach = np.concatenate([[0.0], np.cumsum(line_cost + cnt[lines] * sc["pixel"])[:-1]])[tri_first_line]
            k = np.arange(tri_first_line.size)
            starves |= bool(np.any(reach < k * rate))
    if n and int(gaps.max()) >= (1 << GAP_BITS):
        raise RasterhwError(f"a producer gap of {int(gaps.max())} clocks does not fit {GAP_BITS} bits")
    return {"gaps": gaps, "first_work": first_work, "scan_s": scan_s, "geometry_starves": starves,
            "clocks": sc, "group_clocks": group_clocks, "ratio": ratio}


def golden_schedule(stream: PixelStream, gaps: np.ndarray, first_work: list[float], *, ratio: float) -> dict:
    """The frame's schedule in the golden model: CLEAR accepted at cycle 0, players released
    ``clear_cycles + RELEASE_DELAY`` later, each first write valid at the later of that and its
    fill, every acceptance cycle, the bus idle ``MEM_CYCLE`` after the last, SWAP accepted in
    the next clock, done one clock after that."""
    w, h = stream.width, stream.height
    t_start = clear_cycles(w, h) + RELEASE_DELAY
    g = np.asarray(gaps, dtype=np.int64).copy()
    first_bench = [0, 0]
    for p in range(2):
        idx = np.flatnonzero(stream.pipe == p)
        if idx.size:
            fill_bus = int(np.ceil(first_work[p] / ratio))
            first_bench[p] = max(0, fill_bus - t_start)
            g[idx[0]] = t_start + first_bench[p]
    acc = accept_cycles(stream, g)
    t_pix = int(acc.max()) + MEM_CYCLE if len(stream) else t_start
    return {"t_clear": 0, "t_start": t_start, "t_pixels_done": t_pix, "t_swap": t_pix + 1,
            "cycles": t_pix + 2, "accept": acc, "first_bench_gap": first_bench}


def accept_cycles(stream: PixelStream, gaps: np.ndarray) -> np.ndarray:
    """``golden.pixelbus_accept_cycles(stream, gaps=gaps)``, kept in the build cache
    (``verilog_cache.arrays_cached``: keyed by the stream's writes and gaps and by the model's sources):
    its event loop is Python, one step per write (snu-100px's 199,970: 0.15-0.28 CPU-s a run)."""
    from rasterhw.sim.engines.verilog_cache import arrays_cached

    g = np.asarray(gaps, dtype=np.int64)
    key = [stream.width, stream.height, stream.addr, stream.pipe, g, MEM_CYCLE, N_BANKS]
    return arrays_cached("snu-accept", Path(golden.__file__), key,
                         lambda: {"accept": golden.pixelbus_accept_cycles(stream, gaps=g)})["accept"]


# ====================================================================== the pixel stream alone
def bus_job(stream: PixelStream, gaps: np.ndarray | None = None) -> Job:
    """``stream`` (``gaps``: idle clocks before each write) as one job of the block's testbench
    (``BusBench``), against the golden frame and cycle count."""
    if not isinstance(stream, PixelStream):
        raise RasterhwError(f"expected a PixelStream, not {type(stream).__name__}")
    stream.validate(n_pipes=golden.N_PIPES)
    if stream.z_bits != 24:
        raise RasterhwError(f"the SNU pixel bus has 24-bit Z, not z_bits={stream.z_bits}")
    tb = BusBench()
    params = tb.params(width=stream.width, height=stream.height, z_bits=stream.z_bits)
    stim = tb.stimulus_of(params, stream, gaps)
    return Job(tb, params, stim, tb.expect(params, stim))


def bus_result(d: Done) -> dict:
    """A :func:`bus_job`'s keys: ``cycles`` (the clock the read-out started in, the first clock after
    the last write's memory cycle: the golden model's cycle count), ``cycles_golden``,
    ``cycle_mismatches``, ``writes``, ``mismatches`` (read-out words that differ, plus one if the
    cycle count differs from the golden cycle model), ``frame_rgb`` (the HDL's draw buffer)."""
    stream = d.job.stim.source[0]
    exp = d.job.expect
    # the golden cycle count without the read-out (BusBench.expect: bus idle + read-out + 1)
    g_cycles = exp.cycles - (stream.width * stream.height + 1) if exp.cycles is not None else 0
    rgb, _ = frame_of(d.got, stream.z_bits, (stream.height, stream.width))
    return {"cycles": int(d.got.stamps["o"][0] - 1 if d.got.stamps["o"] else 0), "cycles_golden": g_cycles,
            "cycle_mismatches": d.cmp["cycle_mismatches"], "writes": len(stream),
            "pixels_compared": stream.width * stream.height,
            "mismatches": d.cmp["mismatches"] + (d.cmp["cycle_mismatches"] or 0), "frame_rgb": golden.rgb_image(rgb)}


def simulate_pixelbus(stream: PixelStream, *, engine: str = "pysim", gaps: np.ndarray | None = None,
                      progress: bool = False) -> dict:
    """``stream`` through the pixel-bus HDL on ``engine`` (:func:`bus_job`), compared with the
    golden model: :func:`bus_result`'s keys and ``block``, ``engine``, ``clock_hz`` (12.5 MHz),
    ``build_s``, ``run_s``, ``cycles_per_s`` (simulated clocks, pixel phase + read-out, per second
    of simulation); ``progress``: a line before and after the run on stderr."""
    if engine not in ENGINES:
        raise RasterhwError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    job = bus_job(stream, gaps)
    if progress:
        print(f"pixelbus: {len(stream)} writes, {stream.width}x{stream.height}; running {engine}", file=sys.stderr)
    d = run_job(job, engine)
    if progress:
        print(f"pixelbus: {engine} {d.got.cycles} cycles, {d.cmp['mismatches']} mismatches", file=sys.stderr)
    return {"block": "pixelbus", "engine": engine, "clock_hz": golden.CLOCK_HZ, **bus_result(d),
            "build_s": d.got.build_s, "run_s": d.got.run_s,
            "cycles_per_s": d.got.cycles / d.got.run_s if d.got.run_s > 0 else float("inf")}


def measure_rates(*, engine: str = "verilator", width: int = 1280, height: int = 1024,
                  n_pixels: int = 20_000, seed: int = 0) -> list[dict]:
    """Bus rate per access pattern, from HDL cycles (checked against the golden model): one row
    per (pattern, pipelines): ``pattern``, ``pipes``, ``writes``, ``cycles`` (HDL),
    ``golden_cycles``, ``mismatches``, ``mpixel_s`` (writes x 12.5 MHz / HDL cycles)."""
    rows = []
    for pattern in golden.PATTERNS:
        for pipes in (1, 2):
            s = golden.pattern_stream(pattern, width, height, n_pixels, pipes=pipes, seed=seed)
            r = simulate_pixelbus(s, engine=engine)
            rows.append({"pattern": pattern, "pipes": pipes, "writes": len(s), "cycles": r["cycles"],
                         "golden_cycles": r["cycles_golden"], "mismatches": r["mismatches"],
                         "mpixel_s": golden.pixels_per_second(len(s), r["cycles"]) / 1e6})
    return rows


def main(argv: list[str] | None = None) -> int:
    """``python -m rasterhw.sim.snu.scene [--engine E] [--n N]``: print the rate table."""
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


# ====================================================================== the whole frame
def frame_job(stream: PixelStream, gaps: np.ndarray, sched: dict, *, engine: str = "verilator") -> Job:
    """The frame (``FrameBench``: clear, the producer gaps, swap) as one job: the displayed frame
    and the :data:`~rasterhw.sim.snu.frame_format.SCHEDULE` words against the golden ``sched``. The
    bank RAMs: Amaranth's ``Memory`` for banks of up to 4096 words and always on pysim (which cannot
    run the hand-written Verilog RAM), else the Verilog RAM (``PixelBusBank``: the same ports and clocks)."""
    w, h = stream.width, stream.height
    tb = FrameBench()
    small = -(-w * h // N_BANKS) <= 4096 or engine == "pysim"
    params = tb.params(width=w, height=h, z_bits=stream.z_bits, ram="memory" if small else "verilog")
    g = np.asarray(gaps, dtype=np.int64).copy()
    for p in range(2):
        i = np.flatnonzero(stream.pipe == p)
        if i.size:
            g[i[0]] = sched["first_bench_gap"][p]
    if len(stream) and int(g.max()) >= (1 << GAP_BITS):
        raise RasterhwError(f"a producer gap of {int(g.max())} clocks does not fit {GAP_BITS} bits")
    stim = tb.stimulus_of(params, stream, g, schedule=sched)
    # the run's length, held exactly (``cycle_mismatches``, as BusBench's on the other engines): the
    # schedule word k leaves at edge ``cycles + k``, display word j at ``cycles + 1 + j``, so the
    # last at ``cycles + w h`` (``FrameAdapter``: the sweep starts the clock after SWAP's)
    exp = replace(tb.expect(params, stim), cycles=int(sched["cycles"]) + w * h + 1)
    # packed: the Verilator engine gives the display words as rows, as ``FrameBench.expect`` does
    return Job(tb, params, stim, exp, {"max_cycles": int(sched["cycles"]) + w * h + 10_000, "packed": True})


def frame_words(d: Done, *, ints: bool = True) -> dict:
    """A :func:`frame_job`'s schedule numbers, displayed frame and ``mismatches`` (read-out and
    schedule words that differ from the golden schedule, plus one if the run's length differs from
    the golden schedule's: ``frame_job``). The frame as ``rgb8`` ((H, W, 3) uint8, the image) and, if
    ``ints``, as ``rgb`` and ``z`` ((H, W) int64); from the Verilator engine's packed rows (``{rgb,
    z}`` big-endian: the red, green and blue bytes first) ``rgb8`` is the rows' first three bytes, no
    int per pixel (the scene run asks for no more: 1,310,720 pixels, ~0.03 CPU-s saved)."""
    stream = d.job.stim.source[0]
    h, w, zb = stream.height, stream.width, stream.z_bits
    o = d.got.words["o"]
    out = {**dict(zip(SCHEDULE, as_ints(d.got.words["o_sched"]), strict=False)),
           "mismatches": d.cmp["mismatches"] + (d.cmp["cycle_mismatches"] or 0)}
    if isinstance(o, np.ndarray) and zb % 8 == 0 and o.shape[1] * 8 == RGB_BITS + zb:
        out["rgb8"] = o[:, :RGB_BITS // 8].reshape(h, w, 3)
    if ints or "rgb8" not in out:
        words = _int64(o)
        out["rgb"], out["z"] = (words >> zb).reshape(h, w), (words & ((1 << zb) - 1)).reshape(h, w)
        out.setdefault("rgb8", golden.rgb_image(out["rgb"]))
    return out


def _int64(words) -> np.ndarray:
    """A port's words of up to 63 bits (ints, or packed rows: ``sim/packed.py``) as int64."""
    if not isinstance(words, np.ndarray):
        return np.array(words, dtype=np.int64)
    return memh_uint64(words, 0, words.shape[1]).astype(np.int64)   # big-endian rows of up to 8 bytes


def run_frame_engine(stream: PixelStream, gaps: np.ndarray, sched: dict, *, engine: str = "verilator") -> dict:
    """:func:`frame_job` on ``engine``: :func:`frame_words`' keys."""
    return frame_words(run_job(frame_job(stream, gaps, sched, engine=engine), engine))


def frame_golden(tris, cpu: i860.I860, *, cached: bool = True) -> dict:
    """The frame's golden model for the screen triangles ``tris`` on the i860 model ``cpu``: the two
    pipelines' pixel stream (``gouraud.scan_convert``; ``ran``: what its inner loop executed), the
    producer gaps (:func:`producer_gaps`: ``prod``) and the schedule (:func:`golden_schedule`:
    ``sched``). ``cached``: kept as a build-cache entry (``verilog_cache.arrays_cached``:
    ``build/verilog/snu-frame-golden-<digest>.npz``, SHA-256 checked, keyed by the triangles' bytes,
    ``cpu`` and the digest of every Python source of ours this module imports, transitively), so a
    warm ``rasterhw sim pixelbus`` neither scan-converts nor walks the producer model (snu-100px at
    1280 x 1024: 0.045-0.07 CPU-s computed, ~0.01 read back); ``False``: computed here (the
    specification the entry is held equal to, ``tests/snu/test_pixelbus_sim_engines.py``)."""
    from rasterhw.golden_model.snu.gouraud import scan_convert, setup_spans

    def compute() -> dict:
        ran: dict = {}
        spans = setup_spans(tris)
        stream = scan_convert(tris, counts=ran, spans=spans)
        prod = producer_gaps(tris, stream, cpu, spans=spans)
        sched = golden_schedule(stream, prod["gaps"], prod["first_work"], ratio=prod["ratio"])
        return {"stream": stream, "ran": ran, "prod": prod, "sched": sched}

    if not cached:
        return compute()

    import json

    from rasterhw.sim.engines.verilog_cache import arrays_cached, fields_key

    def arrays() -> dict:
        g = compute()
        s = g["stream"]
        meta = {"ran": g["ran"], "prod": {k: v for k, v in g["prod"].items() if k != "gaps"},
                "sched": {k: v for k, v in g["sched"].items() if k != "accept"},
                "stream": {"width": s.width, "height": s.height, "z_bits": s.z_bits}}
        cols = {"addr": s.addr, "rgb": s.rgb, "z": s.z, "pipe": s.pipe, "gaps": g["prod"]["gaps"],
                "accept": g["sched"]["accept"]}
        # int64 columns kept as int32 where every value fits (half the bytes to read and check)
        return {**{k: v.astype(np.int32) if _fits32(v) else v for k, v in cols.items()},
                "meta": np.frombuffer(json.dumps(meta).encode(), np.uint8)}

    key = fields_key(tris) + [repr(cpu)]
    got = arrays_cached("snu-frame-golden", Path(__file__), key, arrays)
    meta = json.loads(got["meta"].tobytes())
    m = meta["stream"]
    stream = PixelStream(m["width"], m["height"], got["addr"], got["rgb"], got["z"], got["pipe"], z_bits=m["z_bits"])
    return {"stream": stream, "ran": meta["ran"], "prod": {**meta["prod"], "gaps": got["gaps"].astype(np.int64)},
            "sched": {**meta["sched"], "accept": got["accept"].astype(np.int64)}}


def _fits32(v: np.ndarray) -> bool:
    return v.dtype == np.int64 and (v.size == 0 or (int(v.min()) >= -(1 << 31) and int(v.max()) < 1 << 31))


class PixelbusScene(SceneRun):
    """``rasterhw sim pixelbus``: the whole frame on every engine (module docstring; ``frame`` in the
    result holds the schedule, the frame time and each stage's share)."""

    block = "pixelbus"
    steps = ("geometry + scan conversion + golden model", "HDL simulation", "frame")

    def golden(self, scene, width: int, height: int, *, engine: str, cpu: i860.I860 | None = None,
               bus_only_bound: bool = False) -> dict:
        tris = run_geometry(scene, width, height, z_bits=Z_BITS, z_far_is_zero=True)
        cpu = cpu or i860.I860()
        return {"tris": tris, "cpu": cpu, **frame_golden(tris, cpu)}

    def jobs(self, gold: dict, *, engine: str, **_) -> list[Job]:
        return [frame_job(gold["stream"], gold["prod"]["gaps"], gold["sched"], engine=engine)]

    def result(self, gold: dict, done: list[Done], *, engine: str, bus_only_bound: bool = False, **_) -> dict:
        (d,) = done
        return frame_result(gold, frame_words(d, ints=False), bus_only_bound=bus_only_bound)


def frame_result(gold: dict, hdl: dict, *, bus_only_bound: bool = False) -> dict:
    """The whole frame's keys: ``cycles``, ``cycles_golden``, ``writes``, ``pixels_compared``,
    ``mismatches`` (pixels and schedule words that differ), ``frame_rgb`` and ``frame``: the
    schedule, the frame time, each stage's busy time and share, and the limiting bound."""
    from rasterhw.golden_model.snu.gouraud import inner_loop_ops
    from rasterhw.golden_model.snu.traversal import RECORD_BYTES

    tris, stream, prod, sched, cpu = gold["tris"], gold["stream"], gold["prod"], gold["sched"], gold["cpu"]
    width, height = stream.width, stream.height
    bad_sched = sum(int(hdl[k] != sched[k]) for k in SCHEDULE)
    n_tri = [int(np.count_nonzero(np.arange(tris.n_triangles) % 2 == p)) for p in range(2)]
    frame_s = hdl["cycles"] / CLOCK_HZ
    geo_s = [n * max(prod["group_clocks"]) / cpu.clock_hz for n in n_tri]
    bytes_total = tris.n_triangles * 3 * RECORD_BYTES
    dpm_rate = 2 * cpu.clock_hz / cpu.bus_clocks_per_cycle  # 16-bit port, one transfer per bus cycle
    busy = {
        "clear (pixel bus)": clear_cycles(width, height) / CLOCK_HZ,
        "pixel writes (pixel bus, slots used)": len(stream) / CLOCK_HZ,
        "pixel phase (pixel bus, HDL, clear end to last write)": (hdl["t_pixels_done"] - hdl["t_start"]) / CLOCK_HZ,
        "scan conversion (i860 model, busiest pipeline)": max(prod["scan_s"]),
        "geometry (i860 model, slowest of 3 processors, busiest pipeline)": max(geo_s),
        "traversal output (108 B/triangle over a 16-bit dual-port memory)": bytes_total / dpm_rate,
        "swap (pixel bus)": 1 / CLOCK_HZ,
    }
    if bus_only_bound:  # the pixel bus alone, producers infinitely fast (golden cycle model)
        busy["pixel bus alone (golden, producers infinitely fast)"] = golden.pixelbus_cycles(stream) / CLOCK_HZ
    # bounds: each resource's own time for the frame's work; the clear comes first on the bus
    bounds = {k: v for k, v in busy.items() if "phase" not in k and "swap" not in k and "clear" not in k
              and not (bus_only_bound and "slots used" in k)}
    limit = max(bounds, key=bounds.get)
    return {
        "cycles": int(hdl["cycles"]), "cycles_golden": int(sched["cycles"]), "writes": len(stream),
        "pixels_compared": width * height, "mismatches": hdl["mismatches"],
        "frame_rgb": hdl["rgb8"],
        "frame": {
            "triangles": tris.n_triangles, "pixel_writes": len(stream),
            "schedule_hdl": {k: hdl[k] for k in SCHEDULE}, "schedule_golden": {k: sched[k] for k in SCHEDULE},
            "schedule_mismatches": bad_sched,
            "frame_s": frame_s, "polygons_per_s": tris.n_triangles / frame_s,
            "pixels_per_s": len(stream) / frame_s,
            "bus_share_of_frame": len(stream) / hdl["cycles"],
            "busy_s": busy, "share_of_frame": {k: v / frame_s for k, v in busy.items()},
            "limiting": limit, "bound_s": busy["clear (pixel bus)"] + bounds[limit],
            "geometry_starves": prod["geometry_starves"], "i860_clocks": prod["clocks"],
            "geometry_group_clocks": prod["group_clocks"], "inner_loop": inner_loop_ops(gold["ran"]),
            "gap_mean": float(prod["gaps"].mean()) if len(stream) else 0.0,
        },
    }


simulate = PixelbusScene().simulate


def frame_run(scene, width: int, height: int, *, cpu: i860.I860 | None = None, progress: bool = False,
              bus_only_bound: bool = False) -> dict:
    """The whole frame on Verilator (module docstring): :class:`PixelbusScene`'s keys."""
    return simulate(scene, width, height, engine="verilator", progress=progress, cpu=cpu, bus_only_bound=bus_only_bound)


if __name__ == "__main__":
    raise SystemExit(main())
