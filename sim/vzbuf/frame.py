"""The vector Z-buffer's cost of one frame for the demo's cross-machine table: no HDL (the
paper's machine is a FACOM VP200 running vectorised FORTRAN, not a block of logic), so the
frame's time comes from the vector-operation trace priced on the modelled VP200
(:mod:`rasterhw.golden_model.vzbuf.facom`), algorithm 2, no shadows."""

from __future__ import annotations

from rasterhw.golden_model.vzbuf.facom import price
from rasterhw.golden_model.vzbuf.render import render_frame, table_stages
from rasterhw.golden_model.vzbuf.trace import Trace

__all__ = ["frame_cost"]


def frame_cost(scene, width: int, height: int) -> dict:
    """``time_s`` of hidden-surface removal and the whole table-3 frame on the modelled VP200."""
    tr = Trace()
    render_frame(scene, width, height, alg=2, shadows="none", trace=tr)
    phases = price(tr, "vp200")["phases"]
    stages = table_stages(2, "none")
    total = sum(phases.get(p, 0.0) for v in stages.values() for p in v)
    return {"block": "vz2 (golden, traced)", "time_s": total, "clock_hz": None, "source": "model:vp200",
            "note": "no HDL: the paper's machine is a vector computer; time from the vector-operation "
                    "trace priced on the modelled FACOM VP200 (algorithm 2, table 3's stages)"}
