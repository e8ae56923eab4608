"""``rasterhw sim pixelbus`` runs and reports one thing on every engine (issue 46): the whole frame
(CLEAR, the two pipelines' writes after their producer gaps, SWAP, the display buffer read out), so
``cycles`` is the frame's length on pysim as on Verilator. Before, pysim ran the pixel writes alone
(snu-100px at 64 x 48: 861 cycles, ``extra`` without ``frame``) and Verilator the frame (35,845).

The scene is tiny for pysim's sake: experts-solid-5 at 16 x 16 is 2 triangles, 55 writes, a
305-clock frame (the pixel writes alone take about a fifth of that)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from rasterhw.sim.cli.main import main

ARGS = ["sim", "pixelbus", "--scene", "experts-solid-5", "--size", "16x16", "--json"]
SCHEDULE = ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")


def _sim(engine: str, tmp_path, capsys) -> dict:
    try:
        main([*ARGS, "--engine", engine, "-o", str(tmp_path / f"{engine}.png")])
    except SystemExit as e:
        assert not e.code, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def test_sim_pixelbus_on_pysim_is_the_frame(tmp_path, capsys):
    """pysim runs the whole frame: ``cycles`` is the golden schedule's frame length (SWAP + 1), the
    schedule words the HDL gave are the golden ones, and ``extra.frame`` is there."""
    r = _sim("pysim", tmp_path, capsys)
    frame = r["extra"]["frame"]
    assert r["mismatches"] == 0 and r["cycle_mismatches"] == 0 and frame["schedule_mismatches"] == 0
    assert frame["schedule_hdl"] == frame["schedule_golden"]
    assert r["cycles"] == frame["schedule_golden"]["cycles"] == r["extra"]["cycles_golden"]
    # the frame's length is more than the pixel writes: the clear comes first (16 x 16 / 5 banks)
    assert frame["schedule_hdl"]["t_start"] > 16 * 16 // 5 and r["cycles"] > frame["schedule_hdl"]["t_start"]
    # the run's clocks: the frame, then the schedule word and the display buffer read out
    assert r["sim_cycles"] == r["cycles"] + 16 * 16 + 1


@pytest.mark.cocotb   # the Verilator engine (a build of the small frame bench the first time)
def test_sim_pixelbus_pysim_and_verilator_report_the_same(tmp_path, capsys):
    """The same command on both engines: the same top-level and ``extra`` keys, the same ``cycles``,
    ``sim_cycles``, schedule and frame figures, and the same image."""
    got = {e: _sim(e, tmp_path, capsys) for e in ("pysim", "verilator")}
    a, b = got["pysim"], got["verilator"]
    assert set(a) == set(b) and set(a["extra"]) == set(b["extra"]) and set(a["extra"]["frame"]) == set(b["extra"]["frame"])
    for k in ("cycles", "sim_cycles", "mismatches", "cycle_mismatches", "pixels_compared", "clock_hz"):
        assert a[k] == b[k], (k, a[k], b[k])
    assert a["mismatches"] == 0 and a["cycle_mismatches"] == 0
    wall = {"golden_wall_s", "hdl_wall_s"}
    assert {k: v for k, v in a["extra"].items() if k not in wall} == {k: v for k, v in b["extra"].items() if k not in wall}
    assert [a["extra"]["frame"]["schedule_hdl"][k] for k in SCHEDULE] == \
        [b["extra"]["frame"]["schedule_hdl"][k] for k in SCHEDULE]
    assert np.array_equal(np.asarray(Image.open(a["image"])), np.asarray(Image.open(b["image"])))


#: modules a Verilator ``sim pixelbus`` run has no use for (issue 51: its harness CPU): the cocotb
#: package and engine, the mesh reader (the scene is built in), the cache-size report (no
#: ``RASTERHW_CACHE_MAX``). Pillow stays: it writes the .png (the house prefers the library to a
#: hand-written encoder, which saved ~0.04 CPU-s)
UNNEEDED = ("cocotb", "rasterhw.sim.engines.cocotb", "rasterhw.golden_model.meshio", "rasterhw.sim.cacheinfo")


@pytest.mark.cocotb   # the Verilator engine (a build of the small frame bench the first time)
def test_a_verilator_run_imports_nothing_it_does_not_use(tmp_path):
    """The command in a fresh process: after the run, none of :data:`UNNEEDED` is in ``sys.modules``."""
    import os
    import subprocess
    import sys

    code = ("import json, sys\nfrom rasterhw.sim.cli.main import main\n"
            f"try:\n    main({[*ARGS, '--engine', 'verilator', '-o', str(tmp_path / 'f.png')]!r})\n"
            "except SystemExit as e:\n    assert not e.code, e.code\n"
            f"print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in {UNNEEDED!r} or m in {UNNEEDED!r})),"
            " file=sys.stderr)")
    env = {k: v for k, v in os.environ.items() if k != "RASTERHW_CACHE_MAX"}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, env=env)
    assert r.returncode == 0, r.stderr[-2000:]
    assert json.loads(r.stdout)["mismatches"] == 0
    assert json.loads(r.stderr.strip().splitlines()[-1]) == []


def _equal(a, b, path=""):
    """``a == b`` through dicts and dataclasses, arrays by dtype and value, scalars by type and value."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        assert isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype, path
        assert np.array_equal(a, b), path
    elif isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), path
        for k in a:
            _equal(a[k], b[k], f"{path}/{k}")
    elif hasattr(a, "__dataclass_fields__"):
        assert type(a) is type(b), path
        _equal(vars(a), vars(b), path)
    else:
        assert type(a) is type(b) and a == b, (path, a, b)


@pytest.mark.parametrize("scene, w, h", [("experts-solid-5", 16, 16), ("c50", 64, 48)])
def test_the_cached_frame_golden_is_the_computed_one(scene, w, h):
    """``frame_golden`` read back from its build-cache entry (the second call at least) gives the
    stream, producer gaps, schedule and inner-loop counts the golden model computes, value and type."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.snu import i860
    from rasterhw.sim.snu.scene import frame_golden

    tris = run_geometry(build_scene(scene), w, h, z_bits=24, z_far_is_zero=True)
    want = frame_golden(tris, i860.I860(), cached=False)
    for _ in range(2):
        _equal(frame_golden(tris, i860.I860()), want)
