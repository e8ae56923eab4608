"""The bench's segment packer equals Amaranth's own constant for the PXP segment layout."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.hdl.experts.pxp import seg_layout
from rasterhw.sim.experts.pxp_sim import _pack


def test_pack_equals_layout_const():
    lay = seg_layout()
    rng = np.random.default_rng(0)
    for _ in range(500):
        seg = {n: int(rng.integers(-(1 << (f.width - 1)) if f.shape.signed else 0,
                                   1 << (f.width - (1 if f.shape.signed else 0))))
               for n, f in lay if rng.random() < 0.9}
        assert _pack(seg, lay) == int(lay.const(seg).as_value().value)
    with pytest.raises(RasterhwError):
        _pack({"nope": 1}, lay)
