"""One figure of a report, drawn and saved the same way by every machine's report."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def saved_figure(path: Path, *, figsize: tuple[float, float], dpi: int = 110) -> Iterator:
    """Yield the axes of a new one-panel figure; on leaving, lay it out, save it as ``path``
    at ``dpi`` and close it (nothing is saved if the drawing raises)."""
    # matplotlib is imported here, on purpose: most commands never draw, and it costs ~0.3 s
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize)
    try:
        yield ax
        fig.tight_layout()
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
