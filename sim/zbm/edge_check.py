"""Edge-pair streams the ZB/M HDL cannot run, refused before any simulation."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.seggen import check_edge_pair_stream

__all__ = ["check_edge_pairs"]


def check_edge_pairs(eps: G.EdgePairs, width: int, height: int, *, units: int = 1,
                     capacity: int = F.AEP_CAPACITY) -> int:
    """Reject streams the hardware cannot run, before any simulation; return the worst unit's
    peak number of active edge pairs.

    Errors (``RasterhwError``): a frame the chips' line memories cannot hold (``width`` outside
    ``1..MAX_WIDTH``, ``height`` outside ``1..MAX_HEIGHT``); ``len < 0``; lines outside
    ``0..height-1`` (or ``h < 1``); top lines out of FIFO order; more than ``capacity`` pairs
    active on one line in one unit (the loader would stall and segments would be lost: the frame
    would not be the scene).
    """
    for name, v, top in (("width", width, F.MAX_WIDTH), ("height", height, F.MAX_HEIGHT)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not 1 <= v <= top:
            raise RasterhwError(f"ZB/M: {name} must be an integer in 1..{top}, not {v!r}")
    if len(eps) == 0:
        return 0
    check_edge_pair_stream(eps, height, who="ZB/M")
    peak = 0
    for u in range(units):
        pu, line = G.max_active_edge_pairs(eps.take(np.flatnonzero(eps.tag % units == u)))
        if pu > capacity:
            raise RasterhwError(f"ZB/M: unit {u} has {pu} edge pairs active on line {line}, more than the "
                                f"active-edge-pair memory holds ({capacity}); use more units or a smaller scene")
        peak = max(peak, pu)
    return peak
