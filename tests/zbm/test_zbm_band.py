"""A frame drawn as bands of scan lines (``golden_model/zbm/band.py``, ``sim/zbm/bands.py``) and
stitched equals the frame drawn whole: in the golden model at every kind of split line, and
through the unit's HDL (pysim) at a small size."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.band import edge_pair_band


@pytest.mark.parametrize("cuts", [(1,), (17,), (20, 21), (5, 30, 39)])
def test_bands_stitch_to_the_whole_frame(cuts):
    tris = ref.random_triangles(48, 40, 50, mean_area=160, seed=12)
    eps = G.edge_pairs(tris)
    whole = G.chain_frame([eps], 48, 40)
    edges = (0, *cuts, 40)
    parts = [(a, b, G.chain_frame([edge_pair_band(eps, a, b)], 48, 40)) for a, b in zip(edges, edges[1:], strict=False)]
    for k in ("z", "a", "c", "tag"):
        assert np.array_equal(np.concatenate([getattr(f, k)[a:b] for a, b, f in parts]), getattr(whole, k)), k
    for a, b, f in parts:   # a band draws nothing outside its lines
        assert (np.delete(f.z, np.s_[a:b], axis=0) == F.Z_EMPTY).all()
    spanning = [a for a, _, _ in parts[1:] if ((eps.y < a) & (eps.y + eps.h > a)).any()]
    assert spanning   # some pair enters a band stepped from above (the case that needs the adds)


def test_band_bad_lines():
    eps = G.edge_pairs(ref.random_triangles(16, 16, 3, seed=1))
    for y0, y1 in ((-1, 4), (4, 4), (5, 2)):
        with pytest.raises(RasterhwError, match="edge_pair_band"):
            edge_pair_band(eps, y0, y1)


@pytest.mark.slow
@pytest.mark.parametrize("own_height", [False, True])
def test_two_bands_through_the_unit_hdl_equal_the_whole_frame(own_height):
    from rasterhw.sim.zbm.bands import two_bands

    r = two_bands("c50", width=32, height=16, interleave=1, engine="pysim", own_height=own_height)
    assert r["identical"] and 1 <= r["split_line"] < 16
    assert (r["split_line"] == 8) == own_height             # own height: two equal bands, one build
    assert r["whole_mismatches"] == r["top_mismatches"] == r["bottom_mismatches"] == 0
    assert r["whole_frames_ok"] == r["top_frames_ok"] == r["bottom_frames_ok"] == 1
