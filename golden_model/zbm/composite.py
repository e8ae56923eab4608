"""The last stage: alpha-compositing of the final two samples into RGB.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.doublez import DoubleZ
from rasterhw.golden_model.zbm.formats import (
    Z_EMPTY,
)

__all__ = ["composite"]


def composite(px: DoubleZ, background=(0, 0, 0)) -> np.ndarray:
    """Alpha-composite the final 2 samples over the background -> (H, W, 3) uint8.

    ``back = (a1 * c1 + (255 - a1) * bg + 127) // 255`` (bg if s1 empty), then
    ``out = (a0 * c0 + (255 - a0) * back + 127) // 255`` (bg if s0 empty);
    with a0 = 255 the output is exactly c0. Samples behind the second are lost (the paper keeps 2).
    """
    bg = np.asarray(background, np.int64)
    if bg.shape != (3,) or bg.min() < 0 or bg.max() > 255:
        raise RasterhwError(f"ZB/M: background must be three integers 0..255, not {background!r}")
    # worked out where the nearest sample is translucent; an opaque one (a0 = 255) gives c0
    # exactly ((255 * c0 + 127) // 255 = c0); no sample: the background
    v0 = px.z[..., 0] != Z_EMPTY
    out = np.empty(px.z.shape[:-1] + (3,), np.uint8)
    out[...] = bg
    out[v0] = px.c[..., 0, :3][v0]
    t = v0 & (px.a[..., 0] != 255)
    v1 = (px.z[..., 1][t] != Z_EMPTY)[:, None]
    a0, a1 = px.a[..., 0][t][:, None], px.a[..., 1][t][:, None]
    c0, c1 = px.c[..., 0, :3][t], px.c[..., 1, :3][t]
    back = np.where(v1, (a1 * c1 + (255 - a1) * bg + 127) // 255, bg)
    out[t] = (a0 * c0 + (255 - a0) * back + 127) // 255
    return out
