"""Image comparison: counts, largest differences, and a diff picture.

Images are (H, W, 3) arrays of 8-bit RGB (any integer or float dtype holding 0..255 values).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["compare_images", "diff_image", "write_diff_png"]

#: Colour of a differing pixel in :func:`diff_image`.
HIGHLIGHT = (255, 0, 255)


def _pair(a, b) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a)
    b = np.asarray(b)
    for name, im in (("first", a), ("second", b)):
        if im.ndim != 3 or im.shape[2] != 3:
            raise RasterhwError(f"compare: the {name} image must be (H, W, 3), got {im.shape}")
    if a.shape != b.shape:
        raise RasterhwError(f"compare: images differ in size: {a.shape} vs {b.shape}")
    return a.astype(np.int64), b.astype(np.int64)


def compare_images(a, b, *, tolerance: int = 0) -> dict:
    """Compare two RGB images pixel by pixel.

    A pixel differs when any channel differs by more than ``tolerance``.

    Returns
    -------
    dict with ``pixels`` (total), ``differing_pixels`` (beyond the tolerance),
    ``any_difference_pixels`` (differing at all), ``max_abs_diff`` ([r, g, b], largest
    absolute difference per channel), ``tolerance``. All values are plain ints (JSON-ready).
    """
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, np.integer)) or tolerance < 0:
        raise RasterhwError(f"compare: tolerance must be a non-negative integer, not {tolerance!r}")
    ia, ib = _pair(a, b)
    d = np.abs(ia - ib)
    per_pixel = d.max(axis=2) if d.size else np.zeros(d.shape[:2], dtype=np.int64)
    maxc = d.reshape(-1, 3).max(axis=0) if d.size else np.zeros(3, dtype=np.int64)
    return {
        "pixels": int(per_pixel.size),
        "differing_pixels": int(np.count_nonzero(per_pixel > tolerance)),
        "any_difference_pixels": int(np.count_nonzero(per_pixel)),
        "max_abs_diff": [int(v) for v in maxc],
        "tolerance": int(tolerance),
    }


def diff_image(a, b, *, tolerance: int = 0) -> np.ndarray:
    """(H, W, 3) uint8: ``a`` darkened to a quarter of its brightness, with every pixel that
    differs from ``b`` by more than ``tolerance`` (any channel) painted magenta."""
    ia, ib = _pair(a, b)
    out = (np.clip(ia, 0, 255) // 4).astype(np.uint8)
    bad = np.abs(ia - ib).max(axis=2) > tolerance
    out[bad] = HIGHLIGHT
    return out


def write_diff_png(a, b, path: str | Path, *, tolerance: int = 0) -> None:
    """Write :func:`diff_image` of ``a`` and ``b`` as a PNG (Pillow)."""
    from PIL import Image

    Image.fromarray(diff_image(a, b, tolerance=tolerance)).save(str(path))
