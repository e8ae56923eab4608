"""``rasterhw sim pxp``'s golden jobs as a build-cache entry (``sim/experts/scene.py: _cached_jobs`` on ``verilog_cache.arrays_cached``,
issue 51): a warm run reads them back instead of rendering the frame and walking the span cycle
model; what it reads equals what is computed; a damaged entry is computed again, not served; another
scene, option or source gets its own entry."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim import cachefile, paths
from rasterhw.sim.engines import verilog_cache
from rasterhw.sim.experts import scene as S
from rasterhw.sim.experts.pxp_jobs import RANGE_BITS
from rasterhw.sim.packed import as_bytes

OPTS = {"sn": 2, "pn": 4, "aj": "c", "ranges": "static", "pxp": "span"}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "BUILD_ROOT", tmp_path)
    monkeypatch.setattr(cachefile, "BUILD_ROOT", tmp_path)
    monkeypatch.setattr(verilog_cache, "BUILD_ROOT", tmp_path)
    calls = []
    real = S.PxpScene._golden

    def counted(tris, **kw):
        calls.append(kw)
        return real(tris, **kw)

    monkeypatch.setattr(S.PxpScene, "_golden", staticmethod(counted))
    return tmp_path, calls


def _golden(scene="experts-tilt-1000", w=64, h=16, **kw):
    return S.PxpScene().golden(build_scene(scene), w, h, engine="pysim", **{**OPTS, **kw})


def test_the_cached_jobs_are_the_computed_ones(cache):
    tmp, calls = cache
    first = _golden()
    second = _golden()
    assert len(calls) == 1 and len(list((tmp / "verilog").glob("experts-pxp-jobs-*.npz"))) == 1
    tris = run_geometry(build_scene("experts-tilt-1000"), 64, 16, z_bits=16)
    fr = S.render_frame(tris, model="bit", aj="c")
    jb = S.jobs(fr, 2, 4, pxp="span")
    for got in (first, second):
        assert got["fr"] == S._display(fr)
        g = got["jb"]
        assert np.array_equal(g["words"], as_bytes(jb["words"], jb["seg_bits"] + RANGE_BITS))
        for k in ("pixels", "cycles", "pxp_frame_cycles"):
            assert np.array_equal(g[k], jb[k]), k
        for k in ("last_pixel", "lo0", "hi0", "lines", "aj", "seg_bits", "pxp"):
            assert g[k] == jb[k], k
        assert g["span_steps"] == {k: sum(st[k] for st in jb["steps"]) for k in jb["steps"][0]}
        assert list(g["resolve"]) == [t[1] for t in jb["timing"]]
        assert np.array_equal(S._image(got["fr"], jb["pixels"]), S.hdl_image(fr, jb["pixels"]))
    # the run from the cached jobs: the golden pixels and cycles on pysim
    (job,) = S.PxpScene().jobs(second, engine="pysim")
    r = S.PxpScene().result(second, [S.run_job(job, "pysim")], engine="pysim", **OPTS)
    assert r["cycle_mismatches"] == 0 and r["last_pixel_mismatch"] == 0 and r["pixels_compared"] == 64 * 16
    assert np.array_equal(r["frame_rgb"], fr.rgb8)


def test_a_damaged_entry_is_computed_again_and_keys_differ(cache, capsys):
    tmp, calls = cache
    first = _golden()
    (entry,) = (tmp / "verilog").glob("experts-pxp-jobs-*.npz")
    raw = bytearray(entry.read_bytes())
    raw[len(raw) // 2] ^= 1
    entry.write_bytes(bytes(raw))
    again = _golden()
    assert len(calls) == 2 and "does not match the SHA-256" in capsys.readouterr().err
    assert np.array_equal(again["jb"]["words"], first["jb"]["words"])
    _golden(pn=2)
    _golden("experts-1000")
    assert len(calls) == 4 and len(list((tmp / "verilog").glob("experts-pxp-jobs-*.npz"))) == 3
