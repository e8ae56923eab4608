"""Table 1 statistics: checked against the reference rasteriser and the pipeline's counts."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.blocks import setup
from rasterhw.golden_model.vzbuf.shadows import shadow_polygons
from rasterhw.golden_model.vzbuf.stats import table1


def test_table1_counts_against_reference():
    sc = build_scene("c50")
    t = table1(sc)
    sp = setup(sc, 512, 512)
    assert t["initial polygons"] == 301
    assert t["processed polygons"] == sp.stats["polygons_drawn"]
    assert t["pixels processed"] == rasterise(sp.tris).fragments
    assert abs(t["area per polygon"] - t["pixels processed"] / t["processed polygons"]) < 1e-9
    # every visible quad is 1 to 3 segments (split at its vertex lines)
    assert t["processed polygons"] <= t["segments"] <= 3 * t["processed polygons"]
    sh = shadow_polygons(sc, 512, 512)
    shadow_px = sum(rasterise(sh[n].tris).fragments for n in ("front", "back"))
    assert t["shadow pixels processed"] == shadow_px
    # a cube lit on three faces has six silhouette edges
    assert t["initial shadow polygons"] == 6 * 50


def test_table1_orderings_like_the_paper():
    c50, c100 = table1(build_scene("c50"), shadows=False), table1(build_scene("c100"), shadows=False)
    sp8 = table1(build_scene("sp8"), shadows=False)
    assert c50["pixels processed"] < c100["pixels processed"]
    # the paper: area per polygon falls as cubes are added; spheres' polygons are smallest
    assert c50["area per polygon"] > c100["area per polygon"] > sp8["area per polygon"]
    assert np.isclose(sp8["empty lines"] / 512, 0.27, atol=0.03)
