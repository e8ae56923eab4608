"""The multi-run work of the reports, ``synth --all`` and the demo goes through the task runner
(sim/flow/tasks.py: ``run_tasks``): the runs are listed as tasks in the rows' order, come back
in that order, are kept in the store and not run again, and give the same numbers as calling
the run directly. On a cluster: tests/test_cluster.py. Tiny designs only (seconds)."""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from rasterhw.sim.flow.tasks import VARYING, call, run_tasks

REPO = Path(__file__).resolve().parents[1]


def _same(rs):
    return [{k: v for k, v in r.items() if k not in VARYING} for r in rs]


def test_zbm_report_lists_its_runs_in_row_order():
    from rasterhw.sim.zbm import scaling

    names = [(t.name.split(":")[1], dict(t.params)) for t in scaling.report_tasks(engine="verilator", fast=True)]
    assert names == [("pixel_rate", {"interleave": i, "width": scaling.PIXEL_RATE_WIDTH}) for i in (1, 2, 4)] + [
        ("skew", {"engine": "verilator"})] + [("chain", {"units": u, "engine": "verilator"}) for u in (1, 2)]
    full = scaling.report_tasks(engine="icarus")
    assert [dict(t.params).get("interleave") for t in full[:5]] == [1, 2, 4, 8, 16]
    assert [dict(t.params)["units"] for t in full if t.name.endswith(":chain")] == list(scaling.CHAIN_UNITS)
    assert all(t.kind == "call" and t.name.startswith("rasterhw.sim.zbm.scaling:") for t in full)


def test_run_tasks_keeps_order_and_reuses_the_store(tmp_path, monkeypatch):
    """Tasks out of order come back in task order; run again on the store, nothing is
    recomputed; ``fresh`` recomputes everything; an empty list starts nothing."""
    from rasterhw.sim.flow import tasks as T

    ran = []
    real = T.run_task

    def counted(task, code=None):
        ran.append(dict(task.params)["sn"])
        return real(task, code)

    monkeypatch.setattr(T, "run_task", counted)
    tasks = [T.Task("render", "experts", {"sn": s}, scene="c50", size=(8, 8)) for s in (4, 1, 2)]
    got = run_tasks(tasks, scheduler="serial", store=tmp_path)
    assert ran == [4, 1, 2] and [g["sn"] for g in got] == [4, 1, 2] and got[0]["worker"] == "in-process"
    assert len(list(tmp_path.rglob("*.json"))) == 3
    ran.clear()
    assert _same(run_tasks(tasks, scheduler="serial", store=tmp_path)) == _same(got) and ran == []
    run_tasks(tasks, scheduler="serial", store=tmp_path, fresh=True)
    assert ran == [4, 1, 2]
    assert run_tasks([], scheduler="local:2") == []


def test_a_report_run_through_the_runner_is_the_direct_call():
    """One ZB/M pixel-rate run (16-pixel lines, pysim) as a task: the function's own result (as
    ``scaling.pixel_rate(2, width=16, height=12)`` returns it: ceil(16 / 2) + 2 = 10 cycles per
    merge-bound line), plus who ran it."""
    (got,) = run_tasks([call("rasterhw.sim.zbm.scaling:pixel_rate", interleave=2, width=16, height=12)])
    assert _same([got]) == [{"interleave": 2, "width": 16, "cycles_per_line": 10.0, "chip_pixels": 8,
                             "pixels_per_cycle": 1.6, "pixels_per_s": 40e6, "engine": "pysim",
                             # every merge word of the 16 x 12 frame compared (issue 46)
                             "words_compared": 16 * 12, "mismatches": 0}]
    assert got["worker"] == "in-process" and got["wall_s"] > 0


def test_fpga_report_configurations_are_tasks_equal_to_the_flow(tmp_path):
    """A recorded place-and-route configuration read through the runner is the flow's own
    result (build folder as text); the report runs nothing in a fast run."""
    from rasterhw.sim.report import fpga

    cfg = [("zbm-merger", {"fifo_depth": 16}, "ecp5")]
    (got,) = fpga._measure_all(cfg, fast=False, progress=False, timeout=60.0, cached_only=True,
                               scheduler="serial", store=tmp_path, fresh=False)
    want = fpga._measure("zbm-merger", {"fifo_depth": 16}, fast=False, progress=False, timeout=60.0,
                         cached_only=True)
    assert got is not None and want is not None
    norm = {**want, "build_dir": None if want.get("build_dir") is None else str(want["build_dir"])}
    assert got == norm
    assert fpga._measure_all(cfg, fast=True, progress=False, timeout=60.0, cached_only=True,
                             scheduler="local:2", store=None, fresh=False) == [None]


def test_synth_all_runs_each_block_as_a_task(tmp_path):
    from rasterhw.sim import registry
    from rasterhw.sim.flow import synth

    blocks = ["zbm-merger", "experts-dmm"]
    rows = synth.synth_all(small=True, blocks=blocks, scheduler="serial", store=tmp_path)
    assert [r["block"] for r in rows] == blocks
    assert len(list(tmp_path.rglob("*.json"))) == 2
    direct = synth.synthesise("zbm-merger", memory="keep", **registry.flow("zbm-merger").small)
    assert rows[0]["gate_equivalent"] == direct["gate_equivalent"] and rows[0]["flipflops"] == direct["flipflops"]
    assert rows[0]["build_dir"] == str(direct["build_dir"])


def test_demo_hdl_runs_are_tasks_that_bring_their_image_back(tmp_path):
    """The demo's HDL runs go to the runner (no home-made pool); each brings its frame back as
    PNG bytes, pixel for pixel the frame of the run made directly."""
    from rasterhw.sim import registry
    from rasterhw.sim.report import demo

    m = registry.machines()["experts"]
    b = next(s for s in m.sims if s.name == "pxp")

    class Bar:
        n = 0

        def set_postfix_str(self, _s):
            pass

        def update(self, k):
            self.n += k

    bar = Bar()
    (res,) = demo._run_all([(m, b, "c50", (16, 8))], "pysim", bar, scheduler="serial", store=tmp_path)
    assert bar.n == 1 and res["mismatches"] == 0 and res["pixels_compared"] == 128
    img = np.asarray(Image.open(io.BytesIO(base64.b64decode(res["frame_png"]))))
    direct = demo._run_sim("experts", "pxp", "pysim", "c50", (16, 8))
    assert np.array_equal(img, direct["frame_rgb"]) and res["cycles"] == direct["cycles"]


def test_no_home_made_process_pools_left():
    """Many runs go through sim/flow/tasks.py: no process pool or multiprocessing elsewhere in
    the package (the thread pools left split one run, not a list of runs: see their comments)."""
    bad = []
    for top in ("sim", "golden_model", "hdl"):
        for f in (REPO / top).rglob("*.py"):
            if f.name == "tasks.py" and f.parent.name == "flow":
                continue
            text = f.read_text()
            if re.search(r"ProcessPoolExecutor|^\s*(import|from) multiprocessing", text, re.M):
                bad.append(str(f.relative_to(REPO)))
    assert bad == []


@pytest.mark.parametrize("args", [["report", "zbm", "--fast"], ["demo", "--out", "x"], ["synth", "--all", "--small"]])
def test_bad_scheduler_is_one_line_before_anything_runs(args, tmp_path):
    import subprocess
    import sys

    exe = Path(sys.executable).parent / "rasterhw"
    p = subprocess.run([str(exe), *args, "--scheduler", "locale:2"], capture_output=True, text=True, cwd=tmp_path,
                       timeout=120)
    assert p.returncode == 2 and p.stderr.strip().startswith("error: --scheduler must be")
    assert len(p.stderr.strip().splitlines()) == 1 and not (tmp_path / "x").exists()


def test_zbm_mapping_rows_run_as_tasks():
    """The mapping rows' HDL frames are tasks of the report's list (none with ``--fast``), and a
    mapping task gives what calling ``mapping_accesses`` directly gives; the rows read its result."""
    from rasterhw.sim.zbm import report
    from rasterhw.sim.zbm.mapping_hdl import mapping_accesses

    assert report.mapping_tasks(fast=True) == []
    full = report.mapping_tasks()
    assert [(t.name, dict(t.params)) for t in full] == [
        ("rasterhw.sim.zbm.mapping_hdl:mapping_accesses", {"scene": s}) for s in report.REAL_SCENES]
    small = dict(scene="c50", width=64, height=64, interleave=2)
    got = run_tasks([call("rasterhw.sim.zbm.mapping_hdl:mapping_accesses", **small)], scheduler="serial")
    assert _same(got) == _same([mapping_accesses(**small)]) and got[0]["texture_lookups"] > 0
