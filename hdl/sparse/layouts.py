"""Stream payloads of the sparse-raster video processor. Widths come from
``golden_model/sparse/formats.py`` (the one place they live)."""

from __future__ import annotations

from amaranth.hdl import signed, unsigned
from amaranth.lib import data
from rasterhw.golden_model.sparse.formats import (
    COORD_BITS,
    EDGE_AB_BITS,
    EDGE_BITS,
    EXT_BITS,
    MATRIX_LOG2_MAX,
    TRI_BITS,
    UV_BITS,
    Z_ACC_BITS,
)

__all__ = ["BROADCAST", "BROADCAST_RGB", "HEADER", "HEADER_RGB", "WINDOW", "WINDOW_RGB", "Z_FRAC_BITS_HDL", "layouts"]

from rasterhw.golden_model.sparse.formats import Z_FRAC_BITS as Z_FRAC_BITS_HDL  # noqa: E402

#: a triangle as the geometry processor broadcasts it (``fixed.broadcast_records``)
BROADCAST = data.StructLayout({
    "A": data.ArrayLayout(signed(EDGE_AB_BITS), 3),     # -2**8 * dy, oriented; per full-raster pixel
    "B": data.ArrayLayout(signed(EDGE_AB_BITS), 3),     # 2**8 * dx
    "C": data.ArrayLayout(signed(EDGE_BITS), 3),        # edge value at the centre of pixel (0, 0)
    "thr": data.ArrayLayout(unsigned(1), 3),            # 0: top/left edge (E >= 0), 1: E >= 1
    "bbox": data.ArrayLayout(signed(COORD_BITS), 4),    # Xmin, Xmax, Ymin, Ymax, 1/256 px
    "z00": signed(Z_ACC_BITS),                          # zq at pixel (0, 0), Q.16
    "zx": signed(Z_ACC_BITS),                           # dzq/dx per full-raster pixel, Q.16
    "zy": signed(Z_ACC_BITS),                           # dzq/dy, Q.16
    "tri": unsigned(TRI_BITS),                          # triangle index (all ones reserved: empty)
})

#: what travels between the levels, on two streams: a triangle's header (the processor's own
#: increments) goes into a header FIFO just before the triangle's first window at that level;
#: windows (corner values at the window's first sparse pixel) go into a window FIFO, the first
#: window of a triangle marked ``new`` (take the next header with it). A triangle with no window
#: left at a level sends nothing further.
HEADER = data.StructLayout({
    "Ap": data.ArrayLayout(signed(EDGE_AB_BITS + MATRIX_LOG2_MAX), 3),  # p*A
    "Bp": data.ArrayLayout(signed(EDGE_AB_BITS + MATRIX_LOG2_MAX), 3),  # q*B
    "ext": data.ArrayLayout(unsigned(EXT_BITS), 3),     # (|A| alpha + |B| beta) / 2
    "thr": data.ArrayLayout(unsigned(1), 3),
    "bbox": data.ArrayLayout(signed(COORD_BITS), 4),
    "zu": signed(Z_ACC_BITS),                           # p*zx
    "zv": signed(Z_ACC_BITS),                           # q*zy
    "tri": unsigned(TRI_BITS),
})

WINDOW = data.StructLayout({
    "new": unsigned(1),                                 # first window of a triangle at this level
    "E": data.ArrayLayout(signed(EDGE_BITS), 3),        # edge values at (u, v)
    "z": signed(Z_ACC_BITS),                            # depth at (u, v), Q.16
    "u": unsigned(UV_BITS),                             # first sparse pixel of the window
    "v": unsigned(UV_BITS),
})

#: colour (R, G, B) as three more linear functions, 8-bit levels with ``Z_FRAC_BITS`` fraction bits
_RGB = data.ArrayLayout(signed(Z_ACC_BITS), 3)

#: the broadcast record with the vertex colours' planes (``fixed.colour_planes``, over full-raster
#: pixel indices): value at pixel (0, 0) and the per-pixel steps; ``BROADCAST`` is its low bits
BROADCAST_RGB = data.StructLayout({**dict(BROADCAST.members), "c00": _RGB, "cx": _RGB, "cy": _RGB})

#: the header with the processor's colour steps (``cu = p*cx``, ``cv = q*cy``)
HEADER_RGB = data.StructLayout({**dict(HEADER.members), "cu": _RGB, "cv": _RGB})

#: a window with its colour at (u, v)
WINDOW_RGB = data.StructLayout({**dict(WINDOW.members), "c": _RGB})


def layouts(colour: bool) -> tuple[data.StructLayout, data.StructLayout, data.StructLayout]:
    """``(broadcast, header, window)`` layouts, with the colour planes when ``colour``."""
    return (BROADCAST_RGB, HEADER_RGB, WINDOW_RGB) if colour else (BROADCAST, HEADER, WINDOW)
