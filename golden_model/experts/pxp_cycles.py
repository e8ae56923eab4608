"""The PXP HDL's golden side: its input records, its pixels and its exact cycle count.

``hdl/experts/pxp.py`` resolves depth segment by segment into a line depth buffer kept beside
the DSLB (a Z-buffer of one range of one line): for every segment of the clipped ASL it computes
the start values at its first owned pixel with the multiplier, steps z and i, and keeps a pixel
when its 16-bit z key is smaller than the stored one, or equal with a lower ASB address -- the
golden depth search's rule, so the pixels equal the bit model's (tested). Its cycle count is its
own (below), not the span-cull / depth-search operation count of :mod:`pxp`.

The DSLB has two banks: the resolve side (clear, segments, token, hand-over) works on one while
the drain side (read, offer; with A.J. read, segment table, blend/offer) empties the other. Cycles,
the input always valid and the output always ready, are in :func:`schedule`: per line the resolve
side takes ``G + sum(2 + 2 n) + 1`` (clear the G pixels, per segment accept + start values and
read + compare/write per owned pixel, the end-of-line token), then one hand-over cycle, waiting
while the drain side is still busy with the line before; the drain takes ``2 R`` (``3 G`` plus one
at the frame's right edge with A.J.).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.experts.formats import ADDR_BITS
from rasterhw.golden_model.experts.model import ExpertsFrame
from rasterhw.golden_model.experts.pxp import pixel_words

__all__ = ["SEG_FIELDS", "line_segments", "line_pixels", "line_cycles", "ADDR_BITS"]

SEG_FIELDS = ("xl", "xr", "zl", "il", "dzdx", "didx", "hue", "addr", "poly", "sl", "ql", "sr", "qr")


def guarded(lo: int, hi: int, width: int, aj: str) -> tuple[int, int]:
    """The pixels a PXP resolves: its range, plus one guard pixel each side with A.J."""
    return (max(lo - 1, 0), min(hi + 1, width)) if aj == "c" else (lo, hi)


def line_segments(fr: ExpertsFrame, y: int, lo: int, hi: int, *, aj: str = "none") -> list[dict]:
    """The segments the SLP's block lists hand the PXP of ``[lo, hi)`` on line ``y``, in ASL order
    (with A.J., those reaching its guard pixels too)."""
    lo, hi = guarded(lo, hi, fr.width, aj)
    if fr.model != "bit":
        raise ValueError("the PXP HDL's golden side needs the bit model")
    rec, st = fr.records, fr.setup
    if st.n >= (1 << ADDR_BITS) - 1 or (st.n and int(st.poly.max()) >= (1 << ADDR_BITS) - 1):
        raise ValueError(f"{st.n} triangles do not fit the {ADDR_BITS}-bit ASB address / polygon number")
    sel = np.flatnonzero((rec.row == y) & (rec.c1 >= lo) & (rec.c0 <= hi - 1) & (rec.c1 >= rec.c0))
    sel = sel[np.lexsort((rec.tri[sel], rec.xl[sel]))]
    return [asb_record(rec, st, r) for r in sel]


def asb_record(rec, st, r: int) -> dict:
    """Record ``r`` of the frame as the PXP receives it (one ASB: ends, left depth and intensity,
    slopes, 9-bit hue, ASB address, polygon, the A.J. end values)."""
    t = int(rec.tri[r])
    h = st.hue[t]
    return {"xl": int(rec.xl[r]), "xr": int(rec.xr[r]), "zl": int(rec.zl[r]), "il": int(rec.il[r]),
            "dzdx": int(st.dzdx[t]), "didx": int(st.didx[t]),
            "hue": int((h[0] << 6) | (h[1] << 3) | h[2]), "addr": t, "poly": int(st.poly[t]),
            "sl": int(rec.sl[r]), "ql": int(rec.ql[r]), "sr": int(rec.sr[r]), "qr": int(rec.qr[r])}


def line_pixels(fr: ExpertsFrame, y: int, lo: int, hi: int) -> list[int]:
    """The bit model's pixel words (after A.J. if the frame has it) of ``[lo, hi)`` on line ``y``."""
    if fr.aj not in ("none", "c"):
        raise ValueError("the PXP HDL has A.J. method (c) only")
    w = pixel_words(fr.setup, fr.fields).reshape(fr.height, fr.width)
    return [int(v) for v in w[y, lo:hi]]


def resolve_cycles(segs: list[dict], lo: int, hi: int, *, aj: str = "none", width: int = 512) -> int:
    """Resolve-side cycles of one line before its hand-over: clear ``G``, ``2 + 2 n`` per segment,
    1 for the end-of-line token (``G``: the range, with A.J. plus its guard pixels)."""
    glo, ghi = guarded(lo, hi, width, aj)
    cyc = (ghi - glo) + 1
    for s in segs:
        c0 = (s["xl"] + 31) >> 6
        c1 = ((s["xr"] + 31) >> 6) - 1
        n = max(min(c1, ghi - 1) - max(c0, glo) + 1, 0)
        cyc += 2 + 2 * n
    return cyc


def drain_cycles(lo: int, hi: int, *, aj: str = "none", width: int = 512) -> int:
    """Drain-side cycles of one line: ``2 R`` without A.J.; ``3 G`` (+1 at the frame's right edge) with."""
    glo, ghi = guarded(lo, hi, width, aj)
    return 3 * (ghi - glo) + (1 if ghi == hi else 0) if aj == "c" else 2 * (hi - lo)


def schedule(lines: list[tuple[list[dict], int, int]], *, aj: str = "none", width: int = 512) -> dict:
    """Exact timing of lines ``(segments, lo, hi)`` through the PXP with its double-banked DSLB.

    Cycle 0 is line 0's first clear cycle. Resolve of line k starts at ``S_k``, hands its bank over
    at ``H_k = max(S_k + r_k, F_{k-1})`` (``F``: the first cycle the drain is free), the drain runs
    ``H_k + 1 .. H_k + d_k``; ``S_{k+1} = H_k + 1``. The finish-time counter of line k is
    ``H_k - S_k + 1``. Returns ``{"line_cycles": [...], "last_pixel": H_{N-1} + d_{N-1}}``.
    """
    s_k, free = 0, 0
    out, h = [], 0
    d = 0
    for segs, lo, hi in lines:
        r = resolve_cycles(segs, lo, hi, aj=aj, width=width)
        h = max(s_k + r, free)
        out.append(h - s_k + 1)
        d = drain_cycles(lo, hi, aj=aj, width=width)
        free = h + d + 1
        s_k = h + 1
    return {"line_cycles": out, "last_pixel": h + d}


def line_cycles(segs: list[dict], lo: int, hi: int, *, aj: str = "none", width: int = 512) -> int:
    """The finish-time counter of a line run alone (its drain bank free): resolve + hand-over."""
    return resolve_cycles(segs, lo, hi, aj=aj, width=width) + 1


def reference_line(segs: list[dict], lo: int, hi: int, *, intensity_bits: int = 7) -> list[int]:
    """Pixel words of ``[lo, hi)`` from a segment list, one pixel at a time in plain Python.

    An independent statement of the PXP's rules (for random ASLs that come from no scene): the
    covering segments of a pixel are those with ``c0 <= x <= c1``; the nearest has the smallest
    clamped 16-bit key ``((zL << 4) + ((xc - xL) dz/dx >> 6)) >> 4``, then the lowest address;
    its pixel is ``hue << I | clamp(iL + ((xc - xL) di/dx >> 6)) >> (16 - I)``; none: 0.
    """
    f = 16 - intensity_bits
    imax = ((1 << intensity_bits) - 1) << f
    out = []
    for x in range(lo, hi):
        xc = (x << 6) + 32
        best = None
        for s in segs:
            c0 = (s["xl"] + 31) >> 6
            c1 = ((s["xr"] + 31) >> 6) - 1
            if not (c0 <= x <= c1):
                continue
            d = xc - s["xl"]
            key = min(max(((s["zl"] << 4) + ((d * s["dzdx"]) >> 6)) >> 4, 0), 65535)
            if best is None or (key, s["addr"]) < best[0]:
                i = min(max(s["il"] + ((d * s["didx"]) >> 6), 0), imax)
                best = ((key, s["addr"]), (s["hue"] << intensity_bits) | (i >> f))
        out.append(0 if best is None else best[1])
    return out
