"""The plain-Verilator engine: a bench top generated from Amaranth around the block (one
``rasterhw_stream_source`` per input port, one ``rasterhw_stream_sink`` per output port, both in
``cocotb_tests/harness.v``; every clock domain of the block driven by the one clock, or, for a run
with separate clocks, each domain by its own bit of a ``clocks`` port that the main toggles on the
domain's schedule: one build for every set of half periods and phases), built once
per design and memory depth with the one C++ main (``cocotb_tests/plain_main.cpp``), the stimulus
loaded at run time (``$fread`` of each port's packed ``{gap, word}`` records, :mod:`packed`: no
Python int or text line per word) and the words and cycle stamps dumped at the end in binary
(``$fwrite`` ``"%u"`` with ``+dump_bin=1``, read with ``np.fromfile``; the cocotb engines, Icarus
among them, keep the ``$writememh`` text)."""

from __future__ import annotations

import inspect
import json
import os
import re
import shutil
import sys
import time
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cachefile import matches, sha256_file, warn_damaged
from rasterhw.sim.engines import waves
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.engines.ports import GAP_BITS, bench_ports, payload_of, ports_of, tag, unpack
from rasterhw.sim.engines.runner import (
    HARNESS_V,
    build_plain_verilator,
    plain_build_dir,
    run_plain_verilator,
)
from rasterhw.sim.engines.verilog import canonical_port_lists
from rasterhw.sim.engines.verilog_cache import closure_cached, convert_cached, sources_digest
from rasterhw.sim.packed import as_bytes, records
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.testbench import Run, Stimulus, Testbench, compare, port_of
from rasterhw.sim.workdirs import build_lock, release, temp_run_folder

__all__ = ["GAP_BITS", "PGO_OPT", "bench_design", "bench_sources", "collected", "hier_marked",
           "memory_depths", "profile", "run",
           "status_of", "stream_plusargs", "unpack_status"]


def _depth(n: int) -> int:
    """Memory words for ``n`` words (and one spare): the next power of two, at least 16, so runs of
    similar size share one build."""
    d = 16
    while d < n + 2:
        d *= 2
    return d


def bench_sources(tb: Testbench) -> list[Path]:
    """The Python files the bench top around ``tb``'s block is made from, beside the block's own
    (``verilog_cache.design_sources``): this engine's module and the module of ``tb``'s class and
    of each class it derives from (they build the DUT, its adapters and read-outs, its status
    values and speed Verilog), each with every module of ours it imports, transitively
    (``verilog_cache.module_sources``: the same rule as the block's)."""
    roots = [Path(__file__)] + [f for c in type(tb).__mro__ if (f := _class_file(c)) is not None]
    return _closure_cached(roots)


#: the transitive sources of each set of roots, with every file's and folder's (mtime, size) when found:
#: ``build/verilog/bench-sources-<digest>.json``, one per set of roots
_CLOSURES = BUILD_ROOT / "verilog" / "bench-sources"


def _closure_cached(roots: list[Path]) -> list[Path]:
    """:func:`module_sources` of ``roots``, kept in ``build/verilog/bench-sources-*.json`` (``verilog_cache.closure_cached``)."""
    return closure_cached(roots, _CLOSURES)


def _class_file(cls) -> Path | None:
    """The source file of class ``cls`` (None for a built-in one, such as ``object``)."""
    try:
        return Path(inspect.getfile(cls))
    except TypeError:
        return None


class _Design(tuple):
    """(build name, generated files, the main's defines) of a bench top, with ``key``: the JSON
    of everything its Verilog was cached by (:func:`ports.bench_ports` keys its port widths on it)."""

    key: str = ""


def bench_design(tb: Testbench, params: dict, inputs: dict[str, int], outputs: dict[str, int], speed: bool,
            separate: bool = False):
    """(build name, generated files, the main's defines) of the bench top around ``tb``'s block;
    ``speed``: the testbench's speed Verilog (:meth:`Testbench.sim_verilog`); ``separate``: one
    clock per domain (one build serves every set of clocks: they are run-time arguments). A cached
    Verilog is read without constructing the block (or importing Amaranth)."""
    # what builds the DUT and its adapters (the testbench's modules and all they import) is design too
    key = {**params, "inputs": inputs, "outputs": outputs, "bench": sources_digest(bench_sources(tb))[:16],
           **({"speed": True} if speed else {}), **({"clocks": list(tb.domains)} if separate else {})}
    port_domains = {n: tb.domain_of(n) for n in (*inputs, *outputs)} if separate else None

    def top():
        from rasterhw.sim.engines.benchtop import BenchTop

        dut = tb.dut(params)
        return BenchTop(dut, inputs, outputs, tb.domains, status_of(tb, dut, params), port_domains)

    def convert(top, mod):
        from amaranth.back import verilog

        text = canonical_port_lists(verilog.convert(top, name=mod, ports=top.ports)) + _extra(top.dut)
        return tb.sim_verilog(params, text) if speed else text

    text = convert_cached(tb.block, top, params=key, module="rasterhw_bench", convert=convert)
    if separate:   # the main toggles bit k of `clocks` on domain k's own schedule
        d = _Design((f"tb-{tb.block}-clocks", {"rasterhw_bench.v": text}, {**_DEFINES, "RASTERHW_CLOCKS": len(tb.domains)}))
    else:
        d = _Design((f"tb-{tb.block}", {"rasterhw_bench.v": text}, _DEFINES))
    d.key = json.dumps({"block": tb.block, **key}, sort_keys=True, default=str)
    return d


_DEFINES = {"RASTERHW_CYCLES": 1, "RASTERHW_ERRORS": 1, "RASTERHW_STATUS": 1}


def status_of(tb: Testbench, dut, params: dict) -> dict:
    """The testbench's status values (checked: 64 bits together at most)."""
    st = tb.status(dut, params)
    if sum(len(v) for v in st.values()) > 64:
        raise RasterhwError(f"{tb.block}: status values wider than 64 bits together")
    return st


def unpack_status(st: dict, word: int) -> dict[str, int]:
    """A packed status word -> ``{name: value}`` (the order and widths of ``st``)."""
    return unpack([[name, len(v)] for name, v in st.items()], word)


def _build(design, opt: str, pgo=None, hier: tuple[str, ...] = ()) -> tuple[Path, float]:
    name, generated, defines = design
    if hier:
        generated = {k: (hier_marked(v, hier) if k.endswith(".v") else v) for k, v in generated.items()}
    return build_plain_verilator(name, "rasterhw_bench", [HARNESS_V], params={}, opt=opt, defines=defines,
                                 generated=generated, pgo=pgo, hierarchical=bool(hier))


def hier_marked(text: str, modules: tuple[str, ...]) -> str:
    """``text`` with ``/*verilator hier_block*/`` after the header of each of ``modules`` (every one
    defined exactly once in it): Verilator then verilates and compiles each once, however many
    instances it has (``build={"hier": True}``)."""
    for mod in modules:
        text, k = re.subn(rf"^(module {re.escape(mod)}\b[^;]*;)", r"\1 /*verilator hier_block*/", text, flags=re.M)
        if k != 1:
            raise RasterhwError(f"hierarchical build: module {mod} is defined {k} times in the bench's Verilog, not once")
    return text


#: the g++ level of profile-guided builds (and of the instrumented build that trains them)
PGO_OPT = "-O2"


def _settings(build: dict | None, default_opt: str) -> tuple[bool, str | None, bool | str, int, int, bool]:
    """(speed, opt, pgo, depth, out_depth, hier) of a ``build`` argument (see :func:`rasterhw.sim.engines.run`);
    no ``build``: ``default_opt`` (the testbench's level)."""
    b = dict(build or {})
    unknown = sorted(set(b) - {"speed", "opt", "pgo", "depth", "out_depth", "hier"})
    if unknown:
        raise RasterhwError(f"build settings: no {', '.join(unknown)} (speed, opt, pgo, depth, out_depth, hier)")
    if not isinstance(b.get("hier", False), bool):
        raise RasterhwError(f"build settings: hier must be True or False, not {b['hier']!r}")
    for key in ("depth", "out_depth"):
        v = b.get(key, 0)
        if not isinstance(v, int) or isinstance(v, bool) or v < 0:
            raise RasterhwError(f"build settings: {key} must be a word count, not {v!r}")
    depth, out_depth = b.get("depth", 0), b.get("out_depth", 0)
    pgo = b.get("pgo", False)
    env = os.environ.get("RASTERHW_PGO", "")
    if pgo in ("auto", "train") and env in ("0", "1"):
        pgo = env == "1"
    if pgo not in (False, True, "auto", "train"):
        raise RasterhwError(f"build settings: pgo must be False, True, 'auto' or 'train', not {pgo!r}")
    return bool(b.get("speed", False)), b.get("opt", default_opt if not build else None), pgo, depth, out_depth, bool(b.get("hier", False))


def profile(tb: Testbench, params: dict, design, *, inputs: dict[str, int], outputs: dict[str, int],
            opt: str = PGO_OPT, train: bool = True, say: bool = False) -> Path | None:
    """The gcc profile of ``design`` (the bench top with these memory depths): the instrumented build
    run once on the testbench's training stimulus (:meth:`Testbench.train_stimulus`), its output
    checked against the golden model (a wrong training run is an error, not a profile), kept in
    ``build/pgo/<the instrumented build's folder>/``. Paid once per design: a cached profile is
    returned as it is; ``train=False`` returns None instead of training, and so does a testbench
    without a training stimulus or one that does not fit these memories. ``say``: a line on stderr
    before training (a run that trains without being asked to: ``pgo="train"``)."""
    name, generated, defines = design
    prof = BUILD_ROOT / "pgo" / plain_build_dir(name, "rasterhw_bench", [HARNESS_V], params={}, opt=opt,
                                                 defines=defines, generated=generated, pgo="generate").name
    if _trained(prof):
        return prof
    stim = tb.train_stimulus(params) if train else None
    if stim is None:
        return None
    exp = tb.expect(params, stim)
    want = {n: len(w) for n, w in exp.words.items()}
    if any(len(stim.words[n]) + 2 > inputs[n] for n in inputs) or any(want[n] + 2 > outputs[n] for n in outputs):
        return None
    if say:
        print(f"rasterhw: {tb.block}: first build of this design: training its gcc profile on {stim.what} "
              "(once per design, kept in the build cache; RASTERHW_PGO=0 skips it)", file=sys.stderr, flush=True)
    exe, _ = _build(design, opt, pgo="generate")
    with build_lock(prof, what=f"{tb.block} profile"):
        if _trained(prof, quiet=True):
            return prof
        shutil.rmtree(prof, ignore_errors=True)
        prof.mkdir(parents=True)
        got = _run_exe(exe, tb, params, stim, stall=0, seed=1, expect_words=want, inputs=inputs,
                       max_cycles=(10_000 + 64 * (sum(want.values()) + sum(map(len, stim.words.values())))),
                       profile=prof, packed=True)
        bad = compare(exp, Run("verilator", got[0], got[1]))["mismatches"]
        if bad:
            shutil.rmtree(prof, ignore_errors=True)
            raise RasterhwError(f"{tb.block} profile: the instrumented build's training run ({stim.what}) "
                                f"gave {bad} words that are not golden")
        # written last, with the SHA-256 of every profile file: checked at every use (_trained)
        sums = {f.name: sha256_file(f) for f in sorted(prof.glob("*.gcda"))}
        (prof / "trained.json").write_text(json.dumps({"what": stim.what, "cycles": got[3], "sha256": sums}) + "\n")
    return prof


def _trained(prof: Path, *, quiet: bool = False) -> bool:
    """A finished profile: its record is there and every ``*.gcda`` it names has the SHA-256 it
    recorded, and there are no others (a damaged profile is said in one line and trained again)."""
    try:
        sums = json.loads((prof / "trained.json").read_text()).get("sha256")
    except (OSError, ValueError, AttributeError):
        return False
    if not isinstance(sums, dict) or not sums or set(sums) != {f.name for f in prof.glob("*.gcda")}:
        if isinstance(sums, dict) and sums and not quiet:
            warn_damaged(prof, "a gcc profile")
        return False
    return all(matches(prof / k, v, what="a gcc profile file", quiet=quiet) for k, v in sums.items())


def run(tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int, expect_words: dict[str, int],
        max_cycles: int, build: dict | None = None, clocks: dict | None = None, packed: bool = False) -> Run:
    t0 = time.perf_counter()
    speed, opt, pgo, depth, out_depth, hier = _settings(build, tb.verilator_opt)
    blocks = tb.hier_blocks(params) if hier else ()
    if hier and (not blocks or pgo):
        raise RasterhwError(f"build settings: hier: {tb.block}'s testbench names no module to verilate once"
                            if not blocks else "build settings: hier and pgo do not go together")
    inputs, outputs = memory_depths(tb, params, stim, expect_words, depth=depth, out_depth=out_depth)
    top = bench_design(tb, params, inputs, outputs, speed, separate=bool(clocks))
    prof = profile(tb, params, top, inputs=inputs, outputs=outputs, opt=opt or PGO_OPT,
                   train=pgo is True or pgo == "train", say=pgo == "train") if pgo else None
    opt = opt or (PGO_OPT if prof is not None else tb.verilator_opt)
    exe, build_s = _build(top, opt, pgo=prof, hier=blocks)
    if waves.plain_trace_format() is not None:   # a trace's save file splits payloads into the block's fields
        dut = tb.dut(params)
        waves.declare_payloads({n: port_of(dut, n) for n in (*tb.inputs_of(params), *tb.outputs_of(params))})
    # the port widths and the status values' names and widths, cached with the Verilog (no block constructed)
    ports = bench_ports(tb, params, top.key, top[1]["rasterhw_bench.v"])
    words, stamps, meta, _ = _run_exe(exe, tb, params, stim, stall=stall, seed=seed, expect_words=expect_words,
                                      inputs=inputs, max_cycles=max_cycles, widths=ports["widths"], clocks=clocks,
                                      packed=packed)
    status = unpack(ports["status"], int(meta.get("status", 0)))
    return Run("verilator", words, stamps, wall_s=time.perf_counter() - t0, build_s=build_s, run_s=meta["run_s"],
               cpu_s=meta["cpu_s"],
               protocol_errors=int(meta.get("errors", 0)), status=status,
               build={"speed": speed, "opt": opt, "pgo": prof is not None, "hier": bool(blocks)},
               clocks=dict(clocks or {}),
               port_domains={n: tb.domain_of(n) for n in tb.outputs_of(params)} if clocks else {})


def memory_depths(tb: Testbench, params: dict, stim: Stimulus, expect_words: dict[str, int], *, depth: int = 0,
                  out_depth: int = 0) -> tuple[dict[str, int], dict[str, int]]:
    """The bench top's memory words per input and per output port: this run's words, or ``depth``
    / ``out_depth`` at least (one build for many runs), rounded up (:func:`_depth`)."""
    inputs = {n: _depth(max(len(stim.words[n]), depth - 2)) for n in tb.inputs_of(params)}
    outputs = {n: _depth(max(expect_words[n], out_depth - 2)) for n in tb.outputs_of(params)}
    return inputs, outputs


def _run_exe(exe: Path, tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int,
             expect_words: dict[str, int], inputs: dict[str, int], max_cycles: int, profile: Path | None = None,
             widths: dict[str, int] | None = None, clocks: dict | None = None, packed: bool = False):
    """One run of a bench binary: (words, stamps, the main's JSON line, cycles). ``widths``: every
    stream port's payload bits (None: from the block, constructed here); ``packed``: the words as
    packed rows (:func:`collected`)."""
    run_dir = temp_run_folder(exe.parent.parent)
    widths = ports_of(tb, params, tb.dut(params))["widths"] if widths is None else widths
    try:
        plus = stream_plusargs(run_dir, tb, params, stim, stall=stall, seed=seed, expect_words=expect_words,
                               inputs=inputs, widths=widths, clocks=clocks)
        meta = run_plain_verilator(exe, plus + ["+dump_bin=1"], run_dir=run_dir, maxcyc=max_cycles,
                                   profile=profile)
        outs = tb.outputs_of(params)
        words, stamps = collected(run_dir, outs, expect_words, widths={n: widths[n] for n in outs}, packed=packed)
    finally:
        release(run_dir)
    return words, stamps, meta, max((int(s[-1]) + 1 for s in stamps.values() if len(s)), default=0)


def stream_plusargs(run_dir: Path, tb: Testbench, params: dict, stim: Stimulus, *, stall: int, seed: int,
                    expect_words: dict[str, int], inputs: dict[str, int], dut=None,
                    clocks: dict | None = None, widths: dict[str, int] | None = None) -> list[str]:
    """The bench top's plusargs for one run in ``run_dir`` (any simulator): every input's packed
    ``{gap, word}`` records written to ``run_dir``, every sink's dump files, word count,
    back-pressure and seed (``widths``: the input payloads' bits, else from ``dut``, constructed if None). ``clocks`` (``{domain: Clock}``, a build with separate clocks): each
    domain's half period and first edge, as ``+clock_K=HALF,FIRST`` (default: every clock the same)."""
    if widths is None:
        dut = tb.dut(params) if dut is None else dut
        widths = {n: len(payload_of(port_of(dut, n))) for n in inputs}
    plus = []
    for n in inputs:
        t, words, gaps = tag(n), stim.words[n], stim.gaps_of(n)
        g_arr = np.asarray(gaps, dtype=np.int64)
        if g_arr.size and (g_arr.min() < 0 or g_arr.max() >= 1 << GAP_BITS):
            raise RasterhwError(f"{tb.block}: gaps on {n} must lie in 0..{(1 << GAP_BITS) - 1}")
        pw = widths[n]
        (run_dir / f"{t}.bin").write_bytes(records(as_bytes(words, pw), pw, g_arr, GAP_BITS).tobytes())
        plus += [f"+{t}={run_dir / f'{t}.bin'}", f"+{t}_n={len(words)}"]
    for k, n in enumerate(tb.outputs_of(params)):
        t = tag(n)
        plus += [f"+{t}={run_dir / f'{t}.out'}", f"+{t}_cyc={run_dir / f'{t}.cyc'}", f"+{t}_n={expect_words[n]}",
                 f"+{t}_stall={tb.stall_of(n, stall)}", f"+{t}_seed={tb.sink_seed(params, k, seed) & 0xFFFF_FFFF}"]
    # every edge after time 0 (the times are relative), as on pysim
    after = max((c.half for c in (clocks or {}).values()), default=0)
    return plus + [f"+clock_{k}={c.half},{after + c.first}" for k, c in enumerate((clocks or {}).values())]


def collected(run_dir: Path, outs, expect_words: dict[str, int], widths: dict[str, int] | None = None,
              packed: bool = False) -> tuple[dict[str, list[int]], dict[str, list[int]]]:
    """(words, stamps) per output port from the sinks' dumps in ``run_dir``: ``$writememh`` text, or
    with ``widths`` (``{port: payload bits}``, a run with ``+dump_bin=1``) the binary dumps, the
    words then as packed rows if ``packed`` (:func:`_binary_rows`) and the stamps an int64 array."""
    words, stamps = {}, {}
    for n in outs:
        t, k = tag(n), expect_words[n]
        if widths is not None:
            if packed:
                words[n] = (_binary_rows(run_dir / f"{t}.out", widths[n])[:k] if k
                            else np.zeros((0, -(-widths[n] // 8)), np.uint8))
            else:
                words[n] = _binary(run_dir / f"{t}.out", widths[n])[:k] if k else []
            if packed:   # the stamps as one int64 array too: no Python int per word (1.3 M: ~0.04 CPU-s)
                stamps[n] = _dump(run_dir / f"{t}.cyc", 32)[0].view("<u4")[:k].astype(np.int64)
            else:
                stamps[n] = _binary(run_dir / f"{t}.cyc", 32)[:k] if k else []
        else:
            words[n] = _ints(read_memh(run_dir / f"{t}.out", None))[:k] if k else []
            stamps[n] = _ints(read_memh(run_dir / f"{t}.cyc", None))[:k] if k else []
    return words, stamps


def _dump(path: Path, bits: int) -> tuple[np.ndarray, int]:
    """A sink's binary dump (``$fwrite`` ``"%u"``: each word little-endian in ``4 * ceil(bits / 32)``
    bytes) as its bytes, and that word size."""
    size = 4 * -(-bits // 32)
    raw = np.fromfile(path, np.uint8)
    if raw.size % size:
        raise RasterhwError(f"{path}: {raw.size} bytes, not whole {size}-byte words")
    return raw, size


def _binary_rows(path: Path, bits: int) -> np.ndarray:
    """A sink's binary dump as packed rows (``packed.py``: ``(N, ceil(bits / 8))`` uint8, big-endian)."""
    raw, size = _dump(path, bits)
    return np.ascontiguousarray(raw.reshape(-1, size)[:, ::-1][:, size - -(-bits // 8):])


def _binary(path: Path, bits: int) -> list[int]:
    """A sink's binary dump as Python ints; words of up to 64 bits in one NumPy pass."""
    raw, size = _dump(path, bits)
    if size <= 8:
        return raw.view("<u4" if size == 4 else "<u8").tolist()
    b, from_bytes = raw.tobytes(), int.from_bytes   # slices of one bytes object: 0.6x the CPU of row.tobytes()
    return [from_bytes(b[i:i + size], "little") for i in range(0, len(b), size)]


def _extra(dut) -> str:
    """Hand-written Verilog the block instantiates (its ``extra_verilog()``, e.g. a RAM model), if any."""
    return dut.extra_verilog() if hasattr(dut, "extra_verilog") else ""


def _ints(b) -> list[int]:
    """Dumped words (``read_memh`` rows) as Python ints; words of up to 64 bits in one NumPy pass
    (a million-word frame read-out: 0.3 s instead of 4 s)."""
    if 0 < b.shape[1] <= 8:
        return memh_uint64(b, 0, b.shape[1]).tolist()
    return [int.from_bytes(row.tobytes(), "big") for row in b]
