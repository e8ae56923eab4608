"""The speed build of the ``zbm-unit`` testbench on the generic Verilator engine (``UnitBench.sim_verilog``:
identical modules merged, the pixel processor out of line; g++ -O2 with gcc PGO, the profile trained on
``UnitBench.train_stimulus``) changes how fast the model runs, never what it computes: on a small frame,
the same words and the same segment-clock count as the build before issue 31 (one module per instance),
with the profile trained on one scene (c50) and the check run on another (sp8). The merged build alone
is also held word-, cycle- and line-log-exact with the cocotb bench by ``test_zbm_unit_engine.py`` (its
build is the merged one). Cold: three small builds (plain -O0, instrumented -O2, profiled -O2): marked slow."""

from __future__ import annotations

import json

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.words import doublez_words
from rasterhw.sim.engines import verilator
from rasterhw.sim.engines.verilog_cache import generate_cached
from rasterhw.sim.testbench import find_testbench
from rasterhw.sim.zbm.scene import SPEED_BUILD, run_scene
from rasterhw.sim.zbm.testbench import TRAIN_SCENE

pytestmark = pytest.mark.cocotb

# a size no other test builds, so that its profile (kept in build/pgo/) is this test's alone
W, H, IL = 48, 16, 2


@pytest.mark.slow
def test_speed_build_same_frame_same_cycles_as_the_plain_build(capfd):
    """Three builds (~1 min of CPU; 4 min at load 12): slow. The quick version in CI is
    ``test_zbm_unit_engine.py``, whose engine build is the merged one with the pixel
    processor out of line: the same words, cycles and line log as the cocotb bench (unmerged)."""
    tris = run_geometry(build_scene("sp8"), W, H)
    eps = G.edge_pairs(tris)
    gold = doublez_words(G.render_zbm(tris, interleave=IL).pixels)
    plain = run_scene([eps], width=W, height=H, interleave=IL, build={"speed": False, "opt": "-O0", "pgo": False},
                      line_log=True)
    tb = find_testbench("zbm-unit")
    p = tb.params(interleave=IL, width=W, height=H)
    stim = tb.scene_stimulus(p, [eps])
    inputs = {"i": verilator._depth(len(stim.words["i"]))}
    outputs = {n: verilator._depth(len(w)) for n, w in tb.expect(p, stim).words.items()}

    def cached():
        return verilator.profile(tb, p, verilator.bench_design(tb, p, inputs, outputs, True), inputs=inputs,
                                 outputs=outputs, train=False)

    had = cached() is not None
    # "train" (what sim zbm asks for): trains the design's profile with its first build, and says so
    speed = run_scene([eps], width=W, height=H, interleave=IL, build={**SPEED_BUILD, "pgo": "train"}, line_log=True)
    assert speed["build"] == {"speed": True, "opt": "-O2", "pgo": True}
    said = "training its gcc profile on scene c50" in capfd.readouterr().err
    assert said != had        # said exactly when it trained
    # the profile: trained on c50 (not the frame checked here), with gcc's files
    prof = cached()
    assert prof is not None
    assert json.loads((prof / "trained.json").read_text())["what"] == f"scene {TRAIN_SCENE}" != "scene sp8"
    assert TRAIN_SCENE != "sp8"
    assert sorted(prof.glob("*.gcda")), "the training run wrote no profile"
    for r in (plain, speed):
        assert np.array_equal(r["s0"], gold[0]) and np.array_equal(r["s1"], gold[1])
        assert r["proto_errors"] == 0 and r["frames_ok"] == 1 and r["overflow"] == 0
    assert speed["cycles"] == plain["cycles"] > H
    assert speed["line_cycles"] == plain["line_cycles"]
    # "auto" finds the cached profile (and never trains one): the same binary as pgo=True
    auto = run_scene([eps], width=W, height=H, interleave=IL, build=SPEED_BUILD)
    assert auto["build"]["pgo"] and auto["build_s"] == 0.0 and auto["cycles"] == plain["cycles"]


def test_sim_zbm_trains_the_profile_with_the_first_build_unless_told_not_to(monkeypatch):
    """``rasterhw sim zbm`` on Verilator asks for ``pgo="train"`` (the profiled build without a
    training step the user must know of; ``auto``, the soak's and the report's, never trains);
    ``RASTERHW_PGO`` 0 / 1 overrides both."""
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.sim.zbm import scene
    seen = []

    def fake(eps, **kw):
        seen.append((kw["engine"], kw["build"]))
        raise RasterhwError("stop")

    monkeypatch.setattr(scene, "unit_job", fake)
    for engine in ("verilator", "pysim"):
        with pytest.raises(RasterhwError, match="stop"):
            scene.simulate(build_scene("c50"), 32, 16, interleave=2, engine=engine)
    assert seen == [("verilator", {**SPEED_BUILD, "pgo": "train"}), ("pysim", None)]
    monkeypatch.delenv("RASTERHW_PGO", raising=False)
    assert verilator._settings({**SPEED_BUILD, "pgo": "train"}, "-O1")[2] == "train"
    assert verilator._settings(SPEED_BUILD, "-O1")[2] == "auto"
    for env, want in (("0", False), ("1", True)):
        monkeypatch.setenv("RASTERHW_PGO", env)
        assert verilator._settings({**SPEED_BUILD, "pgo": "train"}, "-O1")[2] is want
    with pytest.raises(RasterhwError, match="pgo must be False, True, 'auto' or 'train'"):
        verilator._settings({"pgo": "yes"}, "-O1")


def test_merged_unit_keeps_one_pixel_processor_out_of_line():
    """What the speed build compiles: the I = 2 unit's 16 pixel processors are one module, marked
    for Verilator to keep out of line; the unmerged text has them all."""
    tb = find_testbench("zbm-unit")
    # the cocotb unit bench's 64 x 16 I = 2 unit, from the Verilog cache its runs fill (one
    # conversion for both; 4.9 s warm before, uncached)
    p = {"interleave": IL, "width": 64, "height": 16, "capacity": F.AEP_CAPACITY, "schedule": "overlap"}
    full = generate_cached("zbm-unit", head=True, **p)
    merged = tb.sim_verilog(tb.params(**p), full)
    pp = [ln for ln in full.splitlines() if ln.startswith("module ") and ".pp" in ln.split("(")[0]]
    assert len(pp) == 2 * 8
    kept = [ln for ln in merged.splitlines() if ln.startswith("module ") and ".pp" in ln.split("(")[0]]
    assert len(kept) == 1
    assert merged.count("/*verilator no_inline_module*/") == 1
    assert merged.split(kept[0], 1)[1].split("\n")[1].strip() == "/*verilator no_inline_module*/"
    assert len(merged) < len(full) / 2
