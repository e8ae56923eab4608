"""SNU pixel-bus word packing: the one place golden pixel writes become the words the HDL's
pipeline ports carry (``bank_write_layout``: ``addr`` from bit 0, then ``rgb``, then ``z``)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.snu.formats import RGB_BITS
from rasterhw.golden_model.snu.pixelstream import PixelStream

__all__ = ["payload_fields"]


def payload_fields(stream: PixelStream, idx: np.ndarray, addr_bits: int) -> list[tuple[np.ndarray, int]]:
    """The pixel writes ``idx`` of ``stream`` as ``(column, bits)`` fields, most significant first:
    ``z``, ``rgb``, ``addr`` (for packing millions of words without a Python int each)."""
    return [(stream.z[idx], stream.z_bits), (stream.rgb[idx], RGB_BITS), (stream.addr[idx], addr_bits)]
