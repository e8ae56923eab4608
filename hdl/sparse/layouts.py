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

__all__ = ["BROADCAST", "RECORD", "Z_FRAC_BITS_HDL"]

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

#: what travels between the levels: a triangle header (``hdr = 1``: the processor's own edge
#: and depth increments) followed by its windows (``hdr = 0``: corner values at the window's
#: first sparse pixel)
RECORD = data.StructLayout({
    "hdr": unsigned(1),
    "E": data.ArrayLayout(signed(EDGE_BITS), 3),        # window: edge values at (u, v)
    "z": signed(Z_ACC_BITS),                            # window: depth at (u, v), Q.16
    "u": unsigned(UV_BITS),                             # window: first sparse pixel
    "v": unsigned(UV_BITS),
    "Ap": data.ArrayLayout(signed(EDGE_AB_BITS + MATRIX_LOG2_MAX), 3),  # header: p*A
    "Bp": data.ArrayLayout(signed(EDGE_AB_BITS + MATRIX_LOG2_MAX), 3),  # header: q*B
    "ext": data.ArrayLayout(unsigned(EXT_BITS), 3),     # header: (|A| alpha + |B| beta) / 2
    "thr": data.ArrayLayout(unsigned(1), 3),            # header
    "bbox": data.ArrayLayout(signed(COORD_BITS), 4),    # header
    "zu": signed(Z_ACC_BITS),                           # header: p*zx
    "zv": signed(Z_ACC_BITS),                           # header: q*zy
    "tri": unsigned(TRI_BITS),                          # header
})
