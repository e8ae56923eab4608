"""Many independent runs at once, on one machine or a Dask cluster: the one way every command
that runs more than one simulation (``rasterhw sweep``, ``rasterhw soak``) runs its tasks.

A :class:`Task` is one run, named by what it is and nothing else: its ``kind`` (``"sim"``: a
registered sim block's ``SimBlock.simulate``; ``"render"``: a golden arch's renderer;
``"call"``: any ``"module:function"`` called with the task's parameters, e.g. one soak round),
its typed parameters, its scene and frame size, its engine. Every seed a run uses derives from
the task (a soak round's seed is a parameter), never from the worker that runs it, so a task's
result is the same on every scheduler and every worker, apart from :data:`VARYING` (timings and
who ran it). Its result is the run's JSON-able dict, with ``wall_s`` (the run), ``worker`` (the
Dask worker's address, ``"in-process"`` for ``serial``) and ``pid`` added.

:class:`Runner` runs tasks on a scheduler named by one string (``--scheduler``):

* ``serial`` — in this process, one after another (debugging; nothing is started);
* ``local`` / ``local:N`` — a ``dask.distributed.LocalCluster`` of ``N`` worker processes (default:
  one per core), one thread each (the simulators are single-threaded and the models hold the GIL);
  see "What a local cluster costs" below;
* ``tcp://HOST:PORT`` — an existing Dask scheduler (``dask scheduler`` + ``dask worker``, SLURM via
  dask-jobqueue, SSH hosts: ``docs/scale.md``); ``--scheduler-file FILE`` names it by the file
  ``dask scheduler --scheduler-file FILE`` writes (:func:`scheduler_from_file`).

What a local cluster costs, and what is done about it (issue 51 item 5: ``sweep`` on ``local:2``
was half the speed of ``serial`` on small sweeps). Measured under load (``sim/flow/tasks.py``'s
note in ``docs/scale.md``): starting two worker processes by ``spawn`` (Dask's default) took 4.9-5.3 s
of wall time and each worker imported Python, Dask, NumPy and rasterhw again (1.7 s CPU for two);
closing the cluster 1.7-2.0 s; and a command that runs several lists of tasks (a report) started
and stopped a cluster per list. Now:

* one cluster per process and size: every :class:`Runner` of a command with ``local:N`` uses the
  same cluster (its workers keep what they built and imported: generated Verilog, elaborated
  designs, loaded models, numba's compiled code), closed at the command's end (:func:`close_clusters`);
* workers are forked from a fork server that imported Dask, NumPy and this module once
  (``forkserver`` with a preload list): starting two took 2.6-3.2 s and closing 0.1-0.2 s, same load;
* :meth:`Runner.map` hands small tasks to the workers in batches (a few per worker, so that a
  slow task still leaves the others busy), not one Dask task each;
* the dashboard: with bokeh installed (``pip install rasterhw[dashboard]``) the cluster serves
  Dask's dashboard on a free port and its address is said on stderr; without bokeh none. Every
  port is a free one (never 8787: two commands at once do not clash).

Results come back in task order (:meth:`Runner.map`; :meth:`Runner.submit` / :meth:`Runner.result`
for callers that decide as they go, like the soak). Every finished result is written to the store
(``--store DIR``, default ``build/tasks/`` of the checkout) as soon as it finishes, keyed by
:meth:`Task.digest`: the task, a digest of every source file of the package (the design, the golden
model, the benches: :func:`code_digest`) and the tools (:func:`tool_versions`: Python, NumPy,
Amaranth, Verilator, cocotb, the C++ compiler and the flags the environment passes it). A task
whose result is in the store is not run again (``fresh=True``: run everything). A worker killed
mid-task has the task run again on another worker by the Dask scheduler (up to its
``allowed-failures``); every task still gives exactly one result.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.paths import BUILD_ROOT, REPO_ROOT

__all__ = ["VARYING", "Handle", "Runner", "Task", "call", "check_scheduler", "close_clusters", "code_digest",
           "batch_size", "default_store", "local_client", "one_cluster", "parse_scheduler", "run_batch", "scheduler_from_file", "task_modules",
           "run_task", "run_tasks", "tool_versions"]

#: result keys that may differ between two runs of one task (timings, who ran it)
VARYING = ("wall_s", "build_s", "cycles_per_s", "worker", "pid", "scheduler")

#: the one time limit (seconds) of checking a scheduler named by address: reaching it, seeing that
#: what answers speaks Dask's protocol (:func:`check_scheduler`), and the Dask client's connection
SCHEDULER_CHECK_S = 20.0

#: the folders whose files make up the design, the golden model and the benches
_CODE_TREES = ("golden_model", "hdl", "sim", "cocotb_tests")
_CODE_SUFFIXES = (".py", ".v", ".sv", ".vh", ".cpp", ".h", ".mk")
#: environment variables that reach a compiler or change a run's code path
_ENV_KEYS = ("CC", "CXX", "CFLAGS", "CXXFLAGS", "LDFLAGS", "RASTERHW_REFERENCE", "RASTERHW_VL_RUNTIME")


# ====================================================================== what a task is
@dataclass(frozen=True)
class Task:
    """One independent run (see the module docstring). ``params`` are typed values (int, float,
    str, bool), in the order the caller gives them."""

    kind: str                                           # "sim" | "render" | "call"
    name: str                                           # sim block, arch, or "module:function"
    params: tuple[tuple[str, object], ...] = ()
    scene: str | None = None
    size: tuple[int, int] | None = None
    engine: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("sim", "render", "call"):
            raise RasterhwError(f"task kind must be sim, render or call, not {self.kind!r}")
        if isinstance(self.params, Mapping):
            object.__setattr__(self, "params", tuple(self.params.items()))

    def to_dict(self) -> dict:
        return {"kind": self.kind, "name": self.name, "params": dict(self.params), "scene": self.scene,
                "size": list(self.size) if self.size else None, "engine": self.engine}

    def label(self) -> str:
        p = " ".join(f"{k}={v}" for k, v in self.params)
        return " ".join(s for s in (self.kind, self.name, p, self.scene or "",
                                    "x".join(map(str, self.size)) if self.size else "", self.engine or "") if s)

    def digest(self) -> str:
        """The store key: this task, the package's code and the tools (sha256, hex)."""
        blob = json.dumps({"task": self.to_dict(), "code": code_digest(), "tools": tool_versions()},
                          sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()


@functools.cache
def code_digest() -> str:
    """Digest of every source file of the design, golden model, simulators and benches (once per
    process): any edit to them gives every task a new store key."""
    h = hashlib.sha256()
    for top in _CODE_TREES:
        for f in sorted((REPO_ROOT / top).rglob("*")):
            if f.suffix in _CODE_SUFFIXES and "__pycache__" not in f.parts and f.is_file():
                h.update(str(f.relative_to(REPO_ROOT)).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


@functools.cache
def tool_versions() -> dict:
    """Versions of what a run's result can depend on besides our code: Python, the libraries,
    Verilator, the C++ compiler (its ``--version`` line) and the compiler flags of the environment."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": sys.version.split()[0]}
    for pkg in ("numpy", "amaranth", "verilator", "cocotb", "numba"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = None
    cxx = os.environ.get("CXX", "c++")
    try:
        r = subprocess.run([cxx, "--version"], capture_output=True, text=True, timeout=20)
        out["cxx"] = (r.stdout.splitlines() or [""])[0]
    except (OSError, subprocess.SubprocessError):
        out["cxx"] = None
    out["env"] = {k: os.environ[k] for k in _ENV_KEYS if k in os.environ}
    return out


# ====================================================================== running one task
def _jsonable(v):
    """numpy scalars / small arrays / tuples / paths -> plain JSON values (None if not one)."""
    import numpy as np

    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist()) if v.size <= 4096 else None
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    if isinstance(v, Path):
        return str(v)
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return str(v)


def _frame_digest(frame) -> str:
    import numpy as np

    a = np.ascontiguousarray(frame)
    return hashlib.sha256(str(a.shape).encode() + a.tobytes()).hexdigest()[:16]


def _is_timing(key: str) -> bool:
    """Seconds the run took (``sim_s``, ``run_s``): folded into ``wall_s``, kept out of results
    so that two runs of one task differ only in :data:`VARYING` (``*_per_s`` rates are kept)."""
    return key.endswith("_s") and not key.endswith("_per_s") and key not in VARYING


def _scene(scene: str, size: tuple[int, int] | None):
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.scenes import SCENES

    if size is None:
        info = SCENES.get(scene)
        size = (info.default_width, info.default_height) if info is not None else (512, 512)
    return load_scene(scene), (int(size[0]), int(size[1]))


def _defaults(options, params: dict, who: str) -> dict:
    names = {o.name for o in options}
    for k in params:
        if k not in names:
            raise RasterhwError(f"{who} takes no parameter {k!r}; it takes: {', '.join(sorted(names)) or 'none'}")
    return {o.name: params.get(o.name, o.default) for o in options}


def _run_sim(task: Task) -> dict:
    blocks = registry.sim_blocks()
    if task.name not in blocks:
        raise RasterhwError(f"unknown sim block {task.name!r}; blocks: {', '.join(blocks)}")
    _m, b = blocks[task.name]
    opts = _defaults(b.options, dict(task.params), f"sim {task.name}")
    sc, (w, h) = _scene(task.scene or b.default_scene, task.size)
    res = registry.load(b.simulate)(sc, w, h, engine=task.engine or "verilator", progress=False, **opts)
    frame = res.pop("frame_rgb", None)
    out = {"block": task.name, "scene": sc.name, "width": w, "height": h, **opts, **res}
    if frame is not None:
        out["frame_digest"] = _frame_digest(frame)
    cycles = out.get("cycles")
    if isinstance(cycles, (int, float)) and not isinstance(cycles, bool):
        out["cycles_per_pixel"] = cycles / (w * h)
        if sc.n_polygons:
            out["cycles_per_polygon"] = cycles / sc.n_polygons
    return out


def _run_render(task: Task) -> dict:
    archs = registry.archs()
    if task.name not in archs:
        raise RasterhwError(f"unknown arch {task.name!r}; archs: {', '.join(archs)}")
    if task.engine is not None:
        raise RasterhwError(f"render:{task.name} is a golden model: it takes no engine")
    _m, a = archs[task.name]
    opts = _defaults(a.options, dict(task.params), f"render:{task.name}")
    sc, (w, h) = _scene(task.scene or "c300", task.size)
    res = registry.load(a.render)(sc, w, h, arch=task.name, **opts)
    return {"arch": task.name, "scene": sc.name, "width": w, "height": h, **opts,
            "polygons_in": int(res.tris.stats.get("polygons_in", sc.n_polygons)),
            "polygons_drawn": int(res.tris.stats.get("polygons_drawn", 0)),
            "triangles": int(res.tris.n_triangles), "pixels_written": int(res.pixels_written),
            **res.stats, "frame_digest": _frame_digest(res.rgb8)}


def _worker_address() -> str:
    if "distributed" not in sys.modules:
        return "in-process"
    from distributed import get_worker

    try:
        return get_worker().address
    except ValueError:   # not inside a Dask task
        return "in-process"


def run_task(task: Task, code: str | None = None) -> dict:
    """Run one task here and return its result (see the module docstring). ``code``: the
    submitter's :func:`code_digest`; a worker whose checkout differs refuses the task."""
    if code is not None and code != code_digest():
        raise RasterhwError(f"worker {_worker_address()} runs another version of the code than the "
                            f"submitter ({REPO_ROOT}); every worker needs the same checkout (docs/scale.md)")
    t0 = time.perf_counter()
    if task.kind == "sim":
        res = _run_sim(task)
    elif task.kind == "render":
        res = _run_render(task)
    else:
        res = registry.load(task.name)(**dict(task.params))
    res = {k: _jsonable(v) for k, v in res.items() if not _is_timing(k)}
    res["wall_s"] = round(time.perf_counter() - t0, 6)
    res["worker"] = _worker_address()
    res["pid"] = os.getpid()
    return res


def task_modules(tasks: Iterable[Task]) -> list[str]:
    """The modules ``tasks`` run (a sim block's driver, a golden arch's renderer, a call's own), for
    a fork server to import once instead of every worker at its first task."""
    refs = set()
    for t in tasks:
        if t.kind == "call":
            refs.add(t.name)
        elif t.kind == "sim" and t.name in registry.sim_blocks():
            refs.add(registry.sim_blocks()[t.name][1].simulate)
        elif t.kind == "render" and t.name in registry.archs():
            refs.add(registry.archs()[t.name][1].render)
    return sorted({r.split(":", 1)[0] for r in refs if isinstance(r, str) and ":" in r})


def batch_size(n: int, workers: int) -> int:
    """Tasks per Dask task when ``n`` tasks go to ``workers`` workers: a quarter of each worker's
    share (at least 1), so that every worker gets several batches and a slow one does not leave
    the others idle; up to ``4 * workers`` tasks, one each."""
    return max(1, n // (4 * max(1, workers)))


def run_batch(tasks: Sequence[Task], code: str | None = None) -> list[tuple[bool, object]]:
    """Run ``tasks`` here one after another (a batch :meth:`Runner.map` gives one worker):
    ``(True, result)`` per task, up to the first that fails, whose entry is ``(False, its error)``."""
    out: list[tuple[bool, object]] = []
    for t in tasks:
        try:
            out.append((True, run_task(t, code)))
        except Exception as e:  # noqa: BLE001 - given back to the caller, raised there
            out.append((False, e))
            break
    return out


# ====================================================================== schedulers
def parse_scheduler(text: str) -> tuple[str, object]:
    """``serial`` -> ("serial", None); ``local`` / ``local:N`` -> ("local", N or None);
    ``tcp://HOST:PORT`` (any Dask address) -> ("address", text). Anything else: a one-line error."""
    text = (text or "").strip()
    if text == "serial":
        return "serial", None
    m = re.fullmatch(r"local(?::([0-9]{1,4}))?", text)
    if m:
        n = int(m.group(1)) if m.group(1) else None
        if n is not None and not 1 <= n <= 1024:
            raise RasterhwError(f"--scheduler local:N needs 1 <= N <= 1024, not {n}")
        return "local", n
    if re.fullmatch(r"(tcp|tls|ws|wss|inproc|ucx)://[\w.\-\[\]:/]+", text):
        return "address", text
    raise RasterhwError(f"--scheduler must be serial, local, local:N or a Dask address such as "
                        f"tcp://127.0.0.1:8786, not {text!r}")


def _describe(reply: bytes) -> str:
    """What sent ``reply`` (the first bytes a server sent), in a few words for an error line."""
    if reply.startswith(b"HTTP/"):
        first = reply.split(b"\r\n", 1)[0].decode("ascii", "replace")
        server = re.search(rb"\r\nServer: *([^\r\n]{1,60})", reply, re.I)
        # the dashboard sends "/" to "status" (Tornado's 302), its pages name Bokeh and Dask
        dash = (re.search(rb"\r\nLocation: *\S*status", reply, re.I) is not None
                or b"bokeh" in reply.lower() or b"dask" in reply.lower())
        return (f"an HTTP server ({first}{'; ' + server.group(1).decode('ascii', 'replace') if server else ''})"
                + (": a Dask dashboard? The scheduler's own port is usually 8786" if dash else ""))
    return f"a server that does not speak Dask's protocol (it sent {reply[:24]!r})"


def _dask_handshake(head: bytes) -> bool:
    """Do ``head`` (the first bytes a server sent) start a Dask TCP message (``distributed.comm.tcp``:
    a 64-bit length of the frame header, then the number of frames and each frame's length)?"""
    import struct

    if len(head) < 16:
        return False
    total, nframes = struct.unpack_from("<QQ", head)
    return 16 <= total <= 1 << 24 and 1 <= nframes <= 64 and 8 + 8 * nframes <= total


def _receive(sock, upto: int, timeout: float) -> bytes:
    """What ``sock`` sends within ``timeout`` seconds, until ``upto`` bytes or it closes (a time-out
    with nothing is ``b""``; another error is raised)."""
    out = b""
    sock.settimeout(timeout)
    try:
        while len(out) < upto:
            got = sock.recv(4096)
            if not got:
                break
            out += got
    except TimeoutError:
        pass
    return out


#: addresses :func:`check_scheduler` found a Dask scheduler at (in this process)
_CHECKED: set[str] = set()


def check_scheduler(text: str, *, limit_s: float = SCHEDULER_CHECK_S) -> tuple[str, object]:
    """:func:`parse_scheduler`, and for a ``tcp://HOST:PORT`` address, a look at what answers there
    before any work: a TCP connection and the first bytes the server sends (a Dask scheduler sends its
    handshake at once). Nothing listening, an HTTP server (the dashboard's port typed for the
    scheduler's), a server that sends other bytes or nothing: one :class:`RasterhwError` line naming
    the address and what answered, within ``limit_s`` seconds. Other schemes (``tls://``, ...) are
    left to the Dask client (:class:`Runner`), under the same limit."""
    import socket

    kind, arg = parse_scheduler(text)
    if kind != "address" or not str(arg).startswith("tcp://") or arg in _CHECKED:
        return kind, arg
    m = re.fullmatch(r"tcp://(\[[^\]]+\]|[^:/]+)(?::([0-9]{1,5}))?/?", str(arg))
    if m is None or (m.group(2) is not None and not 0 < int(m.group(2)) < 65536):
        raise RasterhwError(f"--scheduler {arg}: not a tcp://HOST:PORT address")
    host, port = m.group(1).strip("[]"), int(m.group(2) or 8786)
    deadline = time.monotonic() + limit_s

    def left() -> float:
        return max(0.1, deadline - time.monotonic())

    try:
        sock = socket.create_connection((host, port), timeout=min(left(), limit_s / 2))
    except TimeoutError:
        raise RasterhwError(f"cannot reach the Dask scheduler at {arg}: no answer in {limit_s / 2:.0f} s") from None
    except OSError as e:
        raise RasterhwError(f"cannot reach the Dask scheduler at {arg}: {e.strerror or e}") from None
    reply = b""
    with sock:
        try:
            reply = _receive(sock, 16, min(left(), 2.0))   # a Dask scheduler sends its handshake at once
        except OSError as e:
            raise RasterhwError(f"the Dask scheduler at {arg} closed the connection ({e.strerror or e})") from None
        if not reply:   # silent: ask it as a web server would, to say what it is
            try:
                sock.settimeout(min(left(), 3.0))
                sock.sendall(f"GET / HTTP/1.0\r\nHost: {host}\r\n\r\n".encode())
                reply = _receive(sock, 512, min(left(), 3.0))
            except OSError:
                pass
    if _dask_handshake(reply):
        _CHECKED.add(arg)
        return kind, arg
    what = _describe(reply) if reply else (f"a server that accepted the connection and sent nothing in "
                                           f"{limit_s - left():.0f} s (not a Dask scheduler)")
    raise RasterhwError(f"--scheduler {arg} is not a Dask scheduler: {what}")


def scheduler_from_file(path: str | Path) -> str:
    """The address in a Dask scheduler file (``dask scheduler --scheduler-file FILE`` writes
    ``{"address": "tcp://...", ...}``); a file that is missing or holds none is a one-line error."""
    try:
        info = json.loads(Path(path).read_text())
    except OSError as e:
        raise RasterhwError(f"--scheduler-file {path}: {e.strerror or e}") from None
    except ValueError:
        raise RasterhwError(f"--scheduler-file {path}: not a Dask scheduler file (not JSON)") from None
    addr = info.get("address") if isinstance(info, dict) else None
    if not isinstance(addr, str) or not addr:
        raise RasterhwError(f"--scheduler-file {path}: no scheduler address in it (a Dask scheduler file has one)")
    parse_scheduler(addr)
    return addr


# ---------------------------------------------------------------------- local clusters, one per size
#: local clusters this process started, by worker count: (cluster, client); reused by every Runner
_CLUSTERS: dict[int, tuple[object, object]] = {}
#: what the fork server imports once, before it forks each worker
_PRELOAD = ("distributed", "numpy", "rasterhw.sim.flow.tasks", "rasterhw.sim.registry")


#: Dask's periodic work in a local cluster, made rarer: an idle cluster of two workers took 2.5
#: CPU-seconds per 30 s here (0.84 in this process per 20 s, 0.3 per worker), taken from the
#: simulations on a 2-core machine, and more the longer the command runs; and no statistical
#: profiler (sampling a task's stack every 10 ms: the pysim points' deep Python stacks)
_QUIET = {"distributed.worker.profile.enabled": False,
          "distributed.admin.tick.interval": "1s",             # event-loop health checks (default 20 ms)
          "distributed.admin.system-monitor.interval": "2s",   # the dashboard's CPU/memory graphs (500 ms)
          "distributed.admin.system-monitor.disk": False,
          "distributed.worker.memory.monitor-interval": "1s",  # memory limits (none set here; 100 ms)
          }


def _forkserver(extra: Iterable[str] = ()) -> contextlib.AbstractContextManager:
    """Dask's configuration under which a cluster's workers are forked from a fork server that
    imported :data:`_PRELOAD` (see the module docstring); unchanged where there is no fork server."""
    import multiprocessing

    import dask

    if "forkserver" not in multiprocessing.get_all_start_methods():   # pragma: no cover - not Linux/macOS
        return contextlib.nullcontext()
    cfg = dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"})
    from distributed.utils import get_mp_context

    # (takes effect when this process's fork server starts: its first cluster)
    get_mp_context().set_forkserver_preload(list(dict.fromkeys([*_PRELOAD, *extra])))
    return cfg


def _dashboard() -> bool:
    try:
        import bokeh  # noqa: F401 - Dask's dashboard needs it (rasterhw[dashboard])
    except ImportError:
        return False
    return True


#: inside :func:`one_cluster` (a command of the CLI): Runners share one local cluster per size
_SHARE = False


@contextlib.contextmanager
def one_cluster():
    """``with one_cluster():`` every :class:`Runner` with ``local[:N]`` inside uses one cluster of
    that size, its workers forked from a fork server that imported the models' code once, closed
    at the end (the CLI wraps every command in it). Outside it a Runner starts and stops a cluster
    of its own, its workers started by ``spawn`` with the environment of that moment."""
    global _SHARE
    outer, _SHARE = _SHARE, True
    try:
        yield
    finally:
        _SHARE = outer
        if not outer:
            close_clusters()


def _start_local(n: int, *, fork: bool, preload: Iterable[str] = ()):
    import logging

    import dask
    from distributed import Client, LocalCluster

    dash = "127.0.0.1:0" if _dashboard() else None
    with _forkserver(preload) if fork else contextlib.nullcontext(), dask.config.set(_QUIET):
        # a task's error reaches the caller through its result (one line); the workers' own error
        # logs (a failed task's traceback, a closed connection when the command is interrupted) are
        # not printed. The scheduler's HTTP server (health routes; the dashboard with bokeh) on a
        # free loopback port, never 8787 ("Port 8787 is already in use" when another has it)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=dash,
                               silence_logs=logging.CRITICAL,
                               scheduler_kwargs={"dashboard_address": dash or "127.0.0.1:0"})
    client = Client(cluster)
    if dash is not None and cluster.dashboard_link:
        print(f"dask dashboard: {cluster.dashboard_link}", file=sys.stderr, flush=True)
    return cluster, client


def local_client(n: int, preload: Iterable[str] = ()):
    """The client of the shared local cluster of ``n`` workers (:func:`one_cluster`), started if
    there is none (or it stopped); the dashboard's address on stderr when there is one. ``preload``:
    modules the fork server imports too (the tasks' own: :func:`task_modules`) when it starts."""
    got = _CLUSTERS.get(n)
    if got is not None and got[1].status == "running":
        return got[1]
    _CLUSTERS[n] = _start_local(n, fork=True, preload=preload)
    return _CLUSTERS[n][1]


def close_clusters() -> None:
    """Close every local cluster this process started (the CLI calls it when a command ends)."""
    for n in list(_CLUSTERS):
        cluster, client = _CLUSTERS.pop(n)
        with contextlib.suppress(Exception):
            client.close(timeout=5)
        with contextlib.suppress(Exception):
            cluster.close(timeout=5)


def default_store() -> Path:
    """Where finished results are kept unless ``--store`` says otherwise."""
    return BUILD_ROOT / "tasks"


def _cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


@dataclass
class Handle:
    """One submitted task: its place in the caller's order, and where its result will be."""

    task: Task
    digest: str
    result: dict | None = None          # known (from the store, or finished serially)
    future: object = None               # a distributed.Future (of this task, or of its batch)
    index: int | None = None            # its place in the batch its future runs (None: a task of its own)
    stored: bool = False                # came from the store
    saved: bool = False                 # its fresh result is in the store (or there is no store)


class Runner:
    """Run tasks on one scheduler (``with Runner("local:2", store=...) as run: run.map(tasks)``)."""

    def __init__(self, scheduler: str = "local", *, store: str | Path | None = None, fresh: bool = False,
                 preload: Iterable[str] = (),
                 progress: bool = False):
        self.kind, self.arg = parse_scheduler(scheduler)
        self.scheduler = scheduler
        self.store = Path(store) if store is not None else None
        self.fresh = fresh
        self.progress = progress
        self.preload = tuple(preload)   # modules the workers' fork server imports once (task_modules)
        self.client = self.cluster = self._watch = None
        self._shared = False        # the client is this process's local cluster's (close_clusters)
        self.computed = 0           # tasks run (not found in the store)
        self.reused = 0             # tasks whose result came from the store
        self._lock = threading.Lock()
        # each future's value, gathered once: Future.result() gathers again on every call, and a
        # task the scheduler ran twice (a worker lost under load) would store one result and return
        # another (a fresh-clone CI run once stored wall_s 3.9e-05 and returned 4e-06)
        self._gathered: dict[str, object] = {}
        self._gather_lock = threading.Lock()

    # ------------------------------------------------------------------ cluster
    def __enter__(self) -> Runner:
        if self.kind == "serial":
            return self
        from distributed import Client

        if self.kind == "local":
            from rasterhw.sim.workdirs import OrphanWatch

            # a worker killed mid-build leaves its compiler to this process (a subreaper): ended here
            self._watch = OrphanWatch().__enter__()
            n = self.arg or _cores()
            if _SHARE:   # the command's one cluster of this size
                self.client, self._shared = local_client(n, self.preload), True
            else:
                self.cluster, self.client = _start_local(n, fork=False)
        else:
            t0 = time.monotonic()
            check_scheduler(self.scheduler)   # (at once if the command did it first) and the client: one limit
            left = max(1.0, SCHEDULER_CHECK_S - (time.monotonic() - t0))
            try:
                self.client = Client(self.arg, timeout=f"{left:.0f}s")
            except (OSError, TimeoutError) as e:
                raise RasterhwError(f"cannot reach the Dask scheduler at {self.arg}: {e}") from None
            except Exception as e:  # noqa: BLE001 - a reply that is not Dask's: one line, never a traceback
                raise RasterhwError(f"--scheduler {self.arg} did not answer as a Dask scheduler "
                                    f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})") from None
        return self

    def __exit__(self, *exc) -> None:
        if self.client is not None and not self._shared:
            self.client.close()
        elif self.client is not None and exc and exc[0] is not None:
            # a command that failed or was interrupted: its shared cluster goes now, with any task
            # still running on it, not when the process ends
            close_clusters()
        if self.cluster is not None:
            self.cluster.close()
        if self._watch is not None:
            self._watch.__exit__()
        self.client = self.cluster = self._watch = None
        self._shared = False

    @property
    def nworkers(self) -> int:
        """Worker threads the scheduler has now (1 for ``serial``)."""
        if self.client is None:
            return 1
        info = self.client.scheduler_info()
        return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))

    def address(self) -> str:
        """The scheduler's address (``serial`` for in-process runs)."""
        return "serial" if self.client is None else self.client.scheduler.address

    # ------------------------------------------------------------------ store
    def _path(self, digest: str) -> Path:
        return self.store / digest[:2] / f"{digest}.json"

    def _load(self, digest: str) -> dict | None:
        if self.store is None or self.fresh:
            return None
        path = self._path(digest)
        try:
            got = json.loads(path.read_text())["result"]
        except (OSError, ValueError, KeyError):
            return None
        with contextlib.suppress(OSError):
            os.utime(path)   # its last use (rasterhw cache clean removes the least recently used first)
        return got

    def _save(self, h: Handle, result: dict) -> None:
        if self.store is None:
            return
        p = self._path(h.digest)
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=".tmp-", suffix=".json")
        with os.fdopen(fd, "w") as fh:
            json.dump({"task": h.task.to_dict(), "code": code_digest(), "tools": tool_versions(),
                       "result": result}, fh)
        os.replace(tmp, p)

    # ------------------------------------------------------------------ tasks
    def submit(self, task: Task, *, start: bool = True) -> Handle:
        """Start ``task`` (serial: when its result is asked for); a stored result is used as it is.
        ``start=False``: only look in the store (:meth:`map` starts the rest in batches)."""
        h = Handle(task, task.digest())
        got = self._load(h.digest)
        if got is not None:
            h.result, h.stored = got, True
            with self._lock:
                self.reused += 1
            return h
        if self.client is not None and start:
            h.future = self.client.submit(run_task, task, code_digest(), pure=False,
                                          key=f"{task.kind}-{h.digest[:16]}-{os.urandom(4).hex()}")
            h.future.add_done_callback(functools.partial(self._finished, [h]))
        return h

    def _start_batches(self, handles: list[Handle]) -> None:
        """Start ``handles``' tasks on the cluster: one Dask task each when there are few, else in
        batches of about a quarter of the tasks per worker each (scheduling a task costs the same
        whatever it does: a point of a few milliseconds pays it once per batch)."""
        size = batch_size(len(handles), self.nworkers)
        for i in range(0, len(handles), size):
            part = handles[i:i + size]
            if size == 1:
                fut = self.client.submit(run_task, part[0].task, code_digest(), pure=False,
                                         key=f"{part[0].task.kind}-{part[0].digest[:16]}-{os.urandom(4).hex()}")
            else:
                fut = self.client.submit(run_batch, [h.task for h in part], code_digest(), pure=False,
                                         key=f"batch-{part[0].digest[:16]}-{len(part)}-{os.urandom(4).hex()}")
            for k, h in enumerate(part):
                h.future, h.index = fut, (k if size > 1 else None)
            fut.add_done_callback(functools.partial(self._finished, part))

    def _finished(self, handles: list[Handle], fut) -> None:
        """Store results as soon as they arrive (a Dask callback thread)."""
        if fut.status != "finished":
            return
        for h in handles:
            try:
                res = self._value(h)
            except Exception:  # noqa: BLE001 - the caller sees the error through result()
                continue
            self._keep(h, res)

    def _gather(self, fut) -> object:
        """``fut``'s value, fetched once per future (the store and the caller see one object)."""
        with self._gather_lock:
            if fut.key not in self._gathered:
                self._gathered[fut.key] = fut.result()
            return self._gathered[fut.key]

    def _value(self, h: Handle) -> dict:
        """The result of ``h``'s future (its own, or its place in its batch's); its error raised."""
        got = self._gather(h.future)
        if h.index is None:
            return got
        if h.index >= len(got):
            raise RasterhwError(f"{h.task.label()}: not run (an earlier task of its batch failed)")
        ok, val = got[h.index]
        if not ok:
            raise val
        return val

    def _keep(self, h: Handle, res: dict) -> None:
        """Store a fresh result, once per handle, and count it. The store write is under the lock:
        a caller whose result a Dask callback thread is storing waits until the file is there (a
        fresh-clone CI run's second Runner once found 39 of 40 results, the 40th still being
        written by the first Runner's callback after its map had returned)."""
        with self._lock:
            if h.saved:
                return
            h.saved = True
            self.computed += 1
            self._save(h, res)

    def result(self, h: Handle) -> dict:
        """The task's result (waits; a task's error is raised here)."""
        if h.result is None:
            if h.future is None:                       # serial
                h.result = run_task(h.task)
            else:
                h.result = self._value(h)
            self._keep(h, h.result)
        return h.result

    def done(self, h: Handle) -> bool:
        return h.result is not None or (h.future is not None and h.future.done())

    def cancel(self, h: Handle) -> None:
        """Give up a task whose result is no longer wanted."""
        if h.future is not None and h.result is None:
            h.future.cancel()

    def map(self, tasks: Iterable[Task], progress: Callable[[int, Handle], None] | None = None) -> list[dict]:
        """Every task's result, in task order; ``progress(i, handle)`` after each one finishes
        (in the order they finish)."""
        handles = [self.submit(t, start=False) for t in tasks]
        try:
            if self.client is None:
                for i, h in enumerate(handles):
                    self.result(h)
                    if progress:
                        progress(i, h)
            else:
                from distributed import as_completed

                todo = [h for h in handles if h.result is None]
                if todo:
                    self._start_batches(todo)
                index: dict[str, list[int]] = {}
                for i, h in enumerate(handles):
                    if h.future is not None:
                        index.setdefault(h.future.key, []).append(i)
                    elif progress:
                        progress(i, h)
                futures = list({h.future.key: h.future for h in todo}.values())
                for fut in as_completed(futures):
                    for i in index[fut.key]:
                        self.result(handles[i])
                        if progress:
                            progress(i, handles[i])
            return [self.result(h) for h in handles]
        except BaseException:
            for h in handles:
                self.cancel(h)
            raise


# ====================================================================== many calls, one line
def call(fn: str, **params) -> Task:
    """A call task: ``fn`` (``"module:function"``) with these keyword arguments (typed values)."""
    return Task("call", fn, params)


def run_tasks(tasks: Sequence[Task], *, scheduler: str = "serial", store: str | Path | None = None,
              fresh: bool = False, progress: bool = False, desc: str = "tasks") -> list[dict]:
    """Every task's result, in task order, run on ``scheduler`` (a :class:`Runner` started and
    stopped here; ``serial``, the default, starts nothing): what a command that runs a list of
    independent runs (a report's sweeps, ``synth --all``, the demo's HDL runs) hands its list to.
    ``store``: keep and reuse finished results there (``None``: keep nothing); ``fresh``: run
    everything again. ``progress``: a bar over the tasks on stderr (on a terminal), named ``desc``.
    A task's error is raised here (the tasks not yet finished are cancelled)."""
    from tqdm import tqdm

    tasks = list(tasks)
    if not tasks:
        return []
    bar = tqdm(total=len(tasks), desc=desc, unit="run", disable=None if progress else True, leave=False,
               file=sys.stderr)
    try:
        with Runner(scheduler, store=store, fresh=fresh, preload=task_modules(tasks)) as run:
            return run.map(tasks, progress=lambda _i, _h: bar.update(1))
    finally:
        bar.close()
