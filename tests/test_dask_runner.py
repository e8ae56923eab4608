"""Dask that pays for itself and Dask for people who use Dask (issue 51 item 5, issue 53 item 6;
sim/flow/tasks.py): one local cluster per command with forked workers, small tasks in batches,
``--scheduler-file``, free ports."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.flow import tasks
from rasterhw.sim.flow.tasks import (
    VARYING,
    Runner,
    batch_size,
    call,
    one_cluster,
    run_batch,
    scheduler_from_file,
)


def square(x: int) -> dict:
    return {"y": x * x, "ppid": os.getppid()}


def fail_on(x: int, bad: int) -> dict:
    if x == bad:
        raise RasterhwError(f"task {x} fails")
    return {"y": x}


def _steady(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in VARYING}


def _calls(n, fn="test_dask_runner:square", **kw):
    return [call(fn, x=i, **kw) for i in range(n)]


def test_a_batch_runs_its_tasks_in_order_and_stops_at_the_first_error():
    got = run_batch(_calls(3))
    assert [ok for ok, _ in got] == [True] * 3 and [r["y"] for _, r in got] == [0, 1, 4]
    got = run_batch(_calls(4, "test_dask_runner:fail_on", bad=1))
    assert [ok for ok, _ in got] == [True, False] and "task 1 fails" in str(got[1][1])


@pytest.mark.heavy
def test_one_cluster_per_command_forked_workers_batches(tmp_path):
    """Inside one_cluster (every CLI command): two Runners use one cluster; its workers are forked
    from the fork server (their parent is not this process); 40 small tasks go in batches and come
    back in order, equal to serial; a failing task's error is raised by map, once."""
    with one_cluster():
        with Runner("local:1", store=tmp_path / "a") as run:
            first = run.address()
            got = run.map(_calls(40))
            assert run.computed == 40
        with Runner("local:1", store=tmp_path / "a") as run:
            assert run.address() == first                       # the same cluster
            again = run.map(_calls(40))
            assert run.reused == 40 and run.computed == 0
            # equal apart from VARYING (the module's contract); that the stored value is the one
            # returned is held below, on a future that would gather two values
            assert [_steady(r) for r in again] == [_steady(r) for r in got]
            with pytest.raises(RasterhwError, match="task 7 fails"):
                run.map(_calls(20, "test_dask_runner:fail_on", bad=7))
        assert tasks._CLUSTERS
    assert not tasks._CLUSTERS                                  # closed at the end of the command
    assert [r["y"] for r in got] == [i * i for i in range(40)]
    assert all(r["ppid"] != os.getpid() for r in got)           # forked by the fork server, not spawned here
    with Runner("serial") as run:
        ser = run.map(_calls(40))
    assert [r["y"] for r in ser] == [r["y"] for r in got]


def test_a_result_being_stored_by_a_callback_is_in_the_store_when_result_returns(tmp_path, monkeypatch):
    """The race a fresh-clone CI run hit (39 of 40 found by the next Runner): a Dask callback
    thread is writing a handle's result when the caller asks for it; the caller's ``_keep`` must
    not return before the file is there."""
    run = Runner("serial", store=tmp_path)
    task = call("test_dask_runner:square", x=3)
    h = tasks.Handle(task, task.digest())
    writing, real_save = threading.Event(), Runner._save

    def slow_save(self, handle, res):
        writing.set()
        time.sleep(0.5)
        real_save(self, handle, res)

    monkeypatch.setattr(Runner, "_save", slow_save)
    callback = threading.Thread(target=run._keep, args=(h, {"y": 9}))
    callback.start()
    assert writing.wait(5)
    run._keep(h, {"y": 9})                 # the caller's turn while the callback is writing
    assert run._path(h.digest).exists() and run.computed == 1
    callback.join()


def test_the_batch_size_leaves_every_worker_busy():
    """8 points on 2 workers: one Dask task each (a slow point never waits behind another); 400
    tiny points: batches of 50 (8 batches, 4 per worker)."""
    assert batch_size(8, 2) == 1 and batch_size(400, 2) == 50 and batch_size(3, 0) == 1


def test_scheduler_file(tmp_path):
    f = tmp_path / "scheduler.json"
    f.write_text(json.dumps({"type": "Scheduler", "address": "tcp://10.0.0.5:8786", "services": {}}))
    assert scheduler_from_file(f) == "tcp://10.0.0.5:8786"
    for text, says in (("{}", "no scheduler address"), ("nonsense", "not JSON"),
                       (json.dumps({"address": "8786"}), "--scheduler must be")):
        f.write_text(text)
        with pytest.raises(RasterhwError, match=says):
            scheduler_from_file(f)
    with pytest.raises(RasterhwError, match="No such file"):
        scheduler_from_file(tmp_path / "missing.json")


@pytest.mark.parametrize("extra, says", [
    (["--scheduler-file", "{missing}"], "--scheduler-file"),
    (["--scheduler-file", "{file}", "--scheduler", "serial"], "give --scheduler or --scheduler-file, not both"),
])
def test_scheduler_file_on_the_command_line(tmp_path, capsys, extra, says):
    from rasterhw.sim.cli.main import main

    f = tmp_path / "s.json"
    f.write_text(json.dumps({"address": "tcp://127.0.0.1:1"}))
    argv = ["sweep", "render:experts", "--param", "sn=1", "--store", str(tmp_path / "st"),
            *[a.format(missing=tmp_path / "none.json", file=f) for a in extra]]
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.startswith(f"error: {says}") and err.count("\n") == 1, err


def test_a_scheduler_file_names_the_scheduler_the_command_reaches(tmp_path, capsys):
    """The address comes from the file: nothing listens at tcp://127.0.0.1:1, and the error names it."""
    from rasterhw.sim.cli.main import main

    f = tmp_path / "s.json"
    f.write_text(json.dumps({"address": "tcp://127.0.0.1:1"}))
    with pytest.raises(SystemExit) as e:
        main(["sweep", "render:experts", "--param", "sn=1", "--store", str(tmp_path / "st"), "--scheduler-file", str(f)])
    assert e.value.code == 2 and "tcp://127.0.0.1:1" in capsys.readouterr().err


class _Regathering:
    """A finished future whose every ``result()`` is a new value, as a task the scheduler ran
    twice would give (``distributed.Future.result()`` gathers again on every call)."""

    key = "call-regathering"
    status = "finished"

    def __init__(self):
        self.calls = 0

    def result(self):
        self.calls += 1
        return {"y": 1, "wall_s": self.calls * 1e-6}


def test_the_stored_result_is_the_returned_one_when_a_future_would_gather_two_values(tmp_path):
    """The done-callback stores, the caller returns: both from one gather of the future, so the
    store can never hold a result that differs from the one returned (not even in ``VARYING``)."""
    run = Runner("serial", store=tmp_path)
    task = call("test_dask_runner:square", x=1)
    h = tasks.Handle(task, task.digest())
    h.future = fut = _Regathering()
    run._finished([h], fut)                     # the callback thread stores
    returned = run.result(h)                    # the caller's value
    stored = json.loads(run._path(h.digest).read_text())["result"]
    assert fut.calls == 1 and stored == returned == {"y": 1, "wall_s": 1e-6}
