"""One figure of a report, drawn and saved the same way by every machine's report."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def saved_figure(path: Path, *, figsize: tuple[float, float], dpi: int | None = 110, nrows: int = 1,
                 ncols: int = 1, **savefig) -> Iterator:
    """Yield the axes of a new figure (one panel, or an array of ``nrows`` x ``ncols``); on
    leaving, lay it out, save it as ``path`` at ``dpi`` (``None``: matplotlib's default) with the
    keyword arguments ``savefig`` (e.g. ``metadata``) and close it (nothing is saved if the
    drawing raises). The figure is the axes' ``.figure`` (``axes.flat[0].figure``)."""
    # matplotlib is imported here, on purpose: most commands never draw, and it costs ~0.3 s
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(nrows, ncols, figsize=figsize)
    try:
        yield ax
        fig.tight_layout()
        fig.savefig(path, dpi=dpi, **savefig)
    finally:
        plt.close(fig)
