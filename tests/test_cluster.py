"""Many tasks on a Dask cluster (sim/flow/tasks.py, sim/flow/sweep.py, sim/flow/soak.py): a
scheduler and two single-threaded workers started by hand on 127.0.0.1 (``dask scheduler``,
``dask worker --nworkers 2 --nthreads 1``, as docs/scale.md says), tiny designs, against the
same runs in this process (``serial``): equal apart from the keys that may differ; an
interrupted sweep recomputes nothing it had finished; a worker killed mid-soak loses no round
and repeats none; the build lock serialises builds of one model across processes."""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.flow.soak import run_soak
from rasterhw.sim.flow.sweep import run_sweep
from rasterhw.sim.flow.tasks import VARYING, Runner, Task, parse_scheduler

HERE = Path(__file__).resolve().parent
VENV_BIN = Path(sys.executable).parent
ROUNDS = {"slow": "cluster_rounds:slow_round"}


def _same(points):
    return [{k: v for k, v in p.items() if k not in VARYING} for p in points]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """``tcp://127.0.0.1:PORT`` of a scheduler and 2 one-thread workers started by hand; the
    workers log the test rounds to ``cluster.log`` and import them from tests/."""
    d = tmp_path_factory.mktemp("dask")
    sfile, log = d / "scheduler.json", d / "rounds.log"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")]),
           "RASTERHW_TEST_ROUND_LOG": str(log), "RASTERHW_TEST_ROUND_SLEEP": "0.4"}
    procs = [subprocess.Popen([str(VENV_BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(sfile)], env=env, cwd=d,
                              stdout=subprocess.DEVNULL, stderr=open(d / "scheduler.err", "w"))]  # noqa: SIM115
    try:
        t0 = time.monotonic()
        while not sfile.exists() and time.monotonic() - t0 < 60:
            time.sleep(0.2)
        address = json.loads(sfile.read_text())["address"]
        procs.append(subprocess.Popen([str(VENV_BIN / "dask"), "worker", address, "--nworkers", "2", "--nthreads", "1",
                                       "--no-dashboard", "--host", "127.0.0.1"], env=env, cwd=d,
                                      stdout=subprocess.DEVNULL, stderr=open(d / "worker.err", "w")))  # noqa: SIM115
        from distributed import Client

        with Client(address, timeout="60s") as c:
            c.wait_for_workers(2, timeout=120)
        yield {"address": address, "log": log, "dir": d}
    finally:
        for p in reversed(procs):     # the worker command first (its nanny stops its workers), then the scheduler
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


def _worker_pids(address: str) -> dict[str, int]:
    from distributed import Client

    with Client(address, timeout="30s") as c:
        c.wait_for_workers(2, timeout=120)
        return c.run(os.getpid)


def test_scheduler_names():
    assert parse_scheduler("serial") == ("serial", None)
    assert parse_scheduler("local") == ("local", None)
    assert parse_scheduler("local:3") == ("local", 3)
    assert parse_scheduler("tcp://127.0.0.1:8786") == ("address", "tcp://127.0.0.1:8786")
    for bad in ("", "lokal", "local:0", "local:x", "127.0.0.1:8786", "tcp://"):
        with pytest.raises(RasterhwError):
            parse_scheduler(bad)


def test_task_digest_names_the_task_and_nothing_else():
    a = Task("sim", "pxp", {"sn": 1}, scene="c50", size=(16, 8), engine="pysim")
    assert a.digest() == Task("sim", "pxp", {"sn": 1}, scene="c50", size=(16, 8), engine="pysim").digest()
    others = [Task("sim", "pxp", {"sn": 2}, scene="c50", size=(16, 8), engine="pysim"),
              Task("sim", "pxp", {"sn": 1}, scene="c50", size=(16, 16), engine="pysim"),
              Task("sim", "pxp", {"sn": 1}, scene="c50", size=(16, 8), engine="verilator"),
              Task("render", "experts", {"sn": 1}, scene="c50", size=(16, 8))]
    assert len({a.digest(), *(t.digest() for t in others)}) == 5


def test_hand_started_cluster_sweep_equals_serial(cluster, tmp_path):
    """The issue's must-show on a tiny HDL design: `rasterhw sweep ... --scheduler tcp://...
    --json` on 2 workers started by hand and the same sweep in this process give the same points
    apart from timings and who ran them; every point names the worker and its process."""
    args = ["pxp", "--param", "sn=1,2", "--scene", "c50", "--size", "16x8", "--engine", "pysim", "--fresh", "--json"]
    out = subprocess.run([str(VENV_BIN / "rasterhw"), "sweep", *args, "--scheduler", cluster["address"],
                          "--store", str(tmp_path / "a")], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    ser = run_sweep("pxp", ["sn=1,2"], scenes=["c50"], size=(16, 8), engine="pysim", scheduler="serial",
                    store=tmp_path / "b", fresh=True)
    assert res["scheduler"] == cluster["address"] and ser["scheduler"] == "serial"
    assert [p["params"] for p in res["points"]] == [{"sn": 1}, {"sn": 2}]
    assert all(p["mismatches"] == 0 and p["pixels_compared"] == 128 for p in res["points"])
    pids = _worker_pids(cluster["address"])
    for p in res["points"]:
        assert p["worker"] in pids and p["pid"] == pids[p["worker"]]
    assert _same(res["points"]) == _same(ser["points"])
    assert res["points"][0]["cycles"] != res["points"][1]["cycles"] or res["points"][0]["sn"] != res["points"][1]["sn"]


@pytest.mark.parametrize("where", ["serial", "cluster"])
def test_interrupted_sweep_recomputes_nothing_it_had_finished(request, tmp_path, where):
    scheduler = "serial" if where == "serial" else request.getfixturevalue("cluster")["address"]
    store = tmp_path / "store"
    sweep = dict(scenes=["c50"], size=(24, 24), scheduler=scheduler, store=store)
    params = ["sn=1,2,4", "pn=1,2"]
    seen = []

    def stop_after_two(i, res):
        seen.append(i)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep("render:experts", params, on_point=stop_after_two, **sweep)
    time.sleep(0.5)   # results that finished while the sweep was being stopped are stored too
    kept = len(list(store.rglob("*.json")))
    assert 2 <= kept < 6
    again = run_sweep("render:experts", params, **sweep)
    assert again["reused"] == kept and again["computed"] == 6 - kept
    fresh = run_sweep("render:experts", params, **{**sweep, "store": tmp_path / "other"})
    assert fresh["computed"] == 6 and _same(again["points"]) == _same(fresh["points"])
    assert [p["params"] for p in again["points"]] == [{"sn": s, "pn": p} for s in (1, 2, 4) for p in (1, 2)]


def test_soak_stops_at_the_same_round_on_every_scheduler(cluster):
    rows = {}
    for sch in ("serial", cluster["address"]):
        (row,) = run_soak(pixels=10_000, seed=7, progress=False, scheduler=sch,
                          rounds={"fail": "cluster_rounds:failing_round"})
        rows[sch] = row
    ser, clu = rows["serial"], rows[cluster["address"]]
    assert ser["rounds"] == 4 and ser["mismatches"] == 1 and ser["failures"][0]["round"] == 3
    assert {k: v for k, v in ser.items() if k not in VARYING} == {k: v for k, v in clu.items() if k not in VARYING}


def test_worker_killed_mid_soak_every_round_exactly_once(cluster, tmp_path):
    log: Path = cluster["log"]
    log.write_text("")
    killed = []

    def kill_one_mid_round():
        t0 = time.monotonic()
        first_seen = {}
        while time.monotonic() - t0 < 60:
            lines = [ln.split() for ln in log.read_text().splitlines()]
            now = time.monotonic()
            for what, k, pid in lines:
                first_seen.setdefault((what, k, pid), now)
            ended = {(k, pid) for what, k, pid in lines if what == "end"}
            # a round the soak needs (about 12 rounds make 1,200 pixels; at least 9), not one
            # started ahead that it would cancel; and one seen starting within the last 0.15 s of
            # its 0.4 s, so the kill lands before it ends (an older one could end first on a busy
            # machine: the killed round then had finished)
            running = [(k, pid) for what, k, pid in lines
                       if what == "start" and (k, pid) not in ended and int(k) <= 6
                       and now - first_seen[(what, k, pid)] < 0.15]
            if len(ended) >= 2 and running:
                k, pid = running[-1]
                os.kill(int(pid), signal.SIGKILL)
                killed.append((k, pid))
                return
            time.sleep(0.05)

    killer = threading.Thread(target=kill_one_mid_round)
    killer.start()
    (row,) = run_soak(pixels=1_200, seed=11, progress=False, scheduler=cluster["address"], rounds=ROUNDS,
                      store=tmp_path / "store")
    killer.join()
    (ref,) = run_soak(pixels=1_200, seed=11, progress=False, scheduler="serial", rounds=ROUNDS)
    assert killed, "no round was running to kill"
    k, pid = killed[0]
    lines = [ln.split() for ln in log.read_text().splitlines()]
    assert ["end", k, pid] not in lines                      # the killed run never finished ...
    assert any(ln[0] == "end" and ln[1] == k and ln[2] != pid for ln in lines)   # ... and ran again elsewhere
    assert {k: v for k, v in row.items() if k not in VARYING} == {k: v for k, v in ref.items() if k not in VARYING}
    # every round 0..n-1 exactly once: the pixels add up to the serial run's, one stored result per round
    stored = [json.loads(p.read_text())["result"]["round"] for p in (tmp_path / "store").rglob("*.json")]
    assert sorted(stored)[:row["rounds"]] == list(range(row["rounds"]))
    assert len(stored) == len(set(stored))


def _hold_lock(folder: str, out, delay: float) -> None:
    from rasterhw.sim.workdirs import build_lock

    with build_lock(folder):
        t0 = time.time()
        time.sleep(delay)
        out.put((folder, t0, time.time()))


def test_build_lock_serialises_one_model_across_processes(tmp_path):
    """Two processes building one model (one build folder) take turns; another model builds
    meanwhile (the lock is per build folder, not per host)."""
    ctx = multiprocessing.get_context("spawn")
    q = ctx.Queue()
    folders = [str(tmp_path / "model-a"), str(tmp_path / "model-a"), str(tmp_path / "model-b")]
    ps = [ctx.Process(target=_hold_lock, args=(f, q, 1.5)) for f in folders]
    for p in ps:
        p.start()
    spans = sorted(q.get(timeout=120) for _ in ps)
    for p in ps:
        p.join(30)
    (a1, a2), b = sorted(s[1:] for s in spans if s[0].endswith("model-a")), spans[-1][1:]
    assert a2[0] >= a1[1], spans                       # one model: the second waited for the first
    assert any(b[0] < a[1] and a[0] < b[1] for a in (a1, a2)), spans   # another model: built meanwhile


def test_runner_serial_runs_in_order_and_stores(tmp_path):
    tasks = [Task("render", "experts", {"sn": s}, scene="c50", size=(16, 16)) for s in (4, 1, 2)]
    with Runner("serial", store=tmp_path) as run:
        res = run.map(tasks)
        assert (run.computed, run.reused) == (3, 0)
    assert [r["sn"] for r in res] == [4, 1, 2] and all(r["worker"] == "in-process" for r in res)
    with Runner("serial", store=tmp_path) as run:
        assert _same(run.map(tasks)) == _same(res) and (run.computed, run.reused) == (0, 3)
    with Runner("serial", store=tmp_path, fresh=True) as run:
        run.map(tasks)
        assert (run.computed, run.reused) == (3, 0)


def test_soak_resumes_from_the_store(tmp_path, monkeypatch):
    """A longer soak of the same seed reruns none of the rounds a shorter one finished."""
    log = tmp_path / "rounds.log"
    monkeypatch.setenv("RASTERHW_TEST_ROUND_LOG", str(log))
    (short,) = run_soak(pixels=500, seed=3, progress=False, scheduler="serial", rounds=ROUNDS, store=tmp_path / "s")
    first = [ln.split()[1] for ln in log.read_text().splitlines() if ln.startswith("end")]
    assert first == [str(k) for k in range(short["rounds"])]
    log.write_text("")
    (long,) = run_soak(pixels=1_500, seed=3, progress=False, scheduler="serial", rounds=ROUNDS, store=tmp_path / "s")
    again = [ln.split()[1] for ln in log.read_text().splitlines() if ln.startswith("end")]
    assert again == [str(k) for k in range(short["rounds"], long["rounds"])]
    (ref,) = run_soak(pixels=1_500, seed=3, progress=False, scheduler="serial", rounds=ROUNDS)
    assert {k: v for k, v in long.items() if k != "wall_s"} == {k: v for k, v in ref.items() if k != "wall_s"}


def test_a_worker_with_other_code_refuses_the_task():
    from rasterhw.sim.flow.tasks import code_digest, run_task

    t = Task("render", "experts", {"sn": 1}, scene="c50", size=(8, 8))
    assert run_task(t, code_digest())["pixels_written"] == 64
    with pytest.raises(RasterhwError, match="another version of the code"):
        run_task(t, "0" * 64)


def test_report_runs_on_the_cluster_equal_serial(cluster, tmp_path):
    """The demo's HDL runs and a report's runs are tasks like a sweep's (tasks.run_tasks): on the
    hand-started cluster they give what they give in this process (the demo's frame, PNG bytes,
    included), apart from timings and who ran them."""
    from rasterhw.sim.flow.tasks import call, run_tasks

    tasks = [call("rasterhw.sim.report.demo:hdl_run", machine="experts", block="pxp", engine="pysim", scene="c50",
                  width=16, height=8),
             Task("render", "experts", {"sn": 2}, scene="c50", size=(16, 16))]
    far = run_tasks(tasks, scheduler=cluster["address"], store=tmp_path / "a", fresh=True)
    near = run_tasks(tasks, scheduler="serial", store=tmp_path / "b", fresh=True)
    assert far[0]["mismatches"] == 0 and far[0]["frame_png"]
    assert _same(far) == _same(near)
    pids = _worker_pids(cluster["address"])
    assert all(r["worker"] in pids and r["pid"] == pids[r["worker"]] for r in far)
