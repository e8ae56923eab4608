"""The generic scene run (sim/engines/scene.py): a block's SceneRun declared as data, run by one path."""

from __future__ import annotations

from dataclasses import replace

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.scene import Job, SceneRun
from rasterhw.sim.testbench import Expected, find_testbench


class MergerScene(SceneRun):
    """Two seeded merger runs as one "scene"; ``spoil`` changes one expected word of the second."""

    block = "merger-test"

    def check(self, engine: str, spoil: bool = False) -> None:
        if not isinstance(spoil, bool):
            raise RasterhwError("spoil is a flag")

    def golden(self, scene, width: int, height: int, *, engine: str, spoil: bool = False) -> dict:
        return {"seeds": (3, 4)}

    def jobs(self, gold: dict, *, engine: str, spoil: bool = False) -> list[Job]:
        tb = find_testbench("zbm-merger")
        p = tb.params(**{"fifo_depth": 4})
        out = []
        for k, seed in enumerate(gold["seeds"]):
            stim = tb.stimulus(p, seed)
            exp = tb.expect(p, stim)
            if spoil and k == 1:
                port = next(iter(exp.words))
                words = list(exp.words[port])
                words[0] ^= 1
                exp = replace(exp, words={**exp.words, port: words})
            out.append(Job(tb, p, stim, Expected(exp.words, exp.cycles), name=f"seed {seed}"))
        return out

    def result(self, gold: dict, done: list, *, engine: str, spoil: bool = False) -> dict:
        return {"pixels_compared": sum(len(w) for d in done for w in d.job.expect.words.values())}


def test_a_scene_run_compares_every_job_and_takes_the_flow_clock(capsys):
    r = MergerScene().simulate("c50", 8, 8, engine="pysim", progress=True)
    assert r["block"] == "merger-test" and r["engine"] == "pysim" and r["mismatches"] == 0
    assert r["pixels_compared"] > 0 and r["cycles"] > 0 and r["sim_cycles"] >= r["cycles"]
    assert r["clock_hz"] == 25e6                  # zbm-merger's flow: the segment clock first
    assert "merger-test pysim" in capsys.readouterr().err
    bad = MergerScene().simulate("c50", 8, 8, engine="pysim", spoil=True)
    assert bad["mismatches"] == 1                 # the spoilt word, summed over the jobs


def test_a_scene_run_refuses_before_any_work():
    with pytest.raises(RasterhwError, match="engine must be one of"):
        MergerScene().simulate("c50", 8, 8, engine="modelsim")
    with pytest.raises(RasterhwError, match="spoil is a flag"):
        MergerScene().simulate("c50", 8, 8, engine="pysim", spoil=1)
