"""Number formats of the matrix-pipeline generator: the one place its widths live.

The geometry processor broadcasts each triangle as three edge equations and its surface
parameters as linear functions (seed 002: "многоугольников, заданных в форме линейных
уравнений и функций"). Every video processor ``(a, b)`` of a ``p x q`` matrix rewrites the edge
coefficients for its own sparse lattice (``A' = pA, B' = qB, C' = C + aA + bB``) and then only
adds them. The widths below are what those integers need on the largest raster we accept.

Edge equations (exact integers, no rounding anywhere)
------------------------------------------------------
Vertices are snapped to ``1 / 2**SUBPIXEL_BITS`` px (``golden_model/screen.py``). For the edge
from ``(Xa, Ya)`` to ``(Xb, Yb)`` (sub-pixel units, ``dx = Xb - Xa``, ``dy = Yb - Ya``) and a
pixel with integer indices ``(x, y)`` (centre at ``x + 0.5, y + 0.5``)::

    E(x, y) = A*x + B*y + C,   A = -2**S * dy,  B = 2**S * dx,
                               C = dx*(2**(S-1) - Ya) - dy*(2**(S-1) - Xa)

which is the reference rasteriser's edge function at the pixel centre, bit for bit
(``S = SUBPIXEL_BITS``). Coefficients are multiplied by the sign of the area so that the
interior is ``E >= thr`` (``thr = 0`` on a top or left edge, 1 otherwise: the top-left rule).

* ``A, B``: signed ``EDGE_AB_BITS`` (``|A| <= 2**S * |dy|``);
* ``A' = pA``, ``B' = qB``: signed ``EDGE_AB_BITS + MATRIX_LOG2_MAX``;
* ``E``, ``C``, ``C'`` and every window corner value: signed ``EDGE_BITS``.

Surface parameters
------------------
Depth in the bit-accurate layer is the quantised depth ``zq`` (``z_bits`` wide, 0 = near) as a
plane over the processor's sparse lattice, ``Z(u, v) = Z0 + Zu*u + Zv*v`` in fixed point with
``Z_FRAC_BITS`` fraction bits (``Z_ACC_BITS`` signed for ``z_bits = 24``, the default). The value compared is ``clamp(Z >> Z_FRAC_BITS, 0,
2**z_bits - 1)``; the Z test is ``z_new < z_stored``, as everywhere. The float layer uses the
reference rasteriser's own barycentric arithmetic (linear functions of the edge values, summed
in the same order), so its image equals the reference bit for bit.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS

__all__ = [
    "COORD_BITS",
    "EDGE_AB_BITS",
    "EXT_BITS",
    "TRI_BITS",
    "UV_BITS",
    "EDGE_BITS",
    "MATRIX_LOG2_MAX",
    "MAX_RASTER_BITS",
    "SUBPIXEL_BITS",
    "Z_ACC_BITS",
    "Z_BITS_MAX",
    "Z_FRAC_BITS",
    "check_signed",
    "parse_matrix",
    "sparse_geometry",
]

#: largest full raster side: 2**MAX_RASTER_BITS px (4096)
MAX_RASTER_BITS = 12
#: largest matrix side: p, q <= 2**MATRIX_LOG2_MAX (64)
MATRIX_LOG2_MAX = 6
#: snapped coordinates lie in [-2**(MAX_RASTER_BITS + SUBPIXEL_BITS), ...]; dx, dy one bit more
_DELTA_BITS = MAX_RASTER_BITS + SUBPIXEL_BITS + 2
#: A = -2**S*dy, B = 2**S*dx (signed)
EDGE_AB_BITS = _DELTA_BITS + SUBPIXEL_BITS
#: E, C, C' and window-corner values (signed): |dx*(y) - dy*(x)| plus the aperture growth
EDGE_BITS = 2 * _DELTA_BITS + 3
#: snapped vertex coordinates and bounding boxes (signed, sub-pixel units; |x| <= 2**13 px accepted)
COORD_BITS = 13 + SUBPIXEL_BITS + 2
#: triangle index in the local memory; all ones marks an empty pixel
TRI_BITS = 16
#: sparse pixel coordinates u, v (a sparse raster is at most 2**MAX_RASTER_BITS on a side)
UV_BITS = MAX_RASTER_BITS + 1
#: aperture growth (|A| alpha + |B| beta) / 2, unsigned, for apertures up to 15 px
EXT_BITS = EDGE_AB_BITS + 4
#: quantised depth is at most 32 bits wide
Z_BITS_MAX = 32
#: fraction bits of the fixed-point depth plane
Z_FRAC_BITS = 16
#: depth accumulator (signed): z_bits + 1 bits of slope per px times 2**MAX_RASTER_BITS px, the
#: fraction, and a sign (the plane may run past 0..2**z_bits outside the triangle)
Z_ACC_BITS = 24 + 2 + MAX_RASTER_BITS + Z_FRAC_BITS + 2


def check_signed(name: str, values: np.ndarray, bits: int) -> None:
    """Raise :class:`RasterhwError` if any of ``values`` does not fit ``bits`` signed bits."""
    v = np.asarray(values)
    if v.size == 0:
        return
    lim = 1 << (bits - 1)
    lo, hi = int(v.min()), int(v.max())
    if lo < -lim or hi >= lim:
        raise RasterhwError(f"sparse: {name} needs more than {bits} signed bits ({lo}..{hi})")


def _pow2(name: str, v) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise RasterhwError(f"sparse: {name} must be an integer, not {v!r}")
    v = int(v)
    if v < 1 or v & (v - 1):
        raise RasterhwError(f"sparse: {name} must be a power of two >= 1, not {v}")
    return v


def parse_matrix(matrix) -> tuple[int, int]:
    """``"PxQ"`` or ``(p, q)`` -> ``(p, q)``, both powers of two in 1..2**MATRIX_LOG2_MAX."""
    if isinstance(matrix, str):
        parts = matrix.lower().split("x")
        if len(parts) != 2 or not all(s.strip().isdigit() for s in parts):
            raise RasterhwError(f"sparse: matrix must look like PxQ (e.g. 4x4), not {matrix!r}")
        p, q = (int(s) for s in parts)
    else:
        try:
            p, q = matrix
        except (TypeError, ValueError):
            raise RasterhwError(f"sparse: matrix must be 'PxQ' or (p, q), not {matrix!r}") from None
    p, q = _pow2("p", p), _pow2("q", q)
    lim = 1 << MATRIX_LOG2_MAX
    if p > lim or q > lim:
        raise RasterhwError(f"sparse: p and q must be at most {lim}, not {p}x{q}")
    return p, q


def sparse_geometry(width: int, height: int, p: int, q: int) -> int:
    """Check that a ``p x q`` matrix tiles ``width x height`` with square sparse rasters;
    return ``n`` (each processor's sparse raster is ``2**n x 2**n``).

    The paper's full raster is ``p*2**n x q*2**n`` ("полный дискретный растр составляет
    p2^n x q2^n пикселов"): the sparse raster is square and a power of two on a side, and the
    recursive search needs at least one level (``n >= 1``).
    """
    p, q = parse_matrix((p, q))
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise RasterhwError(f"sparse: {name} must be a positive integer, not {v!r}")
    if width % p or height % q:
        raise RasterhwError(f"sparse: a {p}x{q} matrix does not divide a {width}x{height} raster")
    sw, sh = width // p, height // q
    if sw != sh:
        raise RasterhwError(f"sparse: the sparse raster must be square (2^n x 2^n); "
                            f"{width}x{height} on {p}x{q} gives {sw}x{sh}")
    if sw & (sw - 1):
        raise RasterhwError(f"sparse: the sparse raster side must be a power of two, not {sw} "
                            f"({width}x{height} on {p}x{q})")
    n = sw.bit_length() - 1
    if n < 1:
        raise RasterhwError(f"sparse: n must be >= 1 (a {sw}x{sh} sparse raster has no levels to search)")
    if width > 1 << MAX_RASTER_BITS or height > 1 << MAX_RASTER_BITS:
        raise RasterhwError(f"sparse: the full raster may be at most {1 << MAX_RASTER_BITS} px on a side")
    return n
