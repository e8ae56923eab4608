"""SNU pixel-bus word packing: the one place golden pixel writes become the words the HDL's
pipeline ports carry (``bank_write_layout``: ``addr`` from bit 0, then ``rgb``, then ``z``)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.snu.formats import RGB_BITS
from rasterhw.golden_model.snu.pixelstream import PixelStream

__all__ = ["payload_words"]


def payload_words(stream: PixelStream, idx: np.ndarray, addr_bits: int) -> list[int]:
    """The pixel writes ``idx`` of ``stream`` as port payloads ``z << (RGB + A) | rgb << A | addr``."""
    zs = RGB_BITS + addr_bits
    return [(int(z) << zs) | (int(c) << addr_bits) | int(a) for a, c, z in
            zip(stream.addr[idx].tolist(), stream.rgb[idx].tolist(), stream.z[idx].tolist(), strict=True)]
