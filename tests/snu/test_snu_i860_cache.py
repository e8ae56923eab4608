"""``sim/snu/scene.py: i860_clocks``: the i860 scan converter's and geometry groups' clocks, scene
independent, as a build-cache entry (issue 51): what a warm run reads equals what the model
schedules; another processor gets its own entry."""

from __future__ import annotations

from dataclasses import replace

import pytest
from rasterhw.golden_model.snu import i860
from rasterhw.sim import cachefile, paths
from rasterhw.sim.engines import verilog_cache
from rasterhw.sim.snu import scene as S

GROUPS = [("vertex_transform", "normal_transform"), ("normalise", "light"), ("clip", "perspective_divide", "screen_map")]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    for mod in (paths, cachefile, verilog_cache):
        monkeypatch.setattr(mod, "BUILD_ROOT", tmp_path)
    return tmp_path


def _direct(cpu):
    geo = i860.table1_model(cpu, stream_triangles=0)
    return i860.scan_clocks(cpu), [sum(geo[s]["clocks"] for s in g) for g in GROUPS]


def test_the_cached_clocks_are_the_model_s(cache, monkeypatch):
    cpus = (i860.I860(), replace(i860.I860(), dual_instruction=False))
    want = [_direct(cpu) for cpu in cpus]
    assert want[0] != want[1]                                   # the two processors' clocks differ
    for cpu, w in zip(cpus, want, strict=True):
        assert S.i860_clocks(cpu) == w                          # computed, written
        assert [type(v) for v in S.i860_clocks(cpu)[0].values()] == [int, int, float]
    assert len(list(cache.glob("verilog/snu-i860-*.npz"))) == 2   # one entry each

    def boom(*a, **k):
        raise AssertionError("scheduled again")

    monkeypatch.setattr(i860, "scan_clocks", boom)
    monkeypatch.setattr(i860, "table1_model", boom)
    assert [S.i860_clocks(cpu) for cpu in cpus] == want         # read back, not scheduled
