"""The labelled whole-array variant gives algorithm 2's frame."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.render import render_frame
from rasterhw.golden_model.vzbuf.wholearray import render_whole


@pytest.mark.parametrize("name", ["c50", "sp8"])
def test_whole_array_equals_vz2(name):
    sc = build_scene(name)
    w = render_whole(sc, shadows="polygons")
    f = render_frame(sc, alg=2, shadows="polygons")
    assert np.array_equal(w["poly"], f.poly)
    assert np.array_equal(w["shadowed"], f.shadowed)
    m = f.poly >= 0
    # closed-form edge values here, stepped ones in vz2: equal to rounding
    assert (np.abs(w["depth"][m] - f.depth[m]) / f.depth[m]).max() < 1e-12
    assert np.abs(w["inten"] - f.inten).max() < 1e-9
    assert w["fragments_real"] + w["fragments_shadow"] == f.stats["pixels_real"] + f.stats["pixels_shadow"]
