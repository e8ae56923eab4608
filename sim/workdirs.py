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
  if the parent dies (``PR_SET_PDEATHSIG``), and, with its whole process group (make,
  the compiler), if the parent is interrupted or fails while waiting.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from filelock import FileLock, Timeout

__all__ = ["build_lock", "cleanup", "keep", "run_child", "run_folder", "temp_run_folder"]

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
    """A new folder under ``parent`` for one run, removed by :func:`cleanup` (or :func:`release`)."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    d = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
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
        try:
            out, err = p.communicate(timeout=timeout)
        except BaseException:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            raise
        finally:
            # a child that left its own children behind (make -> compiler): end them too
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(p.pid, signal.SIGKILL)
    done = subprocess.CompletedProcess(p.args, p.returncode, out, err)
    done.rusage = p.rusage
    return done
