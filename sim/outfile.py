"""Output files of the command line: checked before any work, written whole or not at all.

* :func:`check_image_output` refuses a name whose extension Pillow cannot write *before* a
  render, compare or simulation starts (not after minutes of work);
* :func:`write_image` / :func:`write_text` write into a temporary file beside the target and
  rename it into place, so an error or Ctrl-C never leaves a partial file under the user's
  name.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["atomic_path", "check_image_output", "image_formats", "write_image", "write_text"]


def image_formats() -> dict[str, str]:
    """Extension (``".png"``) -> Pillow format name, for every format Pillow can save."""
    from PIL import Image

    Image.init()
    return {ext: fmt for ext, fmt in Image.registered_extensions().items() if fmt in Image.SAVE}


def check_image_output(path: str | Path | None, *, flag: str = "-o") -> Path | None:
    """``path`` as a Path if Pillow can write an image there by its extension; else a
    :class:`RasterhwError` naming the extensions that work. ``None`` passes through."""
    if path is None:
        return None
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in image_formats():
        common = ".png, .bmp, .tif, .ppm, .jpg"
        raise RasterhwError(f"{flag} {str(p)!r}: {'no' if not ext else 'unknown'} image extension"
                            f"{'' if not ext else ' ' + repr(ext)}; use one of {common}")
    if p.exists() and p.is_dir():
        raise RasterhwError(f"{flag} {str(p)!r} is a folder, not a file name")
    return p


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """``with atomic_path(p) as tmp:`` write ``tmp``; on success it replaces ``p``, on any
    error (or Ctrl-C) it is removed and ``p`` is untouched."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, path)
    finally:
        tmp_path.unlink(missing_ok=True)


def write_image(path: str | Path, rgb8: np.ndarray) -> Path:
    """Write an (H, W, 3) uint8 image to ``path`` (format from the extension), whole or not at all."""
    from PIL import Image

    path = check_image_output(path)
    fmt = image_formats()[path.suffix.lower()]
    with atomic_path(path) as tmp:
        try:
            Image.fromarray(np.ascontiguousarray(rgb8)).save(tmp, format=fmt)
        except (ValueError, OSError, KeyError, TypeError) as e:  # a format that cannot hold RGB or this size
            raise RasterhwError(f"cannot write {path} as {fmt}: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path``, whole or not at all."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def write_if_changed(path: str | Path, text: str) -> Path:
    """:func:`write_text` unless ``path`` already holds ``text``: an unchanged generated source
    keeps its timestamp, so the build that uses it is not redone."""
    path = Path(path)
    if not path.exists() or path.read_text() != text:
        write_text(path, text)
    return path
