"""``sim/outfile.py: png_bytes``: the PNG that ``write_image`` writes without Pillow (8-bit RGB, the
Sub filter, zlib level 1) holds exactly the pixels it was given, read back with Pillow; a run that
writes its frame as .png imports no Pillow; other formats still go through Pillow."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image
from rasterhw.sim.outfile import png_bytes, write_image


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (5, 1), (3, 4), (48, 64), (17, 301)])
def test_png_holds_the_pixels(tmp_path, shape):
    rng = np.random.default_rng(sum(shape))
    img = rng.integers(0, 256, (*shape, 3), dtype=np.uint8)
    img[0, 0] = (255, 0, 255)                   # the Sub filter's wrap-around: 0 - 255 and 255 - 0
    if shape[1] > 1:
        img[0, 1] = (0, 255, 0)
    p = write_image(tmp_path / "f.png", img)
    with Image.open(p) as im:
        im.verify()                              # the chunks' CRCs and the zlib stream
    with Image.open(p) as im:
        assert im.mode == "RGB" and im.size == (shape[1], shape[0])
        assert np.array_equal(np.asarray(im), img)
    assert p.read_bytes() == png_bytes(img)


def test_png_of_a_view_and_other_formats(tmp_path):
    """A strided view is written as its pixels; .bmp still goes through Pillow."""
    img = np.arange(6 * 8 * 3, dtype=np.uint8).reshape(6, 8, 3)[::2, ::-1]
    write_image(tmp_path / "v.png", img)
    write_image(tmp_path / "v.bmp", img)
    for name in ("v.png", "v.bmp"):
        with Image.open(tmp_path / name) as im:
            assert np.array_equal(np.asarray(im.convert("RGB")), img), name


def test_writing_a_png_imports_no_pillow(tmp_path):
    code = ("import sys, numpy as np\nfrom rasterhw.sim.outfile import check_image_output, write_image\n"
            f"check_image_output({str(tmp_path / 'a.png')!r})\n"
            f"write_image({str(tmp_path / 'a.png')!r}, np.zeros((4, 5, 3), np.uint8))\n"
            "print(sorted(m for m in sys.modules if m == 'PIL' or m.startswith('PIL.')))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"
