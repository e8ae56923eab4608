"""Output files of the command line: checked before any work, written whole or not at all.
This is the one writer of every file a command is asked to write (``-o``, ``--out``).

* :func:`check_output` / :func:`check_image_output` refuse, *before* a render, compare or
  simulation starts, a name that cannot be written: an image extension Pillow cannot write, a
  folder (``-o out/``, an existing folder), an output that is one of the command's inputs;
* :func:`atomic_path` (used by :func:`write_image`, :func:`write_text`, :func:`write_bytes`)
  lets the caller write a temporary file, then puts it at the target by what the target is:

  - ``-``: the bytes go to standard output;
  - a symbolic link: written through to the file it points at (the link stays);
  - a device or FIFO (``/dev/null``, ``mkfifo``): opened and written, never replaced;
  - a regular file with other hard links: rewritten in place (replacing it would break the
    links);
  - any other regular file: replaced atomically (rename), keeping its permission bits;
  - a new file: created atomically with the permissions the umask gives (0666 & ~umask), not
    ``mkstemp``'s 0600.

  An error or Ctrl-C before the end leaves the target as it was and no temporary file behind.
"""

from __future__ import annotations

import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.paths import umask

__all__ = ["STDOUT", "atomic_path", "check_image_output", "check_output", "image_format", "image_formats", "write_bytes",
           "write_image", "write_text"]

#: the output name that means standard output
STDOUT = "-"


def check_output(path: str | Path | None, *, flag: str = "-o", inputs: Iterable[str | Path] = ()) -> Path | None:
    """``path`` as a Path if a command may write a file there: not a folder name (an existing
    folder, or a name ending in ``/``), not one of ``inputs`` (the same file by any name: links
    included). ``-`` (standard output) passes. ``None`` passes through."""
    if path is None:
        return None
    text = str(path)
    if text == STDOUT:
        return Path(STDOUT)
    if text.endswith(("/", os.sep)) or (os.path.isdir(text)):
        raise RasterhwError(f"{flag} {text!r} is a folder, not a file name")
    p = Path(text)
    for inp in inputs:
        try:
            same = os.path.samefile(p, inp)
        except OSError:
            same = os.path.realpath(p) == os.path.realpath(inp)
        if same:
            raise RasterhwError(f"{flag} {text!r} is also an input of this command; write the result elsewhere")
    return p


def image_formats() -> dict[str, str]:
    """Extension (``".png"``) -> Pillow format name, for every format Pillow can save."""
    from PIL import Image

    Image.init()
    return {ext: fmt for ext, fmt in Image.registered_extensions().items() if fmt in Image.SAVE}


def image_format(ext: str) -> str | None:
    """The Pillow format that saves extension ``ext`` (``".png"`` -> ``"PNG"``), None if none: the
    common formats from Pillow's ``preinit`` (five plugins) before loading every plugin
    (:func:`image_formats`, ~40 of them: 0.1-0.2 CPU-s of a ``rasterhw sim`` run writing its .png)."""
    from PIL import Image

    Image.preinit()
    fmt = Image.EXTENSION.get(ext)
    return fmt if fmt in Image.SAVE else image_formats().get(ext)


def check_image_output(path: str | Path | None, *, flag: str = "-o",
                       inputs: Iterable[str | Path] = ()) -> Path | None:
    """``path`` as a Path if Pillow can write an image there by its extension; else a
    :class:`RasterhwError` naming the extensions that work; then :func:`check_output`. ``-``
    (standard output: PNG) and ``None`` pass through."""
    if path is None:
        return None
    p = Path(path)
    if str(path) == STDOUT:
        return p
    ext = p.suffix.lower()
    fmt = image_format(ext)
    if fmt is None:
        common = ".png, .bmp, .tif, .ppm, .jpg"
        raise RasterhwError(f"{flag} {str(p)!r}: {'no' if not ext else 'unknown'} image extension"
                            f"{'' if not ext else ' ' + repr(ext)}; use one of {common}")
    if not _holds_rgb(fmt):   # e.g. .xbm (1 bit): refused now, not after the run
        raise RasterhwError(f"{flag} {str(p)!r}: {fmt} cannot hold an RGB image; "
                            "use one of .png, .bmp, .tif, .ppm, .jpg")
    return check_output(path, flag=flag, inputs=inputs)


#: the largest image each format holds (Pillow shrinks a bigger .ico to 256 x 256 silently)
_MAX_SIDE = {"ICO": 256}


def _holds_rgb(fmt: str) -> bool:
    """Can Pillow write a small RGB image in ``fmt``? (tried in memory, once per format)"""
    if fmt not in _RGB_OK:
        import io

        from PIL import Image

        try:
            Image.new("RGB", (2, 2)).save(io.BytesIO(), format=fmt)
            _RGB_OK[fmt] = True
        except Exception:  # noqa: BLE001 - any refusal of Pillow's means no
            _RGB_OK[fmt] = False
    return _RGB_OK[fmt]


_RGB_OK: dict[str, bool] = {}


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """``with atomic_path(p) as tmp:`` write ``tmp``; on success it is put at ``p`` by the rules
    of this module (stdout, through a link, a device or FIFO, a hard-linked file in place, any
    other file replaced atomically keeping its mode); on any error (or Ctrl-C) ``p`` is untouched
    and ``tmp`` removed."""
    text = str(path)
    if text == STDOUT:
        target, kind = None, "stdout"
    else:
        if text.endswith(("/", os.sep)):
            raise RasterhwError(f"{text!r} is a folder, not a file name")
        target = Path(os.path.realpath(text))    # through symbolic links (a dangling one: its target)
        try:
            st = os.stat(target)
        except FileNotFoundError:
            st = None
        if st is None:
            # a link whose target has no name to resolve (``/dev/stdout`` -> ``/proc/self/fd/1`` ->
            # ``pipe:[...]``): what it opens is what counts
            try:
                st = os.stat(text)
            except OSError:
                st = None
            if st is not None and not stat.S_ISREG(st.st_mode) and not stat.S_ISDIR(st.st_mode):
                target = Path(text)
        if st is None:
            kind = "new"
        elif stat.S_ISDIR(st.st_mode):
            raise RasterhwError(f"{text!r} is a folder, not a file name")
        elif not stat.S_ISREG(st.st_mode):
            kind = "stream"          # device, FIFO, socket: write into it
        elif st.st_nlink > 1:
            kind = "inplace"
        else:
            kind = "replace"
    if kind in ("new", "replace"):
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix, dir=target.parent)
    else:
        fd, tmp = tempfile.mkstemp(prefix=".rasterhw-out.", suffix=Path(text).suffix)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if kind == "stdout":
            sys.stdout.flush()
            with open(tmp_path, "rb") as src:
                shutil.copyfileobj(src, sys.stdout.buffer)
            sys.stdout.buffer.flush()
        elif kind in ("stream", "inplace"):
            with open(tmp_path, "rb") as src, open(target, "wb") as dst:
                shutil.copyfileobj(src, dst)
        else:
            mode = stat.S_IMODE(st.st_mode) if st is not None else 0o666 & ~umask()
            os.chmod(tmp_path, mode)
            os.replace(tmp_path, target)
    finally:
        tmp_path.unlink(missing_ok=True)


def write_image(path: str | Path, rgb8: np.ndarray) -> Path:
    """Write an (H, W, 3) uint8 image to ``path`` (format from the extension), whole or not at all."""
    from PIL import Image

    check_image_output(path)
    fmt = "PNG" if str(path) == STDOUT else image_format(Path(path).suffix.lower())
    side = _MAX_SIDE.get(fmt)
    if side is not None and max(rgb8.shape[:2]) > side:
        raise RasterhwError(f"cannot write {path}: {fmt} holds at most {side}x{side} pixels, the frame is "
                            f"{rgb8.shape[1]}x{rgb8.shape[0]}; use .png")
    with atomic_path(path) as tmp:
        try:
            # PNG at zlib level 1: a 1280 x 1024 frame encodes in 0.054 CPU-s instead of 0.105 (level 6),
            # 10 % larger (sim pixelbus snu-100px: 494 against 447 kB); the pixels are the same
            Image.fromarray(np.ascontiguousarray(rgb8)).save(tmp, format=fmt, **({"compress_level": 1} if fmt == "PNG" else {}))
        except (ValueError, OSError, KeyError, TypeError) as e:  # a format that cannot hold RGB or this size
            raise RasterhwError(f"cannot write {path} as {fmt}: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    return Path(path)


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` (``-``: standard output), whole or not at all."""
    return write_bytes(path, text.encode())


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` (``-``: standard output), whole or not at all."""
    with atomic_path(path) as tmp:   # the name as given: "out/" must stay a folder name
        tmp.write_bytes(data)
    return Path(path)


def write_if_changed(path: str | Path, text: str) -> Path:
    """:func:`write_text` unless ``path`` already holds ``text``: an unchanged generated source
    keeps its timestamp, so the build that uses it is not redone."""
    path = Path(path)
    if not path.exists() or path.read_text() != text:
        write_text(path, text)
    return path
