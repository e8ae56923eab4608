"""A stream of pixel writes as it travels on a pixel bus (SNU) — the contract between the
golden scan converter that produces it and the HDL driver that plays it into the design.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu.formats import RGB_BITS, Z_BITS

__all__ = ["PixelStream"]


@dataclass
class PixelStream:
    """Pixel writes in the order each pipeline issues them.

    Attributes
    ----------
    width, height : frame size; ``addr = y * width + x``.
    addr : (N,) int64 — linear pixel address.
    rgb : (N,) int64 — 24 bits, ``r << 16 | g << 8 | b``.
    z : (N,) int64 — ``z_bits`` wide, **far = 0** (a larger value is nearer).
    pipe : (N,) int64 — the pipeline (0 or 1) that issues the write; order within a
        pipeline is the order of the array.
    z_bits : width of ``z`` (24 in the SNU system).
    """

    width: int
    height: int
    addr: np.ndarray
    rgb: np.ndarray
    z: np.ndarray
    pipe: np.ndarray
    z_bits: int = Z_BITS

    def __post_init__(self) -> None:
        self.addr = np.ascontiguousarray(self.addr, dtype=np.int64)
        self.rgb = np.ascontiguousarray(self.rgb, dtype=np.int64)
        self.z = np.ascontiguousarray(self.z, dtype=np.int64)
        self.pipe = np.ascontiguousarray(self.pipe, dtype=np.int64)

    def __len__(self) -> int:
        return int(self.addr.shape[0])

    def validate(self, *, n_pipes: int = 2) -> None:
        """Raise :class:`RasterhwError` if any field is out of range for the hardware."""
        n = len(self)
        for name in ("rgb", "z", "pipe"):
            if getattr(self, name).shape != (n,):
                raise RasterhwError(f"pixel stream: {name} has shape {getattr(self, name).shape}, expected ({n},)")
        size = self.width * self.height
        if n and (self.addr.min() < 0 or self.addr.max() >= size):
            bad = int(self.addr[(self.addr < 0) | (self.addr >= size)][0])
            raise RasterhwError(f"pixel stream: address {bad} outside the {self.width}x{self.height} frame")
        if n and (self.z.min() < 0 or self.z.max() >= (1 << self.z_bits)):
            bad = int(self.z[(self.z < 0) | (self.z >= (1 << self.z_bits))][0])
            raise RasterhwError(f"pixel stream: Z value {bad} does not fit in {self.z_bits} bits")
        if n and (self.rgb.min() < 0 or self.rgb.max() >= (1 << RGB_BITS)):
            raise RasterhwError(f"pixel stream: an RGB value does not fit in {RGB_BITS} bits")
        if n and (self.pipe.min() < 0 or self.pipe.max() >= n_pipes):
            raise RasterhwError(f"pixel stream: pipeline index outside 0..{n_pipes - 1}")
