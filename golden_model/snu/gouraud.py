"""SNU graphics system: the scan-converting i860's Gouraud loop as a bit-accurate golden model.

The paper (seed 004, section 4.3) splits every polygon into convex polygons, those into
trapezoids by screen y, computes the slopes of each trapezoid's left and right sides and
interpolates colour along them, then fills scan lines with an inner loop of "pixel address
increment, colour increments, z increment, colour/z output, loop count": 6 integer adds,
1 memory access and 1 branch per pixel. Colour is 8 bits per channel when stored, but is
carried "as integers of 16 bits or more including the fraction" while interpolating.

What this module does (decisions the paper leaves open are marked *ours*; see
``docs/snu_geometry.md``):

* **coverage** -- vertices are snapped to a 1/256-pixel grid (*ours*, the same grid as the
  float reference rasteriser, ``docs/conventions.md``); each triangle is split at its middle
  vertex into a top and a bottom trapezoid; the first column of each span and the rows of
  each trapezoid are found *exactly* in integer arithmetic (an edge walker), so a pixel
  centre on an edge is decided by the top-left rule of ``golden_model/screen.py``: rows
  ``ceil(y_top - 1/2) <= row < ceil(y_bot - 1/2)``, columns ``ceil(x_l - 1/2) <= col <
  ceil(x_r - 1/2)``. This is the edge-function top-left rule, so coverage equals the float
  reference's;
* **set-up** (per triangle, in float64 as the i860's FPU would do it): the colour and Z plane
  gradients ``dA/dx``, ``dA/dy`` and, per trapezoid, the value at its *anchor* -- the first
  column of its first scan line -- are rounded to fixed point with ``frac_bits`` fraction
  bits (round half up); colour in units of one 8-bit step (``c * 255``), Z in units of one
  24-bit step of ``tris.zq``; half an output step is added to the anchor once, so the loop
  output is a plain truncation ``acc >> frac_bits`` (the store takes the register's upper
  bits, no rounding add per pixel);
* **outer loop** (per scan line): the span-start accumulators step by
  ``dA/dy + (cs(row+1) - cs(row)) * dA/dx`` (integer adds, evaluated in closed form, which is
  bit-identical because integer addition is exact), **inner loop** (per pixel): run pass by
  pass -- store, step address, r, g, b, z, count, branch -- and *counted as it runs*
  (``counts``, :data:`EXECUTED`); ``tests/snu/test_snu_gouraud.py`` checks it against a closed
  form and a literal one-pixel-at-a-time loop;
* **output** -- the 8-bit channels and the ``z_bits`` Z are the accumulators' integer parts,
  masked to their widths as the hardware store would (no clamp: no clamp is in the paper's
  8-operation loop; with ``frac_bits >= 12`` the error bound keeps every covered pixel in
  range, see :func:`error_bound_lsb`);
* **two pipelines** (*ours*): the paper has two parallel geometry + scan-conversion
  pipelines but does not say how polygons are dealt to them; triangle ``i`` goes to
  pipeline ``i % n_pipes``. The stream lists triangles in submission order, each
  triangle's pixels top to bottom, left to right; a pipeline's order is its subsequence.

Error bound (proved in ``docs/snu_geometry.md``): at a pixel ``i`` lines below and ``j``
columns from its trapezoid's anchor, ``|acc / 2**F - exact| <= 2**-(F+1) * (1 + i + |j|)``
output steps. For 1280 x 1024 and ``F = 16`` that is < 0.018, so every output is the float
value rounded half up, or one step away when the float value lies within 0.018 of a
half-step.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap
from rasterhw.golden_model.snu.pixelstream import PixelStream

__all__ = [
    "EXECUTED",
    "SUBPIXEL_BITS",
    "error_bound_lsb",
    "inner_loop_ops",
    "scan_convert",
    "scan_convert_float",
    "setup_spans",
    "stream_difference",
]

#: Vertices are snapped to 1/2**SUBPIXEL_BITS px (round half up) before coverage is decided:
#: the float reference's grid (``reference.SUBPIXEL = 256``, docs/reference.md).

#: What the inner loop executes per pixel, the keys of the ``counts`` :func:`scan_convert`
#: fills: adds on the pixel address, r, g, b, z (Q8.F colour, Q24.F Z in a 64-bit register)
#: and the pixel count, the store to the pixel bus, the loop branch.
EXECUTED = ("add_addr", "add_r", "add_g", "add_b", "add_z", "add_count", "store", "branch")

_CHANNELS = ("r", "g", "b", "z")
_MAX_COORD = float(1 << 15)  # px; keeps snapped products well inside int64


def inner_loop_ops(counts: dict) -> dict:
    """Operations per pixel from what :func:`scan_convert` executed (its ``counts``).

    Returns ``add``, ``mem``, ``branch`` and ``total`` per pixel (means over the pixels
    written), plus ``pixels`` and ``spans`` (scan lines that entered the loop).
    """
    px = counts.get("pixels", 0) if isinstance(counts, dict) else 0
    if px <= 0:
        raise RasterhwError("inner_loop_ops needs the counts of at least one pixel")
    add = sum(counts[k] for k in EXECUTED if k.startswith("add_"))
    return {"add": add / px, "mem": counts["store"] / px, "branch": counts["branch"] / px,
            "total": sum(counts[k] for k in EXECUTED) / px, "pixels": px, "spans": counts["spans"]}


def error_bound_lsb(frac_bits: int, width: int, height: int) -> float:
    """Largest possible |fixed - exact| in output steps before the final truncation.

    ``2**-(F+1) * (1 + height + width)``: anchor rounding plus at most ``height`` dy steps and
    ``width`` dx steps, each increment off by at most half a fixed-point LSB.
    """
    return 2.0 ** -(frac_bits + 1) * (1 + height + width)


# --------------------------------------------------------------------------- input checks


def _check(tris: ScreenTriangles, frac_bits, n_pipes) -> None:
    if not isinstance(tris, ScreenTriangles):
        raise RasterhwError(f"scan_convert needs ScreenTriangles, not {type(tris).__name__}")
    if isinstance(frac_bits, bool) or not isinstance(frac_bits, (int, np.integer)) or not 8 <= frac_bits <= 28:
        raise RasterhwError(f"frac_bits must be an integer in 8..28, not {frac_bits!r}")
    if isinstance(n_pipes, bool) or not isinstance(n_pipes, (int, np.integer)) or n_pipes < 1:
        raise RasterhwError(f"n_pipes must be a positive integer, not {n_pipes!r}")
    if not tris.z_far_is_zero:
        raise RasterhwError("the SNU scan converter needs zq with far = 0 (z_far_is_zero=True), got False")
    if not 1 <= tris.z_bits <= 32:
        raise RasterhwError(f"z_bits must be in 1..32, not {tris.z_bits!r}")
    tris.validate(who="SNU scan converter", max_coord=_MAX_COORD)
    t = tris.n_triangles
    col = np.asarray(tris.colour, dtype=np.float64)
    if t and not (col.min() >= 0.0 and col.max() <= 1.0):  # finite: validate() checked
        bad = col[(col < 0) | (col > 1)][0]
        raise RasterhwError(f"vertex colour {bad!r} outside [0, 1]")
    zq = np.asarray(tris.zq)
    if t and (not np.issubdtype(zq.dtype, np.integer) or zq.min() < 0 or zq.max() >= (1 << tris.z_bits)):
        bad = zq.ravel()[0] if not np.issubdtype(zq.dtype, np.integer) else zq[(zq < 0) | (zq >= (1 << tris.z_bits))][0]
        raise RasterhwError(f"zq value {bad!r} is not an integer in 0..2**{tris.z_bits}-1")


def _ceildiv(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return -((-a) // b)


# --------------------------------------------------------------------------- set-up


def setup_spans(tris: ScreenTriangles, *, frac_bits: int = 16) -> dict:
    """Trapezoid set-up and span list: everything the inner loop needs, one entry per scan line.

    Returns a dict of arrays, one element per (triangle, scan line) span in emission order:
    ``tri``, ``row``, ``col`` (first column, clipped to the frame), ``n`` (pixels, may be 0),
    ``acc`` (R, 4) int64 accumulators ``r, g, b, z`` at the span's first pixel (rounding bias
    included), ``inc`` (R, 4) int64 per-pixel increments; and per-span float64 ``plane0``
    (R, 4) value at the first pixel centre and ``grad_x`` (R, 4) for the float twin.
    """
    _check(tris, frac_bits, 1)
    f = int(frac_bits)
    s = 1 << SUBPIXEL_BITS
    half_px = s // 2
    w, h = int(tris.width), int(tris.height)
    t = tris.n_triangles

    # Snap to the sub-pixel grid (round half up, as the float reference), units of 1/s px.
    xs = snap(tris.xy).astype(np.int64)  # (T,3,2)
    attr = np.empty((t, 3, 4), dtype=np.float64)
    attr[:, :, :3] = np.asarray(tris.colour, dtype=np.float64) * 255.0
    attr[:, :, 3] = np.asarray(tris.zq, dtype=np.float64)

    order = np.argsort(xs[:, :, 1], axis=1, kind="stable")  # top vertex first
    xs = np.take_along_axis(xs, order[:, :, None], axis=1)
    attr = np.take_along_axis(attr, order[:, :, None], axis=1)
    X, Y = xs[:, :, 0], xs[:, :, 1]

    area2 = (X[:, 1] - X[:, 0]) * (Y[:, 2] - Y[:, 0]) - (X[:, 2] - X[:, 0]) * (Y[:, 1] - Y[:, 0])
    live = area2 != 0  # zero-area triangles cover nothing

    # Plane gradients in float64 on the snapped positions (output steps per pixel).
    xf, yf = X / s, Y / s
    den = np.where(live, area2 / float(s * s), 1.0)[:, None]
    da1, da2 = attr[:, 1] - attr[:, 0], attr[:, 2] - attr[:, 0]
    dx1, dx2 = (xf[:, 1] - xf[:, 0])[:, None], (xf[:, 2] - xf[:, 0])[:, None]
    dy1, dy2 = (yf[:, 1] - yf[:, 0])[:, None], (yf[:, 2] - yf[:, 0])[:, None]
    gx = (da1 * dy2 - da2 * dy1) / den  # (T,4)
    gy = (da2 * dx1 - da1 * dx2) / den

    # Trapezoids: k=0 top (v0..v1), k=1 bottom (v1..v2). Long edge v0->v2 on the right when the
    # middle vertex is left of it (area2 < 0 in y-down coordinates).
    mid_left = area2 < 0
    tri_of = np.repeat(np.arange(t), 2)
    k = np.tile(np.array([0, 1]), t)
    y_top = Y[tri_of, k]
    y_bot = Y[tri_of, k + 1]
    short_a, short_b = k, k + 1  # short edge v0->v1 or v1->v2
    long_a, long_b = np.zeros_like(k), np.full_like(k, 2)
    ml = mid_left[tri_of]
    la, lb = np.where(ml, short_a, long_a), np.where(ml, short_b, long_b)
    ra, rb = np.where(ml, long_a, short_a), np.where(ml, long_b, short_b)

    r0 = np.clip(_ceildiv(y_top - half_px, s), 0, h)
    r1 = np.clip(_ceildiv(y_bot - half_px, s), 0, h)
    nrows = np.where(live[tri_of], np.maximum(r1 - r0, 0), 0)

    # Expand trapezoids into scan lines.
    trap = np.repeat(np.arange(2 * t), nrows)
    first = np.repeat(np.cumsum(nrows) - nrows, nrows)
    i = np.arange(trap.size) - first  # line index inside the trapezoid
    tri = tri_of[trap]
    row = r0[trap] + i
    yc = row * s + half_px

    def edge_col(a_idx, b_idx):
        xa, ya = X[tri, a_idx[trap]], Y[tri, a_idx[trap]]
        xb, yb = X[tri, b_idx[trap]], Y[tri, b_idx[trap]]
        dy = yb - ya  # > 0 on every emitted line
        return _ceildiv((xa - half_px) * dy + (yc - ya) * (xb - xa), s * dy)

    cs = edge_col(la, lb)  # unclipped first column
    ce = edge_col(ra, rb)
    col = np.clip(cs, 0, w)
    n = np.maximum(np.clip(ce, 0, w) - col, 0)

    # Anchor: the first column of the trapezoid's first (clipped) line.
    first_line = np.cumsum(nrows) - nrows  # index of each trapezoid's first line
    cs0 = np.zeros(2 * t, dtype=np.int64)
    has = nrows > 0
    cs0[has] = cs[first_line[has]]
    anchor_x = (cs0 + 0.5)[trap]
    anchor_y = (r0 + 0.5)[trap]
    plane_anchor = (attr[tri, 0] + (anchor_x - xf[tri, 0])[:, None] * gx[tri]
                    + (anchor_y - yf[tri, 0])[:, None] * gy[tri])

    one = float(1 << f)
    q_gx = np.floor(gx * one + 0.5).astype(np.int64)
    q_gy = np.floor(gy * one + 0.5).astype(np.int64)
    q_anchor = np.floor(plane_anchor * one + 0.5).astype(np.int64) + (1 << (f - 1))

    # Outer loop in closed form: line i starts at anchor + i*dA/dy + (cs - cs0)*dA/dx, and the
    # first *emitted* pixel is (col - cs) further right when the span was clipped at x = 0.
    acc = q_anchor + i[:, None] * q_gy[tri] + (col - cs0[trap])[:, None] * q_gx[tri]
    plane0 = (attr[tri, 0] + (col + 0.5 - xf[tri, 0])[:, None] * gx[tri]
              + (row + 0.5 - yf[tri, 0])[:, None] * gy[tri])
    return {"tri": tri, "row": row, "col": col, "n": n, "acc": acc, "inc": q_gx[tri],
            "plane0": plane0, "grad_x": gx[tri], "frac_bits": f}


# --------------------------------------------------------------------------- scan conversion


def _expand(spans: dict) -> tuple[np.ndarray, np.ndarray]:
    n = spans["n"]
    span = np.repeat(np.arange(n.size), n)
    k = np.arange(span.size) - np.repeat(np.cumsum(n) - n, n)
    return span, k


def scan_convert(tris: ScreenTriangles, *, frac_bits: int = 16, n_pipes: int = 2,
                 counts: dict | None = None, spans: dict | None = None) -> PixelStream:
    """Bit-accurate Gouraud scan conversion of ``tris`` into the two pipelines' pixel writes.

    Parameters
    ----------
    tris : screen triangles with ``z_far_is_zero=True`` (far = 0, larger is nearer).
    frac_bits : fraction bits of the colour and Z accumulators (8..28; the paper asks for
        "16 bits or more including the fraction"; 16 is the default, see the module docstring).
    n_pipes : pipelines; triangle ``i`` is issued by pipeline ``i % n_pipes``.
    counts : if a dict, it receives what the inner loop executed (:data:`EXECUTED`, plus
        ``pixels`` and ``spans``); :func:`inner_loop_ops` turns it into operations per pixel.
    spans : ``setup_spans(tris, frac_bits=frac_bits)`` if the caller already has it (not checked
        beyond its ``frac_bits``).

    Returns
    -------
    PixelStream, triangles in submission order, each top to bottom and left to right.
    """
    _check(tris, frac_bits, n_pipes)
    f = int(frac_bits)
    if spans is None:
        spans = setup_spans(tris, frac_bits=f)
    elif spans.get("frac_bits") != f:
        raise RasterhwError(f"spans were set up with frac_bits={spans.get('frac_bits')!r}, not {f}")
    w = int(tris.width)
    out = _inner_loop(spans, w, counts)
    r, g, b = ((out[c] >> f) & 0xFF for c in ("r", "g", "b"))
    z = (out["z"] >> f) & ((1 << int(tris.z_bits)) - 1)
    return PixelStream(width=w, height=int(tris.height), addr=out["addr"],
                       rgb=(r << 16) | (g << 8) | b, z=z,
                       pipe=out["tri"] % int(n_pipes), z_bits=int(tris.z_bits))


def _inner_loop(spans: dict, w: int, counts: dict | None) -> dict:
    """Run the inner loop: in each pass every span still in the loop stores its pixel, steps its
    six registers and tests its count (vectorised across spans, one pixel per pass). Spans go
    longest first, so the spans still looping are always a prefix. ``counts`` (a dict or None)
    receives what ran (:data:`EXECUTED`, ``pixels``, ``spans``)."""
    n = spans["n"]
    order = np.argsort(-n, kind="stable")
    n_o = n[order]
    regs = {"addr": (spans["row"] * w + spans["col"])[order], "count": n_o.copy()}
    inc = {"addr": np.ones_like(n_o)}
    for c, name in enumerate(_CHANNELS):
        regs[name], inc[name] = spans["acc"][order, c].copy(), spans["inc"][order, c]
    pos = (np.cumsum(n) - n)[order]  # where each span's next pixel goes in the stream (bookkeeping)
    total = int(n.sum())
    out = {name: np.empty(total, dtype=np.int64) for name in ("addr", *_CHANNELS)}
    out["tri"] = np.repeat(spans["tri"], n)
    ran = dict.fromkeys(EXECUTED, 0)
    live = int(np.count_nonzero(n_o > 0))
    ran["spans"] = live
    while live:
        p = pos[:live]
        for name in ("addr", *_CHANNELS):  # one store: the address and the four accumulators
            out[name][p] = regs[name][:live]
        ran["store"] += live
        pos[:live] += 1
        for name in ("addr", *_CHANNELS):
            regs[name][:live] += inc[name][:live]
            ran[f"add_{name}"] += live
        regs["count"][:live] -= 1
        ran["add_count"] += live
        ran["branch"] += live  # loop while count != 0
        live = int(np.count_nonzero(regs["count"][:live] > 0))
    ran["pixels"] = total
    if counts is not None:
        counts.update(ran)
    return out


def scan_convert_float(tris: ScreenTriangles, *, n_pipes: int = 2) -> PixelStream:
    """Float twin of :func:`scan_convert`: same coverage and order, ideal arithmetic.

    Colour and Z are the float64 plane values at each pixel centre, rounded half up to
    8 bits and to ``z_bits`` and clamped -- the float reference's rounding.
    """
    _check(tris, 16, n_pipes)
    spans = setup_spans(tris, frac_bits=16)
    span, k = _expand(spans)
    w = int(tris.width)
    v = spans["plane0"][span] + k[:, None] * spans["grad_x"][span]
    q = np.floor(v + 0.5).astype(np.int64)
    rgb8 = np.clip(q[:, :3], 0, 255)
    z = np.clip(q[:, 3], 0, (1 << int(tris.z_bits)) - 1)
    return PixelStream(width=w, height=int(tris.height),
                       addr=spans["row"][span] * w + spans["col"][span] + k,
                       rgb=(rgb8[:, 0] << 16) | (rgb8[:, 1] << 8) | rgb8[:, 2], z=z,
                       pipe=spans["tri"][span] % int(n_pipes), z_bits=int(tris.z_bits))


def stream_difference(a: PixelStream, b: PixelStream) -> dict:
    """Per-write differences between two streams of the same coverage and order.

    Returns ``pixels``, ``max_abs`` per channel (``r, g, b, z``) and ``exact_fraction`` (writes
    whose RGB and Z agree exactly). Raises :class:`RasterhwError` if the addresses differ.
    """
    if len(a) != len(b) or not np.array_equal(a.addr, b.addr) or not np.array_equal(a.pipe, b.pipe):
        raise RasterhwError(f"streams differ in coverage or order ({len(a)} vs {len(b)} writes)")
    chans = {
        "r": (a.rgb >> 16) - (b.rgb >> 16),
        "g": ((a.rgb >> 8) & 0xFF) - ((b.rgb >> 8) & 0xFF),
        "b": (a.rgb & 0xFF) - (b.rgb & 0xFF),
        "z": a.z - b.z,
    }
    same = np.ones(len(a), dtype=bool)
    for d in chans.values():
        same &= d == 0
    return {
        "pixels": len(a),
        "max_abs": {c: int(np.abs(d).max()) if len(a) else 0 for c, d in chans.items()},
        "exact_fraction": float(same.mean()) if len(a) else 1.0,
    }
