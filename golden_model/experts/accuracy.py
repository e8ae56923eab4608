"""The bit model's error against the float model, for one datapath (issue 48 item 2).

Both models render the same screen triangles; the float model keeps x as an exact rational and
z, i in float64 (:mod:`slp`), the bit model uses the widths of its :class:`formats.Datapath`.
The figures compare the displayed colour (``rgb8``, 8 bits a channel):

* ``max_abs_error``: the largest difference of one channel of one pixel (0..255);
* ``pixels_differing_from_float``: pixels where any channel differs;
* ``psnr_db``: ``10 log10(255^2 / MSE)`` over every channel of every pixel (``inf`` when equal);
* ``visible_differing``: pixels whose visible triangle differs (x and z, not rounding of colour);
* ``pixels_differing_from_ours``: pixels whose colour differs from the bit model at ours (40-bit).

Most pixels differ from float at either datapath: the pixel's hue is 3 bits a channel (seed 000,
3.2), the float model's is not. The datapath's own effect is the last two figures.
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.experts.formats import DATAPATHS, Formats
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = ["float_error"]


def float_error(tris: ScreenTriangles, datapath: str = "ours", *, aj: str = "none",
                intensity_bits: int = 7) -> dict:
    """Render ``tris`` with the float model and the bit model at ``datapath``; the figures above."""
    dp = DATAPATHS[datapath]
    fl = render_frame(tris, model="float", aj=aj)
    bt = render_frame(tris, model="bit", aj=aj, fmt=Formats(intensity_bits=intensity_bits, datapath=dp))
    ours = bt if dp.name == "ours" else render_frame(tris, model="bit", aj=aj, fmt=Formats(intensity_bits=intensity_bits))
    a, b = fl.rgb8.astype(np.int64), bt.rgb8.astype(np.int64)
    d = np.abs(a - b)
    mse = float(np.mean(d.astype(np.float64) ** 2))
    return {"datapath": dp.name, "label": dp.label, "datapath_bits": dp.word_bits, "multipliers": dp.multipliers,
            "max_abs_error": int(d.max()) if d.size else 0,
            "pixels_differing_from_float": int(np.count_nonzero(d.max(axis=2))),
            "psnr_db": math.inf if mse == 0 else 10.0 * math.log10(255.0 ** 2 / mse),
            "visible_differing": int(np.count_nonzero(fl.tri_id != bt.tri_id)),
            "pixels_differing_from_ours": int(np.count_nonzero((ours.rgb8 != bt.rgb8).any(axis=2))),
            "pixels": int(fl.width * fl.height)}
