"""Driver: run a scene through the ZB/M HDL (one or more units) and check it bit for bit.

``simulate_zbm`` runs the golden geometry pipeline, builds the edge pairs, checks them,
runs the whole frame through ``units`` chained ``ZbmUnit``\\s (``interleave`` chips each)
and compares every scan line's double-Z pixels (both samples, Z and colour: the whole
128-bit merge word) with ``golden_model.zbm.render_zbm``, then composites.

Engines: ``pysim`` (Amaranth simulator, small frames), ``verilator`` (the generated Verilog
inside ``cocotb_tests/zbm/fast/tb_zbm_unit_fast.v`` on plain Verilator with a C++ main:
:func:`rasterhw.sim.zbm.fast.run_unit_fast`) and ``icarus``: the generated Verilog inside
``cocotb_tests/zbm/tb_zbm_unit.v`` (Verilog-side clocks, edge pairs preloaded from a hex file
and played out at full speed, merge words collected into a frame memory and dumped), run under
cocotb through :mod:`rasterhw.sim.engines.runner` (``run_unit_bench``, also on Verilator).  The same benches
(with random idle gaps, back-pressure, clock ratios and the Python stream checkers) are the
cocotb tests, ``tests/zbm/test_zbm_cocotb.py``.

Generated Verilog is cached under ``build/zbm-verilog/`` keyed by the block parameters and a
digest of the ZB/M HDL sources, so a changed HDL file regenerates it.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.seggen import check_edge_pair_stream
from rasterhw.golden_model.zbm.words import (
    doublez_words,
    edge_pair_words,
    merge_words,
    segment_words,
    split_merge_words,
)
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    REPO_ROOT,
    build_dir_for,
    get_sim,
    run_cocotb,
    verilator_make_flags,
)
from rasterhw.sim.workdirs import keep as keep_run_folder
from rasterhw.sim.workdirs import temp_run_folder

__all__ = [
    "CLOCK_HZ", "ENGINES", "GAP_BITS",
    "check_edge_pairs", "chain_verilog", "stimulus_depth", "chip_stimulus", "random_gaps",
    "read_hex_words", "run_chip_bench", "run_unit_bench", "run_units_pysim",
    "chip_speed",
]

ENGINES = ("pysim", "verilator", "icarus")
CLOCK_HZ = 25e6          # the paper's segment clock (sec. 6.1)
GAP_BITS = 8             # idle clocks before a stimulus word, in the bench's stimulus files
BENCH_DIR = REPO_ROOT / "cocotb_tests" / "zbm"
TEST_MODULE = "cocotb_tests.zbm.test_zbm"
# Verilator: cocotb's runner passes --public-flat-rw, which makes every signal of the ~0.4 MB
# (chip) / 3 MB (unit, I = 8) generated Verilog public: Verilator then keeps every alias wire
# as a member, optimises nothing across them and writes megabytes of run-once constructor code
# (the 357 s first build and 5.5 k cycles/s of the c300 unit run). The benches read only the
# wrappers' own signals: zbm_public.vlt makes those (read-only) public and nothing else.
VERILATOR_ARGS = ("--no-public-flat-rw", str(BENCH_DIR / "zbm_public.vlt"))
#: the unit bench's Verilog beside the generated units: its top, the part it shares with the plain
#: bench (fast/tb_zbm_unit_fast.v), and the harness
UNIT_BENCH = (HARNESS_V, BENCH_DIR / "tb_zbm_unit_core.v", BENCH_DIR / "tb_zbm_unit.v")
# The cocotb test module imports NumPy inside the simulator process: one BLAS thread, so that
# idle OpenBLAS workers do not compete with the simulation for this machine's 2 cores.
_SIM_ENV = {"OPENBLAS_NUM_THREADS": "1"}


# ====================================================================== stimulus and words
def random_gaps(n: int, seed: int | None, *, p_idle: float = 0.3, max_gap: int = 4) -> np.ndarray:
    """Idle clocks before each of ``n`` words: 0 with probability ``1 - p_idle``, else 1..max_gap.
    ``seed=None`` gives no gaps."""
    if seed is None:
        return np.zeros(n, np.int64)
    rng = np.random.default_rng(seed)
    return rng.integers(1, max_gap + 1, n) * (rng.random(n) < p_idle)


def _write_hex(path: Path, words, gaps, pw: int) -> None:
    if len(words) and int(np.max(gaps, initial=0)) >= (1 << GAP_BITS):
        raise RasterhwError(f"gap {int(np.max(gaps))} does not fit the bench's {GAP_BITS}-bit gap field")
    text = "\n".join(f"{(int(g) << pw) | int(w):x}" for w, g in zip(words, gaps, strict=True))
    path.write_text((text or "0") + "\n")   # $readmemh wants at least one word


def read_hex_words(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A $writememh dump of 128-bit words -> (s0, s1) uint64 arrays (low, high 64 bits)."""
    b = read_memh(path)
    if b.shape[1] > 16:
        raise RasterhwError(f"{path}: words wider than 128 bits")
    b = np.concatenate([np.zeros((b.shape[0], 16 - b.shape[1]), np.uint8), b], axis=1)
    return memh_uint64(b, 8, 16), memh_uint64(b, 0, 8)


def check_edge_pairs(eps: G.EdgePairs, width: int, height: int, *, units: int = 1,
                     capacity: int = F.AEP_CAPACITY) -> int:
    """Reject streams the hardware cannot run, before any simulation; return the worst unit's
    peak number of active edge pairs.

    Errors (``RasterhwError``): ``len < 0``; lines outside ``0..height-1`` (or ``h < 1``);
    top lines out of FIFO order; more than ``capacity`` pairs active on one line in one unit
    (the loader would stall and segments would be lost: the frame would not be the scene).
    """
    if len(eps) == 0:
        return 0
    check_edge_pair_stream(eps, height, who="ZB/M")
    peak = 0
    for u in range(units):
        pu, line = G.max_active_edge_pairs(eps.take(np.flatnonzero(eps.tag % units == u)))
        if pu > capacity:
            raise RasterhwError(f"ZB/M: unit {u} has {pu} edge pairs active on line {line}, more than the "
                                f"active-edge-pair memory holds ({capacity}); use more units or a smaller scene")
        peak = max(peak, pu)
    return peak


# ====================================================================== Verilog
def _digest(**params) -> str:
    from rasterhw.sim.engines.verilog_cache import source_digest

    # every source the block's generated Verilog can depend on (its HDL, the formats, the
    # generator); the tail unit and the chain adapter go with the unit
    block = str(params.get("block", ""))
    h = hashlib.sha1(json.dumps(params, sort_keys=True, default=str).encode())
    h.update(source_digest({"zbm-unit-tail": "zbm-unit", "zbm-chain-flat": "zbm-unit"}.get(block, block)).encode())
    return h.hexdigest()[:12]


def _cached(name: str, text_fn, **params) -> tuple[Path, str]:
    """Generated Verilog cached by (block, parameters, HDL digest); returns (path, digest)."""
    dig = _digest(block=name, **params)
    path = REPO_ROOT / "build" / "zbm-verilog" / f"{name}-{dig}.v"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(text_fn())
        tmp.replace(path)
    return path, dig


def _adapter(interleave: int, units: int, has_overflow: bool) -> str:
    """``zbm_chain_flat``: ``units`` units chained by merge ports, ports packed into vectors.
    ``overflow`` (one bit per unit) is the units' sticky overflow flag, 0 if they have none."""
    I, U, EW, MW = interleave, units, F.EP_WORD_BITS, F.PIXEL2.width  # noqa: E741
    out = [
        "// Written by rasterhw.sim.zbm.driver: units chained by their merge ports (unit 0 = head),",
        "// ports packed into vectors for tb_zbm_unit.v.",
        "module zbm_chain_flat(clk, rst, merge_clk, merge_rst, i_valid, i_ready, i_payload,",
        "                      o_valid, o_ready, o_payload, cycles, frames, overflow);",
        "  input clk, rst, merge_clk, merge_rst;",
        f"  input [{U - 1}:0] i_valid;", f"  output [{U - 1}:0] i_ready;", f"  input [{EW * U - 1}:0] i_payload;",
        f"  output [{I - 1}:0] o_valid;", f"  input [{I - 1}:0] o_ready;", f"  output [{MW * I - 1}:0] o_payload;",
        f"  output [{32 * U - 1}:0] cycles;", f"  output [{16 * U - 1}:0] frames;",
        f"  output [{U - 1}:0] overflow;",
    ]
    if not has_overflow:
        out.append(f"  assign overflow = {U}'d0;")
    for k in range(U - 1):
        for c in range(I):
            out += [f"  wire m{k}_{c}_v, m{k}_{c}_r;", f"  wire [{MW - 1}:0] m{k}_{c}_p;"]
    for k in range(U):
        mod = "zbm_unit" if k == 0 else "zbm_unit_tail"
        ports = [".clk(clk)", ".rst(rst)", ".merge_clk(merge_clk)", ".merge_rst(merge_rst)",
                 f".i__valid(i_valid[{k}])", f".i__ready(i_ready[{k}])",
                 f".i__payload(i_payload[{EW * k + EW - 1}:{EW * k}])",
                 f".cycles(cycles[{32 * k + 31}:{32 * k}])", f".frames(frames[{16 * k + 15}:{16 * k}])"]
        if has_overflow:
            ports.append(f".overflow(overflow[{k}])")
        for c in range(I):
            if k == U - 1:
                ports += [f".o_merge__{c}__valid(o_valid[{c}])", f".o_merge__{c}__ready(o_ready[{c}])",
                          f".o_merge__{c}__payload(o_payload[{MW * c + MW - 1}:{MW * c}])"]
            else:
                ports += [f".o_merge__{c}__valid(m{k}_{c}_v)", f".o_merge__{c}__ready(m{k}_{c}_r)",
                          f".o_merge__{c}__payload(m{k}_{c}_p)"]
            if k > 0:
                ports += [f".i_merge__{c}__valid(m{k - 1}_{c}_v)", f".i_merge__{c}__ready(m{k - 1}_{c}_r)",
                          f".i_merge__{c}__payload(m{k - 1}_{c}_p)"]
        out.append(f"  {mod} u{k} (\n    " + ",\n    ".join(ports) + "\n  );")
    out.append("endmodule")
    return "\n".join(out) + "\n"


def chain_verilog(*, interleave: int, width: int, height: int, units: int = 1,
                  capacity: int = F.AEP_CAPACITY, schedule: str = "overlap") -> list[Path]:
    """Verilog sources of ``units`` chained ``zbm-unit``\\s (``generate_verilog``), cached.

    The head unit is the generated ``zbm_unit``; the others (``head=False``, with merge
    inputs) are renamed ``zbm_unit_tail`` so both can live in one simulation.
    """
    from rasterhw.sim.engines.verilog import generate_verilog

    p = {"interleave": interleave, "width": width, "height": height, "capacity": capacity, "schedule": schedule}
    head, _ = _cached("zbm-unit", lambda: generate_verilog("zbm-unit", head=True, **p), head=True, **p)
    srcs = [head]
    if units > 1:
        def tail_text():
            t = generate_verilog("zbm-unit", head=False, **p)
            return t.replace("zbm_unit", "zbm_unit_tail")
        tail, _ = _cached("zbm-unit-tail", tail_text, head=False, **p)
        srcs.append(tail)
    decl = head.read_text().split("module zbm_unit(", 1)[1].split(";", 1)[0]
    ovf = "overflow" in decl
    adapter, _ = _cached("zbm-chain-flat", lambda: _adapter(interleave, units, ovf), interleave=interleave,
                         units=units, overflow=ovf)
    return srcs + [adapter]


def _plusargs(ratio: tuple[int, int], stall: int, seed: int, maxcyc: int, phase: int = 1) -> list[str]:
    """Bench plusargs. ``phase`` (ns) delays the merge clock against the segment clock: 1 (the
    tests) puts every merge edge in its own simulator time slot; 0 (speed runs, equal clocks)
    lets both clocks tick in the same slots, half as many evaluations per cycle."""
    sh, mh = ratio
    if phase not in (0, 1):
        raise RasterhwError(f"merge clock phase must be 0 or 1 ns, not {phase!r}")
    if not (isinstance(sh, int) and isinstance(mh, int) and sh >= 1 and mh >= 1):
        raise RasterhwError(f"clock ratio must be two positive integer half periods (ns), not {ratio!r}")
    if not 0 <= stall <= 255:
        raise RasterhwError(f"stall must be in 0..255, not {stall!r}")
    return [f"+sync_half={sh}", f"+merge_half={mh}", f"+merge_phase={phase}", f"+stall={stall}", f"+seed={seed}",
            f"+maxcyc={maxcyc}"]


def _expect_env(expect, speed_run: bool) -> dict:
    """A bench run compares with the golden frame inside cocotb; without one it must be an
    explicit speed run whose caller compares the dump itself (simulate_zbm, chip_speed)."""
    if expect is None and not speed_run:
        raise RasterhwError("ZB/M bench: give the golden frame (expect=) or say speed_run=True")
    return {"ZBM_SPEED_RUN": "1"} if expect is None else {}


def _depth(n: int) -> int:
    return max(1024, 1 << int(n + 2).bit_length())


def stimulus_depth(words: int, depth: int | None = None) -> int:
    """A bench's stimulus memory depth for ``words`` words: ``depth`` if given (it must hold them),
    else the smallest power of two (>= 1024) that does."""
    need = _depth(words)
    if depth is None:
        return need
    if not isinstance(depth, int) or depth < words + 2:
        raise RasterhwError(f"stimulus depth {depth!r} does not hold {words} words")
    return depth


# ====================================================================== unit bench
def write_unit_stimulus(run_dir: Path, words: list[list[int]], gap_seed: int | None) -> tuple[list[int], list[int]]:
    """The unit benches' stimulus files (tb_zbm_unit.v, fast/tb_zbm_unit_fast.v): every unit's
    loader words in one ``stim.hex`` (with random idle gaps from ``gap_seed``, None: none) and
    ``index.hex``, two lines per unit (first word, number of words). Returns (words, index)."""
    flat, index = [], []
    for w in words:
        index += [len(flat), len(w)]
        flat += w
    _write_hex(run_dir / "stim.hex", flat, random_gaps(len(flat), gap_seed), F.EP_WORD_BITS)
    (run_dir / "index.hex").write_text("\n".join(f"{v:x}" for v in index) + "\n")
    return flat, index


def unit_watchdog(total_words: int, *, width: int, height: int, stall: int = 0,
                  ratio: tuple[int, int] = (5, 5)) -> int:
    """The unit benches' watchdog in segment clocks (cocotb and plain Verilator alike): generously
    above any frame this design can take with ready always high and equal clocks, times the
    expected slow-down of the back-pressure (ready high in ``256 - stall`` of 256 merge clocks) and
    of a merge clock slower than the segment clock (``ratio`` = half periods, segment : merge)."""
    base = 200 * (total_words + 64) + 40 * height * (width + 64)
    slow = 256 / max(1, 256 - stall) * max(1.0, ratio[1] / ratio[0])
    return min(int(base * max(1.0, slow)), 2**31 - 1)   # the bench's MAXCYC is a Verilog integer


def run_unit_bench(eps_per_unit: list[G.EdgePairs], *, width: int, height: int, interleave: int,
                   sim: str | None = None, capacity: int = F.AEP_CAPACITY, ratio: tuple[int, int] = (5, 5),
                   stall: int = 0, seed: int = 1, gap_seed: int | None = None,
                   expect: tuple[np.ndarray, np.ndarray] | None = None, speed_run: bool = False,
                   check_protocol: bool = False,
                   keep: bool = False, phase: int = 1, schedule: str = "overlap", line_log: bool = False,
                   opt: str = "-O1", sdepth: int | None = None) -> dict:
    """Run a chain of units (unit k gets ``eps_per_unit[k]``) on the generated Verilog.

    ``ratio`` = (segment, merge) clock half periods in ns; ``stall`` = back-pressure level
    (0..255, ready low when a seeded 8-bit random number is below it); ``gap_seed`` = seed of
    the random idle gaps before input words (None: none); ``phase`` = merge clock delay in ns
    (1, or 0 for speed runs: see :func:`_plusargs`).  With ``expect`` = (s0, s1) (H, W)
    golden words the cocotb test itself compares every scan line and (``check_protocol``)
    runs the Python stream checkers and in-order scoreboards. Without ``expect`` the caller must say
    ``speed_run=True`` (it compares the returned dump itself); else RasterhwError.
    ``opt``: C++ optimisation of the per-cycle code (``-O0`` for the small timing benches, whose
    build dominates). ``line_log``: also return ``line_cycles`` (H,): unit 0's segment-clock count in the merge
    cycle in which the last chip slot finished each merge output line. ``sdepth``: the bench's
    stimulus memory depth (a build parameter; default the smallest that holds the words): runs of
    different sizes that pass the same depth share one build.
    Returns ``{"s0", "s1": (H, W) uint64, "cycles", "proto_errors", "build_s", "run_s", ...}``.
    """
    exp_env = _expect_env(expect, speed_run)   # before any work
    sim = get_sim(sim)
    units = len(eps_per_unit)
    t0 = time.perf_counter()
    srcs = chain_verilog(interleave=interleave, width=width, height=height, units=units, capacity=capacity,
                         schedule=schedule)
    words = [edge_pair_words(e) for e in eps_per_unit]
    total = sum(len(w) for w in words)
    sdepth = stimulus_depth(total, sdepth)
    params = {"I": interleave, "U": units, "W": width, "H": height, "GW": GAP_BITS, "SDEPTH": sdepth}
    # the .vlt is a build input too: a change to it must give a fresh build
    bdir = build_dir_for("zbm-unit", sim, sources=[*srcs, *UNIT_BENCH, BENCH_DIR / "zbm_public.vlt"], **params)
    bdir.mkdir(parents=True, exist_ok=True)
    run_dir = temp_run_folder(bdir)
    flat, index = write_unit_stimulus(run_dir, words, gap_seed)
    out_path = run_dir / "frame.hex"
    env = {"ZBM_BENCH": "unit", "ZBM_OUT": str(out_path), "ZBM_CHECK_PROTOCOL": "1" if check_protocol else "0",
           **exp_env, **_SIM_ENV}
    if expect is not None:
        exp_path = run_dir / "expect.npz"
        np.savez(exp_path, s0=expect[0], s1=expect[1], interleave=interleave, units=units,
                 stim=np.array([f"{x:x}" for x in flat]), index=np.array(index, np.int64))
        env["ZBM_EXPECT"] = str(exp_path)
    maxcyc = unit_watchdog(total, width=width, height=height, stall=stall, ratio=ratio)
    t1 = time.perf_counter()
    timings: dict = {}
    with verilator_make_flags(opt, coroutines=True):
        run_cocotb(sources=[*srcs, *UNIT_BENCH], toplevel="tb_zbm_unit",
                   test_module=TEST_MODULE, testcase="zbm_unit_frame", build_dir=bdir, test_dir=run_dir, sim=sim,
                   parameters=params,
                   plusargs=[f"+stim={run_dir / 'stim.hex'}", f"+index={run_dir / 'index.hex'}", f"+out={out_path}",
                             *_plusargs(ratio, stall, seed, maxcyc, phase),
                             *([f"+lines={run_dir / 'lines.hex'}"] if line_log else [])],
                   extra_env=env, timings=timings, verilator_args=VERILATOR_ARGS)
    t2 = time.perf_counter()
    meta = json.loads((run_dir / "result.json").read_text())
    s0, s1 = read_hex_words(out_path)
    if s0.size != width * height:
        raise RasterhwError(f"{out_path}: {s0.size} words, expected {width * height}")
    res = {"s0": s0.reshape(height, width), "s1": s1.reshape(height, width), **meta,
           "prepare_s": t1 - t0, "build_s": timings["build_s"], "run_s": timings["test_s"],
           "total_s": t2 - t0, "run_dir": run_dir if keep else None}
    if line_log:
        res["line_cycles"] = [int(v, 16) for v in (run_dir / "lines.hex").read_text().split()
                              if not v.startswith("//")]
    if keep or os.environ.get("ZBM_KEEP") == "1":
        keep_run_folder(run_dir)
    else:
        shutil.rmtree(run_dir, ignore_errors=True)
    return res


# ====================================================================== chip bench
def chip_stimulus(segs: G.Segments, lines: int, upstream: G.DoubleZ, *, chip: int, interleave: int,
                  width: int) -> tuple[list[int], list[int], tuple[np.ndarray, np.ndarray]]:
    """Segment-port words for lines ``0..lines-1`` (segments + end of line), upstream merge
    words (``upstream``: (lines, npx) DoubleZ, chip order) and the expected merge output
    ``merge(upstream, chip_scanline)`` as (s0, s1) (lines, npx) words."""
    seg_words = []
    exp = G.DoubleZ.empty((lines, upstream.z.shape[1]))
    for y in range(lines):
        seg_words += segment_words(segs, y)
        own, _ = G.chip_scanline(segs, y, chip, interleave, width)
        up = G.DoubleZ(upstream.z[y], upstream.a[y], upstream.c[y], upstream.tag[y])
        m = G.merge(up, own)
        exp.z[y], exp.a[y], exp.c[y], exp.tag[y] = m.z, m.a, m.c, m.tag
    return seg_words, merge_words(*doublez_words(upstream)), doublez_words(exp)


def run_chip_bench(seg_words: list[int], up_words: list[int], *, lines: int, chip: int, interleave: int,
                   width: int, sim: str | None = None, ratio: tuple[int, int] = (5, 5), stall: int = 0,
                   seed: int = 1, gap_seed: int | None = None, repeat: int = 1,
                   expect: tuple[np.ndarray, np.ndarray] | None = None, speed_run: bool = False,
                   check_protocol: bool = False,
                   phase: int = 1) -> dict:
    """Run one ``zbm-chip`` on the generated Verilog (see :func:`run_unit_bench` for the knobs);
    ``repeat`` plays the stimulus that many times (speed runs).  Returns ``{"s0", "s1":
    (lines, npx) uint64 of the last repetition, "cycles", "lines", "proto_errors", "run_s", ...}``."""
    exp_env = _expect_env(expect, speed_run)   # before any work
    from rasterhw.sim.engines.verilog import generate_verilog

    sim = get_sim(sim)
    t0 = time.perf_counter()
    p = {"interleave": interleave, "chip": chip, "width": width}
    src, _ = _cached("zbm-chip", lambda: generate_verilog("zbm-chip", **p), **p)
    npx = -(-(width - chip) // interleave)
    params = {"I": interleave, "CHIP": chip, "W": width, "L": lines, "GW": GAP_BITS,
              "SDEPTH": _depth(len(seg_words)), "MDEPTH": _depth(len(up_words))}
    bdir = build_dir_for("zbm-chip", sim, sources=[src, HARNESS_V, BENCH_DIR / "tb_zbm_chip.v", BENCH_DIR / "zbm_public.vlt"],
                         **params)
    bdir.mkdir(parents=True, exist_ok=True)
    run_dir = temp_run_folder(bdir)
    g = random_gaps(len(seg_words) + len(up_words), gap_seed)
    _write_hex(run_dir / "seg.hex", seg_words, g[:len(seg_words)], F.LOOP_BITS)
    _write_hex(run_dir / "up.hex", up_words, g[len(seg_words):], F.PIXEL2.width)
    out_path = run_dir / "out.hex"
    env = {"ZBM_BENCH": "chip", "ZBM_OUT": str(out_path), "ZBM_CHECK_PROTOCOL": "1" if check_protocol else "0",
           **exp_env, **_SIM_ENV}
    if expect is not None:
        np.savez(run_dir / "expect.npz", s0=expect[0], s1=expect[1], repeat=repeat,
                 seg=np.array([f"{x:x}" for x in seg_words]), up=np.array([f"{x:x}" for x in up_words]))
        env["ZBM_EXPECT"] = str(run_dir / "expect.npz")
    maxcyc = repeat * (40 * len(seg_words) + 40 * lines * (npx + 16)) + 1000
    t1 = time.perf_counter()
    timings: dict = {}
    with verilator_make_flags("-O2", coroutines=True):
        run_cocotb(sources=[src, HARNESS_V, BENCH_DIR / "tb_zbm_chip.v"], toplevel="tb_zbm_chip",
                   test_module=TEST_MODULE, testcase="zbm_chip_lines", build_dir=bdir, test_dir=run_dir, sim=sim,
                   parameters=params,
                   plusargs=[f"+seg={run_dir / 'seg.hex'}", f"+up={run_dir / 'up.hex'}", f"+out={out_path}",
                             f"+nseg={len(seg_words)}", f"+nup={len(up_words)}", f"+repeat={repeat}",
                             *_plusargs(ratio, stall, seed, maxcyc, phase)],
                   extra_env=env, timings=timings, verilator_args=VERILATOR_ARGS)
    t2 = time.perf_counter()
    meta = json.loads((run_dir / "result.json").read_text())
    s0, s1 = read_hex_words(out_path)
    res = {"s0": s0.reshape(lines, npx), "s1": s1.reshape(lines, npx), **meta, "prepare_s": t1 - t0,
           "build_s": timings["build_s"], "run_s": timings["test_s"], "total_s": t2 - t0}
    if os.environ.get("ZBM_KEEP") != "1":
        shutil.rmtree(run_dir, ignore_errors=True)
    return res


def chip_speed(*, interleave: int = 8, width: int = 512, height: int = 512, scene: str = "c300",
               repeat: int = 8, sim: str = "verilator") -> dict:
    """Segment-clock cycles per second of one chip (chip 0) on preloaded stimulus: the
    segments of ``scene`` at ``width x height`` (golden segment generator), played ``repeat``
    times with no gaps or back-pressure; the last repetition is checked bit for bit."""
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.pipeline import run_geometry

    tris = run_geometry(load_scene(scene), width, height)
    segs = G.segment_generator(G.edge_pairs(tris), height, width=width)
    npx = -(-width // interleave)
    up = G.DoubleZ.empty((height, npx))
    seg_w, up_w, exp = chip_stimulus(segs, height, up, chip=0, interleave=interleave, width=width)
    r = run_chip_bench(seg_w, up_w, lines=height, chip=0, interleave=interleave, width=width, sim=sim,
                       repeat=repeat, phase=0, speed_run=True)
    bad = int(np.count_nonzero((r["s0"] != exp[0]) | (r["s1"] != exp[1])))
    return {"block": "zbm-chip", "engine": sim, "interleave": interleave, "scene": scene, "repeat": repeat,
            "cycles": r["cycles"], "run_s": r["run_s"], "build_s": r["build_s"],
            "cycles_per_s": r["cycles"] / r["run_s"], "mismatches": bad, "proto_errors": r["proto_errors"]}


# ====================================================================== pysim
def run_units_pysim(eps_per_unit: list[G.EdgePairs], *, width: int, height: int, interleave: int,
                    capacity: int = F.AEP_CAPACITY, max_cycles: int = 2_000_000,
                    schedule: str = "overlap") -> dict:
    """The same chain in the Amaranth simulator (small frames): returns ``{"s0", "s1", "cycles",
    "proto_errors"}`` (stream-rule violations counted by checkers on every input and output)."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.zbm.chain import ZbmChain
    from rasterhw.hdl.zbm.unit import ZbmUnit

    units = [ZbmUnit(interleave=interleave, width=width, height=height, capacity=capacity, head=(k == 0),
                     schedule=schedule) for k in range(len(eps_per_unit))]
    sim = Simulator(ZbmChain(units))
    sim.add_clock(1e-8, domain="sync")
    sim.add_clock(1e-8, domain="merge")
    last = units[-1]
    got = {c: [] for c in range(interleave)}
    need = {c: last.chip_pixels(c) * height for c in range(interleave)}
    out: dict = {}

    def src(u, words):
        async def bench(ctx):
            for w in words:
                await stream_put(ctx, u.i, w)
        return bench

    async def sink(ctx):
        for c in got:
            ctx.set(last.o_merge[c].ready, 1)
        sigs = [s for c in got for s in (last.o_merge[c].valid, last.o_merge[c].payload)]
        n = 0
        while any(len(got[c]) < need[c] for c in got):
            _, _, *vals = await ctx.tick("merge").sample(*sigs)
            n += 1
            if n > max_cycles:
                raise RasterhwError(f"ZB/M pysim: no complete frame after {max_cycles} cycles")
            for i, c in enumerate(got):
                if vals[2 * i] and len(got[c]) < need[c]:
                    got[c].append(vals[2 * i + 1].as_value().value)
        out["cycles"] = int(ctx.get(units[0].cycles))

    violations: list[str] = []   # stream-rule violations on every unit input and merge output
    for u, e in zip(units, eps_per_unit, strict=True):
        sim.add_testbench(src(u, edge_pair_words(e)), background=True)
        sim.add_testbench(stream_protocol_checker(u.i, "i", errors=violations), background=True)
    for c in range(interleave):
        sim.add_testbench(stream_protocol_checker(last.o_merge[c], f"o_merge[{c}]", errors=violations,
                                                  domain="merge"), background=True)
    sim.add_testbench(sink)
    sim.run()
    s0 = np.zeros((height, width), np.uint64)
    s1 = np.zeros((height, width), np.uint64)
    for c in got:
        s0[:, c::interleave], s1[:, c::interleave] = split_merge_words(np.array(got[c], dtype=object).reshape(height, -1))
    return {"s0": s0, "s1": s1, "cycles": out["cycles"], "proto_errors": len(violations)}
