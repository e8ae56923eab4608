"""The SNU headline frame end to end: traversal, geometry and scan conversion on the i860 timing
model's clock, the two pipelines' real pixel streams through the pixel-bus HDL on plain
Verilator, clear and swap included, the frame checked bit for bit against the golden model.

Flow (``frame_run``):

1. **Geometry**: the scene through the golden geometry (``pipeline.run_geometry``, far = 0);
   triangle ``i`` goes to pipeline ``i % 2``. Its cost on the i860 model: the three-processor
   split of section 4.5 (``i860.table1_model()``; the slowest group sets the rate, the sum of
   the groups the latency of the first triangle).
2. **Scan conversion**: ``gouraud.scan_convert`` makes each pipeline's pixel writes, counting
   what its inner loop executes. The scan-converting i860's time between two pixel stores comes
   from the model (``i860.scan_clocks``: set-up per triangle, per scan line, per pixel), turned
   into idle bus clocks before each write (``gap``): the processor stalls on a store while the
   bus is not ready ("as if writing internal memory", 3.2.1) and resumes after the transfer.
3. **Pixel bus (HDL)**: the generic Verilator engine (``sim/engines/``) with the frame adapter
   ``sim/snu/frame_adapter.py`` (``FrameBench``): CLEAR, the two streams with their 16-bit gaps,
   SWAP, read-out of the displayed frame and of the schedule; cycles from the DUT's own counter.
4. **Golden**: the same schedule in ``golden_model.snu.pixelbus`` (clear length, release of
   the players, every acceptance cycle, swap) and the same frame; ``mismatches`` counts pixels
   that differ plus one per schedule number that differs.

Times are reported at the paper's clocks: 12.5 MHz bus (80 ns slot), i860 at
``I860.clock_hz`` (40 MHz, assumed: the paper never states it).
"""

from __future__ import annotations

import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu import i860
from rasterhw.golden_model.snu import pixelbus as golden
from rasterhw.golden_model.snu.formats import CLOCK_HZ, MEM_CYCLE, N_BANKS
from rasterhw.golden_model.snu.pixelstream import PixelStream

__all__ = ["clear_cycles", "frame_run", "golden_schedule", "producer_gaps", "run_frame_engine"]

GAP_BITS = 16
#: clocks from the end of the clear (``clear_cycles`` after its accept) to the first clock the
#: pipelines run: ``idle`` rises one clock after the clear's last word, the frame adapter sees it
#: and releases the pipelines in the next clock (``sim/snu/frame_adapter.py``: ``run``, then ``t_start``)
RELEASE_DELAY = 2


def clear_cycles(width: int, height: int, n_banks: int = N_BANKS) -> int:
    """Clocks a clear keeps the banks busy: one word per clock per bank, all banks at once."""
    return -(-width * height // n_banks)


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
    sc = i860.scan_clocks(cpu)
    geo = i860.table1_model(cpu)
    groups = [("vertex_transform", "normal_transform"), ("normalise", "light"),
              ("clip", "perspective_divide", "screen_map")]
    group_clocks = [sum(geo[s]["clocks"] for s in g) for g in groups]
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
    acc = golden.pixelbus_accept_cycles(stream, gaps=g)
    t_pix = int(acc.max()) + MEM_CYCLE if len(stream) else t_start
    return {"t_clear": 0, "t_start": t_start, "t_pixels_done": t_pix, "t_swap": t_pix + 1,
            "cycles": t_pix + 2, "accept": acc, "first_bench_gap": first_bench}


def run_frame_engine(stream: PixelStream, gaps: np.ndarray, sched: dict, *, engine: str = "verilator") -> dict:
    """The frame on the generic engines (``FrameBench``: ``sim/snu/frame_adapter.py``): the
    schedule numbers (:data:`~rasterhw.sim.snu.frame_adapter.SCHEDULE`), the displayed frame
    (``rgb``, ``z``), ``mismatches`` (read-out and schedule words that differ from the golden
    ``sched``) and timings."""
    from rasterhw.sim import engines
    from rasterhw.sim.snu.testbench import FrameBench
    from rasterhw.sim.testbench import compare

    w, h = stream.width, stream.height
    t0 = time.perf_counter()
    tb = FrameBench()
    params = tb.params(width=w, height=h, z_bits=stream.z_bits, ram="memory" if -(-w * h // N_BANKS) <= 4096 else "verilog")
    g = np.asarray(gaps, dtype=np.int64).copy()
    for p in range(2):
        i = np.flatnonzero(stream.pipe == p)
        if i.size:
            g[i[0]] = sched["first_bench_gap"][p]
    if len(stream) and int(g.max()) >= (1 << GAP_BITS):
        raise RasterhwError(f"a producer gap of {int(g.max())} clocks does not fit {GAP_BITS} bits")
    stim = tb.stimulus_of(params, stream, g, schedule=sched)
    exp = tb.expect(params, stim)
    t1 = time.perf_counter()
    r = engines.run(tb, params, stim, engine=engine, expect_words={k: len(v) for k, v in exp.words.items()},
                    max_cycles=int(sched["cycles"]) + w * h + 10_000)
    t2 = time.perf_counter()
    cmp = compare(exp, r, cycle_exact=False)
    words = np.array(r.words["o"], dtype=np.int64)
    zmask = (1 << stream.z_bits) - 1
    got = dict(zip(("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles"), r.words["o_sched"], strict=False))
    return {**got, "rgb": (words >> stream.z_bits).reshape(h, w), "z": (words & zmask).reshape(h, w),
            "mismatches": cmp["mismatches"], "build_s": r.build_s, "prepare_s": t1 - t0 + (r.wall_s - r.build_s - r.run_s),
            "run_s": t2 - t1, "sim_cycles": r.cycles, "loop_s": r.run_s}


def frame_run(scene, width: int, height: int, *, cpu: i860.I860 | None = None, progress: bool = False,
              bus_only_bound: bool = False) -> dict:
    """The whole frame (module docstring). Returns the ``simulate_pixelbus`` keys (``block``,
    ``engine``, ``cycles``, ``cycles_golden``, ``writes``, ``pixels_compared``, ``mismatches``,
    ``wall_s``, ``build_s``, ``cycles_per_s``, ``frame_rgb``) plus ``frame``: the schedule, the
    frame time, each stage's busy time and share, and the limiting bound."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.snu.formats import Z_BITS
    from rasterhw.golden_model.snu.gouraud import inner_loop_ops, scan_convert, setup_spans
    from rasterhw.golden_model.snu.traversal import RECORD_BYTES

    cpu = cpu or i860.I860()
    t0 = time.perf_counter()
    tris = run_geometry(scene, width, height, z_bits=Z_BITS, z_far_is_zero=True)
    ran: dict = {}
    spans = setup_spans(tris)
    stream = scan_convert(tris, counts=ran, spans=spans)
    t_geo = time.perf_counter()
    prod = producer_gaps(tris, stream, cpu, spans=spans)
    sched = golden_schedule(stream, prod["gaps"], prod["first_work"], ratio=prod["ratio"])
    t_gold = time.perf_counter()
    if progress:
        print(f"snu frame: {tris.n_triangles} triangles, {len(stream)} writes; golden {sched['cycles']} cycles "
              f"({t_geo - t0:.1f} s geometry+scan, {t_gold - t_geo:.1f} s golden schedule); running Verilator")
    # the golden frame is the engine's expected read-out (FrameBench.expect)
    hdl = run_frame_engine(stream, prod["gaps"], sched, engine="verilator")
    wall = time.perf_counter() - t0
    keys = ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")
    bad_sched = sum(int(hdl[k] != sched[k]) for k in keys)
    bad = hdl["mismatches"]   # read-out words (pixels) and schedule words that differ
    # --- the frame's time budget ------------------------------------------------------------
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
    bound_s = busy["clear (pixel bus)"] + bounds[limit]
    out = {
        "block": "pixelbus", "engine": "verilator", "cycles": int(hdl["cycles"]), "cycles_golden": int(sched["cycles"]),
        "writes": len(stream), "clock_hz": CLOCK_HZ, "pixels_compared": width * height, "mismatches": bad,
        "wall_s": wall, "build_s": hdl["build_s"],
        "cycles_per_s": hdl["sim_cycles"] / hdl["loop_s"] if hdl["loop_s"] > 0 else float("inf"),
        "frame_rgb": golden.rgb_image(hdl["rgb"]),
        "frame": {
            "triangles": tris.n_triangles, "pixel_writes": len(stream),
            "schedule_hdl": {k: hdl[k] for k in keys}, "schedule_golden": {k: sched[k] for k in keys},
            "schedule_mismatches": bad_sched,
            "frame_s": frame_s, "polygons_per_s": tris.n_triangles / frame_s,
            "pixels_per_s": len(stream) / frame_s,
            "bus_share_of_frame": len(stream) / hdl["cycles"],
            "busy_s": busy, "share_of_frame": {k: v / frame_s for k, v in busy.items()},
            "limiting": limit, "bound_s": bound_s,
            "geometry_starves": prod["geometry_starves"], "i860_clocks": prod["clocks"],
            "geometry_group_clocks": prod["group_clocks"], "inner_loop": inner_loop_ops(ran),
            "gap_mean": float(prod["gaps"].mean()) if len(stream) else 0.0,
            "timing_s": {"geometry_and_scan": t_geo - t0, "golden": t_gold - t_geo, "hdl_prepare": hdl["prepare_s"],
                         "hdl_run": hdl["run_s"], "hdl_clock_loop": hdl["loop_s"]},
        },
    }
    return out
