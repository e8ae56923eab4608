"""Reading the images ``rasterhw compare`` is given, at any size the memory allows.

Pillow refuses images above ``Image.MAX_IMAGE_PIXELS`` (89 Mpx warns, 178 Mpx raises
``DecompressionBombError``) as a guard against hostile files. Here the guard is our own: the
header gives the size without decoding, :func:`~rasterhw.golden_model.memcheck.check_memory`
is asked before anything is decoded, and only then is Pillow's limit lifted for that file.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.memcheck import check_memory

__all__ = ["image_size", "read_rgb8", "read_rgb8_pair"]

#: peak bytes per pixel while one image is decoded and converted to an RGB array (the
#: decoded image, its RGB conversion, the array)
DECODE_BYTES_PER_PIXEL = 10


def image_size(path: str | Path) -> tuple[int, int]:
    """(width, height) from the file's header (nothing decoded)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            old, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
            try:
                with Image.open(path) as im:
                    return im.size
            finally:
                Image.MAX_IMAGE_PIXELS = old
    except UnidentifiedImageError:
        raise RasterhwError(f"{path}: not an image Pillow can read") from None


def read_rgb8(path: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 of the image at ``path`` (any mode converted to RGB); the caller has
    checked the memory (see :func:`read_rgb8_pair`)."""
    from PIL import Image

    old, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
    try:
        with Image.open(path) as im:
            im.load()
            rgb = im if im.mode == "RGB" else im.convert("RGB")
            return np.asarray(rgb)
    except (OSError, ValueError, SyntaxError) as e:  # truncated or corrupt data
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise RasterhwError(f"{path}: cannot decode the image ({msg})") from None
    finally:
        Image.MAX_IMAGE_PIXELS = old


def read_rgb8_pair(a: str | Path, b: str | Path, *, extra_bytes_per_pixel: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Both images as RGB arrays, after checking that they have one size and that decoding
    them (and ``extra_bytes_per_pixel`` more, e.g. a diff image) fits in memory."""
    (wa, ha), (wb, hb) = image_size(a), image_size(b)
    if (wa, ha) != (wb, hb):
        raise RasterhwError(f"images differ in size: {wa}x{ha} vs {wb}x{hb}")
    npix = wa * ha
    check_memory((3 + DECODE_BYTES_PER_PIXEL + extra_bytes_per_pixel) * npix + (64 << 20),
                 f"compare {wa}x{ha}")
    ia = read_rgb8(a)
    ib = read_rgb8(b)
    return ia, ib
