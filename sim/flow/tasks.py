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
  one per core), one thread each (the simulators are single-threaded and the models hold the GIL),
  no dashboard; started on entry and stopped on exit;
* ``tcp://HOST:PORT`` — an existing Dask scheduler (``dask scheduler`` + ``dask worker``, SLURM via
  dask-jobqueue, SSH hosts: ``docs/scale.md``).

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

__all__ = ["VARYING", "Handle", "Runner", "Task", "call", "check_scheduler", "code_digest", "default_store",
           "parse_scheduler",
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
    future: object = None               # a distributed.Future
    stored: bool = False                # came from the store
    saved: bool = False                 # its fresh result is in the store (or there is no store)


class Runner:
    """Run tasks on one scheduler (``with Runner("local:2", store=...) as run: run.map(tasks)``)."""

    def __init__(self, scheduler: str = "local", *, store: str | Path | None = None, fresh: bool = False,
                 progress: bool = False):
        self.kind, self.arg = parse_scheduler(scheduler)
        self.scheduler = scheduler
        self.store = Path(store) if store is not None else None
        self.fresh = fresh
        self.progress = progress
        self.client = self.cluster = self._watch = None
        self.computed = 0           # tasks run (not found in the store)
        self.reused = 0             # tasks whose result came from the store
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ cluster
    def __enter__(self) -> Runner:
        if self.kind == "serial":
            return self
        import logging

        from distributed import Client, LocalCluster

        if self.kind == "local":
            from rasterhw.sim.workdirs import OrphanWatch

            # a worker killed mid-build leaves its compiler to this process (a subreaper): ended here
            self._watch = OrphanWatch().__enter__()
            n = self.arg or _cores()
            self.cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                        dashboard_address=None, silence_logs=logging.CRITICAL,
                                        # a task's error reaches the caller through its result (one
                                        # line); the workers' own error logs (a failed task's traceback,
                                        # a closed connection when the command is interrupted) are not
                                        # printed. No dashboard; the scheduler's own small HTTP server (health
                                        # routes) on a free loopback port, not 8787 ("Port 8787 is
                                        # already in use" on stderr when another cluster has it)
                                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
            self.client = Client(self.cluster)
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
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        if self._watch is not None:
            self._watch.__exit__()
        self.client = self.cluster = self._watch = None

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
    def submit(self, task: Task) -> Handle:
        """Start ``task`` (serial: when its result is asked for); a stored result is used as it is."""
        h = Handle(task, task.digest())
        got = self._load(h.digest)
        if got is not None:
            h.result, h.stored = got, True
            with self._lock:
                self.reused += 1
            return h
        if self.client is not None:
            h.future = self.client.submit(run_task, task, code_digest(), pure=False,
                                          key=f"{task.kind}-{h.digest[:16]}-{os.urandom(4).hex()}")
            h.future.add_done_callback(functools.partial(self._finished, h))
        return h

    def _finished(self, h: Handle, fut) -> None:
        """Store a result as soon as it arrives (a Dask callback thread)."""
        if fut.status != "finished":
            return
        try:
            res = fut.result()
        except Exception:  # noqa: BLE001 - the caller sees the error through result()
            return
        self._keep(h, res)

    def _keep(self, h: Handle, res: dict) -> None:
        """Store a fresh result, once per handle, and count it."""
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
                h.result = h.future.result()
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
        handles = [self.submit(t) for t in tasks]
        try:
            if self.client is None:
                for i, h in enumerate(handles):
                    self.result(h)
                    if progress:
                        progress(i, h)
            else:
                from distributed import as_completed

                index = {h.future.key: i for i, h in enumerate(handles) if h.future is not None}
                for i, h in enumerate(handles):
                    if h.future is None and progress:
                        progress(i, h)
                for fut in as_completed([h.future for h in handles if h.future is not None]):
                    i = index[fut.key]
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
        with Runner(scheduler, store=store, fresh=fresh) as run:
            return run.map(tasks, progress=lambda _i, _h: bar.update(1))
    finally:
        bar.close()
