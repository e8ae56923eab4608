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


#: rows per band: images are compared a band at a time, so the int16 working copies stay
#: small whatever the image size (a whole-image int64 copy was ~100 bytes per pixel)
BAND_PIXELS = 1 << 20
#: bytes per pixel :func:`compare_images` plus :func:`diff_image` keep beyond the two inputs
#: (the diff image, 3; the per-pixel flags of a band are bounded by BAND_PIXELS)
BYTES_PER_PIXEL = 3


def _pair(a, b) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a)
    b = np.asarray(b)
    for name, im in (("first", a), ("second", b)):
        if im.ndim != 3 or im.shape[2] != 3:
            raise RasterhwError(f"compare: the {name} image must be (H, W, 3), got {im.shape}")
    if a.shape != b.shape:
        raise RasterhwError(f"compare: images differ in size: {a.shape} vs {b.shape}")
    return a, b


def _bands(a: np.ndarray, b: np.ndarray):
    """``(row slice, |a - b| of those rows as int64 (h, W, 3))`` band by band."""
    step = max(1, BAND_PIXELS // max(1, a.shape[1]))
    for y in range(0, a.shape[0], step):
        sl = slice(y, y + step)
        yield sl, np.abs(a[sl].astype(np.int64) - b[sl].astype(np.int64))


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
    differing = anydiff = 0
    maxc = np.zeros(3, dtype=np.int64)
    for _sl, d in _bands(ia, ib):
        if not d.size:
            continue
        per_pixel = d.max(axis=2)
        differing += int(np.count_nonzero(per_pixel > tolerance))
        anydiff += int(np.count_nonzero(per_pixel))
        maxc = np.maximum(maxc, d.reshape(-1, 3).max(axis=0))
    return {
        "pixels": int(ia.shape[0] * ia.shape[1]),
        "differing_pixels": differing,
        "any_difference_pixels": anydiff,
        "max_abs_diff": [int(v) for v in maxc],
        "tolerance": int(tolerance),
    }


def diff_image(a, b, *, tolerance: int = 0) -> np.ndarray:
    """(H, W, 3) uint8: ``a`` darkened to a quarter of its brightness, with every pixel that
    differs from ``b`` by more than ``tolerance`` (any channel) painted magenta."""
    ia, ib = _pair(a, b)
    out = np.empty(ia.shape, dtype=np.uint8)
    for sl, d in _bands(ia, ib):
        band = out[sl]
        band[...] = np.clip(ia[sl], 0, 255).astype(np.int64) // 4
        band[d.max(axis=2) > tolerance] = HIGHLIGHT
    return out


def write_diff_png(a, b, path: str | Path, *, tolerance: int = 0) -> None:
    """Write :func:`diff_image` of ``a`` and ``b`` as a PNG (Pillow)."""
    from PIL import Image

    Image.fromarray(diff_image(a, b, tolerance=tolerance)).save(str(path))
