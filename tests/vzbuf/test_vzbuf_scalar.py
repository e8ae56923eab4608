"""The scalar (one element at a time) machine gives the vector machine's frame bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.render import render_frame
from rasterhw.golden_model.vzbuf.scalar import scalar_run


@pytest.mark.parametrize("alg,shadows", [(1, "none"), (2, "none"), (1, "polygons"), (2, "map")])
def test_scalar_equals_vector(alg, shadows):
    sc = build_scene("sp8")
    f = render_frame(sc, 512, 512, alg=alg, shadows=shadows)
    r = scalar_run(sc, 512, 512, alg=alg, shadows=shadows)
    qid = np.array(r["qid"]).reshape(512, 512)
    polys = np.array([p["poly"] for p in r["polys"]])
    pid = np.where(qid >= 0, polys[np.maximum(qid, 0)], -1)
    assert np.array_equal(pid, f.poly)
    m = pid >= 0
    assert np.array_equal(np.array(r["depth"]).reshape(512, 512)[m], f.depth[m])
    assert np.allclose(np.array(r["inten"]).reshape(512, 512)[m], f.inten[m], rtol=0, atol=1e-12)
    assert set(r["stages"]) == {k.split()[0] for k in f.stages}
