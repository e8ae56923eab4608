# amaranth: UnusedElaboratable=no
"""ZB/M sub-blocks registered for Verilog, synthesis, place and route and proofs.

``zbm-pixel``, ``zbm-loop`` and ``zbm-merger`` are parts of ``zbm-chip``; they are registered
on their own so ``rasterhw synth``/``fpga``/``prove`` can name them. The merger takes the chip's
double-Z word (:data:`rasterhw.hdl.zbm.layouts.PIXEL2`) by default; ``z_bits``/``colour_bits``
build a word of the same shape (``s0``, ``s1`` samples of ``z, a, c0..c3``) with narrower
fields, which is what the formal proof uses: the merger never looks at a bit of the word
except by comparing ``z``, so its behaviour does not depend on the widths.
"""

from __future__ import annotations

from amaranth import unsigned
from amaranth.lib import data
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.zbm.layouts import PIXEL2
from rasterhw.hdl.zbm.loop import ZbmLoop
from rasterhw.hdl.zbm.merger import ZbmMerger
from rasterhw.hdl.zbm.pixel import ZbmPixelProcessor

__all__ = ["loop", "merger", "pixel", "pixel2_layout"]


def pixel2_layout(*, z_bits: int = F.Z_BITS, colour_bits: int = F.COLOUR_BITS) -> data.StructLayout:
    """The double-Z word ``{s0, s1}`` with ``z_bits``-bit Z and ``colour_bits``-bit a, c0..c3."""
    if (z_bits, colour_bits) == (F.Z_BITS, F.COLOUR_BITS):
        return PIXEL2
    if not (isinstance(z_bits, int) and 1 <= z_bits <= F.Z_BITS):
        raise ValueError(f"z_bits must be 1..{F.Z_BITS}, not {z_bits!r}")
    if not (isinstance(colour_bits, int) and 0 <= colour_bits <= F.COLOUR_BITS):
        raise ValueError(f"colour_bits must be 0..{F.COLOUR_BITS}, not {colour_bits!r}")
    sample = data.StructLayout({"z": unsigned(z_bits),  # 0 = near, all ones = empty
                                **{c: unsigned(colour_bits) for c in ("a", "c0", "c1", "c2", "c3")}})
    return data.StructLayout({"s0": sample, "s1": sample})


def merger(*, fifo_depth: int = 16, z_bits: int = F.Z_BITS, colour_bits: int = F.COLOUR_BITS) -> ZbmMerger:
    """The chip's merger (default: its 16-word clock-crossing FIFO and the PIXEL2 word)."""
    return ZbmMerger(word_layout=pixel2_layout(z_bits=z_bits, colour_bits=colour_bits), fifo_depth=fifo_depth)


def pixel(*, index: int = 0, interleave: int = 8, width: int = F.MAX_WIDTH) -> ZbmPixelProcessor:
    """One pixel processor (defaults: processor 0 at the paper's interleave 8)."""
    return ZbmPixelProcessor(index=index, interleave=interleave, width=width)


def loop(*, interleave: int = 8, width: int = F.MAX_WIDTH) -> ZbmLoop:
    """Segment processor + 8 pixel processors (default: the paper's interleave 8)."""
    return ZbmLoop(interleave=interleave, width=width)
