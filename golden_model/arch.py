"""What every architecture's golden renderer returns: :class:`Rendered`.

A machine's golden renderer is a function ``render(scene, width, height, *, arch, **options)
-> Rendered``; the machine registry (``rasterhw.sim.registry``) names it, and ``rasterhw render
--arch NAME`` calls it.  Keeping the result one type means the CLI, the demo page and the
comparisons treat every machine alike.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.screen import ScreenTriangles

__all__ = ["Rendered"]


@dataclass
class Rendered:
    """One frame from an architecture's golden model.

    Attributes
    ----------
    rgb8:
        ``(height, width, 3)`` ``uint8`` image, row 0 at the top.
    tris:
        The screen triangles the geometry pipeline produced for this frame (their ``stats``
        carry ``polygons_in`` / ``polygons_drawn``).
    pixels_written:
        Pixel writes the machine made (a machine that overdraws counts every write).
    stats:
        Further JSON-able numbers the machine reports (cycles, passes, fragments ...).
    """

    rgb8: np.ndarray
    tris: ScreenTriangles
    pixels_written: int
    stats: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.rgb8.dtype != np.uint8 or self.rgb8.ndim != 3 or self.rgb8.shape[2] != 3:
            raise ValueError(f"rgb8 must be (H, W, 3) uint8, not {self.rgb8.shape} {self.rgb8.dtype}")
