"""Build folders, run folders and simulator children that never outlive their run.

* :func:`build_lock` — one build at a time per build folder, across processes (the ``filelock``
  library on ``build/<name>.lock``: ``flock`` on POSIX, ``msvcrt`` locking on Windows, so the
  command line imports everywhere): two cold runs of the same design wait for each other instead
  of compiling into one folder and one ``build.log``;
* :func:`run_folder` — a fresh ``run-*`` folder for one run's stimulus and dumps, removed when
  the run ends however it ends (``with``), or, for code that only asks for a path, by
  :func:`cleanup` (the CLI calls it in ``finally``; ``atexit`` too). ``RASTERHW_KEEP=1`` keeps
  them for debugging; :func:`keep` keeps one a caller asked to keep (and the runner keeps the
  folder of a simulation whose checks failed: its error names the logs there);
* :func:`run_child` — ``subprocess.run`` whose child is killed with the parent: by the kernel
  if the parent dies (``PR_SET_PDEATHSIG``), and, with its whole process tree (make, the
  compiler, SymbiYosys's solvers in process groups of their own: :func:`end_tree`, psutil), if
  the parent is interrupted or fails while waiting;
* the one mechanism that no external tool outlives its command: the CLI makes itself a
  subreaper (:func:`become_subreaper`: what a killed parent leaves comes to it, not to PID 1),
  ends what it inherits while a local Dask cluster runs (:class:`OrphanWatch`: a worker killed
  mid-build) and, last, everything below it (:func:`end_descendants`); builds work in
  work folders (:func:`work_folder`) named by host and process, removed once their process is gone
  (:func:`remove_dead_work_folders`).
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

__all__ = ["OrphanWatch", "become_subreaper", "build_lock", "cleanup", "end_descendants", "end_orphans", "end_tree",
           "host_tag", "keep", "remove_dead_work_folders", "run_child", "run_folder", "temp_run_folder", "work_folder"]

_live: set[Path] = set()
_held: set[str] = set()
#: any of these set to 1 keeps run folders (the drivers' older per-machine names included)
_KEEP_VARS = ("RASTERHW_KEEP", "ZBM_KEEP", "PIXELBUS_KEEP")


@contextlib.contextmanager
def build_lock(bdir: str | Path, *, what: str = "") -> Iterator[None]:
    """Hold an exclusive lock on ``bdir`` (a build folder) across processes; re-entrant
    within a process (a nested lock on the same folder does not deadlock)."""
    bdir = Path(bdir)
    key = str(bdir.resolve())
    if key in _held:
        yield
        return
    # imported here: a warm run takes no lock (importing filelock: ~0.03 CPU-s)
    from filelock import FileLock, Timeout

    bdir.parent.mkdir(parents=True, exist_ok=True)
    lock = FileLock(bdir.parent / f"{bdir.name}.lock")
    try:
        lock.acquire(timeout=0)       # try first: a message only when we have to wait
    except Timeout:
        print(f"waiting for another build of {what or bdir.name} to finish", file=sys.stderr)
        lock.acquire()
    try:
        _held.add(key)
        yield
    finally:
        _held.discard(key)
        lock.release()



def temp_run_folder(parent: str | Path, prefix: str = "run-") -> Path:
    """A new folder ``parent/PREFIX-HOST-PID-*`` for one run, removed by :func:`cleanup` (or
    :func:`release`); the host and process in its name tell ``rasterhw cache clean`` that the
    build folder holding it is in use while that process runs (``sim/cacheinfo.py``)."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    d = Path(tempfile.mkdtemp(prefix=f"{prefix}{_HOST}-{os.getpid()}-", dir=parent))
    _live.add(d)
    return d


@contextlib.contextmanager
def run_folder(parent: str | Path, prefix: str = "run-") -> Iterator[Path]:
    """``with run_folder(bdir) as d:`` — a fresh run folder, removed at the end of the block."""
    d = temp_run_folder(parent, prefix)
    try:
        yield d
    finally:
        release(d)


def keep(d: str | Path | None) -> None:
    """Do not remove ``d`` (a caller asked for the run's files)."""
    if d is not None:
        _live.discard(Path(d))


def release(d: str | Path | None) -> None:
    """Remove run folder ``d`` now (unless ``RASTERHW_KEEP=1``)."""
    if d is None:
        return
    d = Path(d)
    _live.discard(d)
    if not any(os.environ.get(k) == "1" for k in _KEEP_VARS):
        shutil.rmtree(d, ignore_errors=True)


def cleanup() -> None:
    """Remove every run folder of this process still alive (interrupted or failed runs)."""
    for d in list(_live):
        release(d)


atexit.register(cleanup)


# ---------------------------------------------------------------- process trees
#: pids :func:`run_child` started in this process and has not reaped yet (not orphans)
_started: set[int] = set()
_PR_SET_CHILD_SUBREAPER = 36


def _libc():
    try:
        return ctypes.CDLL(None, use_errno=True)
    except OSError:   # pragma: no cover - not Linux
        return None


def become_subreaper() -> bool:
    """Make this process the one that inherits every orphaned process below it (Linux
    ``PR_SET_CHILD_SUBREAPER``) instead of PID 1: a tool whose parent died (a Dask worker killed
    mid-build, SymbiYosys killed under its solvers) stays findable here, and :func:`end_orphans`
    and :func:`end_descendants` end it. The CLI calls it first thing; False where not supported."""
    lib = _libc() if sys.platform.startswith("linux") else None
    try:
        return bool(lib is not None and lib.prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)
    except AttributeError:   # pragma: no cover
        return False


def _is_subreaper() -> bool:
    lib = _libc() if sys.platform.startswith("linux") else None
    if lib is None:
        return False
    flag = ctypes.c_int(0)
    try:
        return lib.prctl(37, ctypes.byref(flag), 0, 0, 0) == 0 and bool(flag.value)   # PR_GET_CHILD_SUBREAPER
    except AttributeError:   # pragma: no cover
        return False


def end_tree(pids: Iterable[int], *, reap_roots: bool = False) -> int:
    """End the processes ``pids`` and every process descended from them, whatever process group or
    session they put themselves in (SymbiYosys starts each solver in a group of its own; make,
    the compiler and ``cc1plus`` sit under Verilator's make): every one found is stopped first
    (``SIGSTOP``: none can start another), the tree looked at again until nothing new appears, then
    all are killed (``SIGKILL``) and those that became this process's children reaped. The roots
    themselves are reaped only if ``reap_roots`` (a :class:`subprocess.Popen` reaps its own).
    Returns how many processes were ended (psutil)."""
    import psutil

    me = os.getpid()
    roots = set(pids) - {me}
    found: dict[int, psutil.Process] = {}
    frontier = []
    for pid in roots:
        with contextlib.suppress(psutil.Error):
            frontier.append(psutil.Process(pid))
    for _ in range(100):
        new = []
        for proc in frontier:
            try:
                family = [proc, *proc.children(recursive=True)]
            except psutil.Error:
                family = [proc]
            for q in family:
                if q.pid != me and q.pid not in found:
                    found[q.pid] = q
                    new.append(q)
                    with contextlib.suppress(psutil.Error):
                        q.suspend()
        if not new:
            break
        frontier = new
    for q in found.values():
        with contextlib.suppress(psutil.Error):
            q.kill()
    deadline = time.monotonic() + 5.0
    left = {pid for pid in found if pid not in roots or reap_roots}
    while left and time.monotonic() < deadline:
        for pid in list(left):
            try:
                done, _ = os.waitpid(pid, os.WNOHANG)   # ours (a subreaper's orphan): reap it
                if done:
                    left.discard(pid)
                    continue
            except ChildProcessError:
                pass
            try:
                if found[pid].status() == psutil.STATUS_ZOMBIE:   # someone else's to reap: it is dead
                    left.discard(pid)
            except psutil.Error:
                left.discard(pid)
        if left:
            time.sleep(0.02)
    return len(found)


def end_orphans() -> int:
    """End every process this (subreaper) process inherited: a child it did not start itself
    (:func:`run_child` or in its own process group, as ``subprocess`` and ``multiprocessing``
    children are), with its whole tree. Returns how many processes were ended."""
    import psutil

    try:
        kids = psutil.Process().children()
        mine = os.getpgrp()
        orphans = [k.pid for k in kids if k.pid not in _started and os.getpgid(k.pid) != mine]
    except (psutil.Error, OSError):
        return 0
    return end_tree(orphans, reap_roots=True) if orphans else 0


def end_descendants() -> int:
    """End every process below this one (its whole tree: children, their children, the orphans
    it inherited as a subreaper). The CLI calls it last, however a command ended."""
    if _child_pids() == []:   # nothing below us (the usual end): psutil not imported (~0.012 CPU-s)
        return 0
    import psutil

    try:
        kids = [k.pid for k in psutil.Process().children()]
    except psutil.Error:
        return 0
    return end_tree([k for k in kids if k not in _started], reap_roots=True) + end_tree(
        [k for k in kids if k in _started])


def _child_pids() -> list[int] | None:
    """This process's children as the kernel lists them (``/proc/self/task/*/children``: every
    thread's, so orphans given to this subreaper are among them); None where the kernel gives no
    such list (then :mod:`psutil` is asked)."""
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        return None
    pids: list[int] = []
    for tid in tasks:
        try:
            with open(f"/proc/self/task/{tid}/children") as f:
                pids += [int(p) for p in f.read().split()]
        except OSError:
            if int(tid) == os.getpid():   # the main thread has one unless the kernel lacks it
                return None
            # another thread that ended meanwhile: its children went to a thread still listed
    return pids


class OrphanWatch:
    """``with OrphanWatch():`` ends, every ``period`` seconds, the processes a subreaper process
    inherits while it waits on others (a Dask worker killed mid-build leaves its compiler to the
    process that started the local cluster). Does nothing unless this process is a subreaper."""

    def __init__(self, period: float = 1.0):
        self.period = period
        self._stop = threading.Event()
        self._thread = None

    def __enter__(self):
        if _is_subreaper():
            self._thread = threading.Thread(target=self._run, name="rasterhw-orphans", daemon=True)
            self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.wait(self.period):
            with contextlib.suppress(Exception):
                end_orphans()
                remove_dead_work_folders()

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5)


# ---------------------------------------------------------------- work folders of one process
def work_folder(parent: str | Path, name: str) -> Path:
    """A new folder ``parent/.NAME.tmp-HOST-PID-*`` for a build in progress: the host and the
    process are in its name, so one left by a process that was killed outright (a Dask worker
    ended mid-build) is removed by :func:`remove_dead_work_folders` (and by the next build of
    the same model), never one still in use."""
    return Path(tempfile.mkdtemp(prefix=f".{name}.tmp-{_HOST}-{os.getpid()}-", dir=parent))


def host_tag() -> str:
    """This host's name as it goes into work and run folder names: letters and digits, at most 32.
    On POSIX the kernel's node name (what ``socket.gethostname`` returns, without importing socket)."""
    if hasattr(os, "uname"):
        name = os.uname().nodename
    else:
        import socket

        name = socket.gethostname()
    return re.sub(r"[^A-Za-z0-9]", "", name)[:32] or "host"


_HOST = host_tag()


def remove_dead_work_folders(parent: str | Path | None = None) -> int:
    """Remove the work folders (:func:`work_folder`) under ``parent`` (default the build root) of
    processes of this host that no longer run; returns how many."""
    from rasterhw.sim.paths import BUILD_ROOT

    n = 0
    for d in Path(parent or BUILD_ROOT).glob(f".*.tmp-{_HOST}-*-*"):
        m = re.search(rf"\.tmp-{_HOST}-(\d+)-[^-]*$", d.name)
        if m and d.is_dir() and not _pid_exists(int(m.group(1))):
            shutil.rmtree(d, ignore_errors=True)
            n += 1
    return n


def _pid_exists(pid: int) -> bool:
    import psutil  # here: a run that finds no work folder does not import it (~0.004 CPU-s)

    return psutil.pid_exists(pid)


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class _Popen(subprocess.Popen):
    """:class:`subprocess.Popen` that keeps the child's resource usage (``os.wait4``) when it reaps it."""

    rusage = None

    def _try_wait(self, wait_flags):   # CPython's reaping step (Popen.wait), with wait4 for waitpid
        try:
            pid, sts, ru = os.wait4(self.pid, wait_flags)
        except ChildProcessError:
            return self.pid, 0
        if pid == self.pid:
            self.rusage = ru
        return pid, sts


def run_child(cmd: Sequence[str], *, timeout: float | None = None, **kw) -> subprocess.CompletedProcess:
    """:func:`subprocess.run` (same keywords) whose child, in its own process group, is
    killed with that group if this process is interrupted, times out or dies; the result's
    ``rusage`` is the child's resource usage (``os.wait4``; None where it was not reaped by us)."""
    linux = sys.platform.startswith("linux")
    if kw.pop("capture_output", False):
        kw["stdout"] = kw["stderr"] = subprocess.PIPE
    with _Popen(cmd, preexec_fn=_die_with_parent if linux else None, process_group=0, **kw) as p:
        _started.add(p.pid)
        try:
            out, err = p.communicate(timeout=timeout)
        except BaseException:
            # the whole tree, whatever groups it made (SymbiYosys's solvers), then the child itself
            end_tree([p.pid])
            p.wait()
            raise
        finally:
            # a child that left its own children behind (make -> compiler): end them too
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(p.pid, signal.SIGKILL)
            _started.discard(p.pid)
    done = subprocess.CompletedProcess(p.args, p.returncode, out, err)
    done.rusage = p.rusage
    return done
