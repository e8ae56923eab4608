"""The SLP's set-up (ASL creation) as ``hdl/experts/slp_setup.py`` does it: its words and its cycles.

Seed 000, 3.2: "SLPにおけるASL作成の処理は、以後のインクリメンタルな計算のための各種の増分値の計算を
含んだりするため、乗除算の高速化を行なう必要がある。そこでSLPには、加減算およびシフト演算を行なう
ALU ... の他に、乗算器、および逆数表(ROMによる)を装備した". The set-up turns a PL triangle (three
vertices in PL order: x, y in Q10.6, z, i words) into the triangle word the SLP's list work takes
(``slp_cycles.tri_words``): the vertices sorted top / middle / bottom, the first and last line,
which edge is left, the edge increments of x, z, i (eq. (1'): one division per edge, ``dY`` the
divisor), eq. (3)'s dz/dx and di/dx (numerator and denominator with the multiplier, one division)
and the A.J. slopes dx/dy and dy/dx of each edge. Every division is the SLP's
``formats.rom_div``: multiply by the reciprocal ``R = round(2**S / |d|)``.

**The reciprocal ROM** (its size is ours: the paper says only "逆数表(ROMによる)"): ``2**15`` words of
16 bits, ``ROM[m - 2**15] = round(2**31 / m)`` for the normalised 16-bit mantissa ``m`` of the
divisor (its top 16 bits, leading one at bit 15; ``2**16`` stored as ``2**16 - 1``): one 32K x 16
ROM, two 32K x 8 chips. For a divisor of at most 16 bits the ROM word is the exact reciprocal; the
eq. (3) denominator has up to 36 bits, so the ROM word is only within 2 of it. The SLP then
corrects with the multiplier and the ALU: ``R := ROM + 1``, ``e := 2**S + |d| // 2 - R |d|`` (one
multiply), and while ``e < 0``: ``R -= 1``, ``e += |d|`` (one ALU cycle each, at most 3, proven in
the docstring of :func:`recip` and tested). The result is exactly ``formats.recip_rom``'s ``R``,
so the set-up gives the golden bit model's words bit for bit.

Cycles of one PL triangle (every term; one multiplier, one multiply a cycle):

* ``1``: take the PL word; sort the vertices on y (stable), first and last line, band test;
* out of the band: ``1`` (the word with ``t``, ``r0``, ``r1`` only: the list work's Y-sort drops it);
* in the band: ``6`` (eq. (3): the denominator, z and i numerators, two multiplies each)
  ``+ 7 reciprocals`` (``dY`` and ``dX`` of each edge, the denominator), each ``2 + c`` (``c``
  corrections) ``+ 17`` multiply-and-rounds (per edge x, z, i increments, dx/dy and dy/dx; dz/dx,
  di/dx) ``+ 1`` (the word out).

The paper's datapath (``extra`` 0): the one multiplier is 16 x 16 (seed 000 3.2: "SLP、PXPの基本演算
データ幅は16ビットである"), so a product wider than 16 x 16 is a multi-word product, one 16 x 16
partial product a cycle (``hdl/experts/slp_setup.py: LIMBS``): eq. (3)'s six products and every
edge's multiply-and-round are 16 x 16 (one cycle, as ours); each edge's reciprocal remainder
``|d| (ROM + 1)`` is 1 x 2 limbs (``+1``), the denominator's 3 x 2 (``+5``), dz/dx and di/dx 3 x 1
(``+2`` each): ``+ 15`` cycles a triangle in the band (:data:`MULTIWORD`).
"""

from __future__ import annotations

from functools import cache

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import ACC_EXTRA, SLOPE_FRAC, X_FRAC

__all__ = ["ROM_INDEX_BITS", "MULTIWORD", "rom_table", "recip", "pl_words", "set_up_triangle", "band_setup", "EDGES"]

ROM_INDEX_BITS = 15
#: the three edges: (name, from vertex, to vertex), vertices sorted top (0), middle (1), bottom (2)
EDGES = (("ac", 0, 2), ("ab", 0, 1), ("bc", 1, 2))
_MAX16 = (1 << 16) - 1
#: the paper's datapath: the extra cycles of the multi-word products of one triangle in the band
#: (six edge reciprocals 1 each, the denominator's 5, dz/dx and di/dx 2 each)
MULTIWORD = 6 * 1 + 5 + 2 * 2
_S7 = (1 << 15) - 1


@cache
def rom_table() -> np.ndarray:
    """The reciprocal ROM: ``2**15`` words, ``round(2**31 / m)`` for ``m = 2**15 ..  2**16 - 1`` (16 bits)."""
    m = np.arange(1 << ROM_INDEX_BITS, 1 << (ROM_INDEX_BITS + 1), dtype=np.int64)
    return np.minimum(((1 << 31) + m // 2) // m, _MAX16)


def recip(d: int) -> tuple[int, int, int]:
    """``|d| -> (R, S, corrections)``: ``formats.recip_rom`` from the ROM, one multiply and the ALU.

    With ``|d| = m 2**k + r`` (``m`` the 16-bit mantissa, ``0 <= r < 2**k``) and ``t = 2**S / |d|``:
    ``2**31 / (m + 1) < t <= 2**31 / m``, so ``round(t)`` lies in ``ROM[m] - 2 .. ROM[m] + 1``
    (``2**31 / m - 2**31 / (m + 1) < 2`` for ``m >= 2**15``); starting at ``ROM[m] + 1``, at most
    three decrements.
    """
    d = abs(int(d))
    if d == 0:
        return 0, 15, 0
    bl = d.bit_length()
    s = 15 + bl
    m = d >> (bl - 16) if bl > 16 else d << (16 - bl)
    r = int(rom_table()[m - (1 << ROM_INDEX_BITS)]) + 1
    e = (1 << s) + d // 2 - r * d
    c = 0
    while e < 0:
        r -= 1
        e += d
        c += 1
    return min(r, _MAX16), s, c


def _md(num: int, r: int, s: int, dneg: bool, shift: int) -> int:
    """``formats.rom_div`` with the reciprocal ``(r, s)`` of a divisor of sign ``dneg``."""
    q = ((abs(num) * r << shift) + (1 << (s - 1))) >> s
    return -q if (num < 0) != dneg else q


def _sat16(v: int) -> int:
    return max(-(1 << 15), min(_S7, v))


def pl_words(st) -> list[dict]:
    """The PL triangles the set-up takes (the bit model's kept triangles, vertices in PL order):
    ``t``, ``x0 y0 z0 i0 .. x2 y2 z2 i2``, ``hue`` (R, G, B 3 bits each), ``poly``."""
    inv = np.argsort(st.order, axis=1)          # PL vertex j is sorted vertex inv[k, j]
    out = []
    for t in range(st.n):
        w = {"t": t, "hue": int((int(st.hue[t][0]) << 6) | (int(st.hue[t][1]) << 3) | int(st.hue[t][2])),
             "poly": int(st.poly[t])}
        for j in range(3):
            r = int(inv[t, j])
            w.update({f"x{j}": int(st.X[r, t]), f"y{j}": int(st.Y[r, t]), f"z{j}": int(st.Z[r, t]),
                      f"i{j}": int(st.Iv[r, t])})
        out.append(w)
    return out


def set_up_triangle(pl: dict, band: tuple[int, int], height: int, extra: int = ACC_EXTRA) -> tuple[dict, int]:
    """One PL triangle through the set-up: its triangle word (``slp_cycles.tri_words``' fields;
    out of the band only ``t``, ``r0``, ``r1``) and its cycles (:data:`__doc__`)."""
    v = sorted(range(3), key=lambda j: pl[f"y{j}"])      # stable: equal y keep PL order
    X = [pl[f"x{j}"] for j in v]
    Y = [pl[f"y{j}"] for j in v]
    Z = [pl[f"z{j}"] for j in v]
    Iv = [pl[f"i{j}"] for j in v]
    g, half = 1 << X_FRAC, 1 << (X_FRAC - 1)
    r0 = max((Y[0] + half - 1) >> X_FRAC, 0)
    r1 = min(((Y[2] + half - 1) >> X_FRAC) - 1, height - 1)
    assert g == 64
    w = {"t": pl["t"], "r0": r0, "r1": r1}
    if extra == 0 and not all(0 <= a <= _MAX16 for a in X + Y):
        raise RasterhwError(f"experts: the paper's datapath holds a vertex x, y in one 16-bit word (Q10.6, "
                            f"0..{_MAX16}); PL triangle {pl['t']} has x {X}, y {Y}")
    if not (r1 >= band[0] and r0 < band[1]):
        return w, 2

    def plane(A):
        return (Y[1] - Y[2]) * (A[0] - A[1]) - (Y[0] - Y[1]) * (A[1] - A[2])
    den, nz, ni = plane(X), plane(Z), plane(Iv)
    cyc = 1 + 6
    sh = X_FRAC + extra           # the paper's datapath (extra 0): each increment one saturated 16-bit word
    inc = _sat16 if extra == 0 else (lambda v: v)
    for e, i, j in EDGES:
        dX, dY = X[j] - X[i], Y[j] - Y[i]
        r, s, c = recip(dY)
        cyc += 2 + c + 4
        w[f"inc_{e}"] = inc(_md(dX, r, s, dY < 0, sh))
        w[f"zinc_{e}"] = inc(_md(Z[j] - Z[i], r, s, dY < 0, sh))
        w[f"iinc_{e}"] = inc(_md(Iv[j] - Iv[i], r, s, dY < 0, sh))
        w[f"s_{e}"] = _sat16(_md(dX, r, s, dY < 0, SLOPE_FRAC))
        r, s, c = recip(dX)
        cyc += 2 + c + 1
        w[f"q_{e}"] = _S7 if dX == 0 else _sat16(_md(dY, r, s, dX < 0, SLOPE_FRAC))
    r, s, c = recip(den)
    cyc += 2 + c + 2 + 1 + (MULTIWORD if extra == 0 else 0)
    w.update({"ll": int(den > 0), "xa": X[0], "ya": Y[0], "xb": X[1], "yb": Y[1], "za": Z[0], "zb": Z[1],
              "ia": Iv[0], "ib": Iv[1], "dzdx": _sat16(_md(nz, r, s, den < 0, 6 + 4)),
              "didx": _sat16(_md(ni, r, s, den < 0, 6)), "hue": pl["hue"], "poly": pl["poly"]})
    return w, cyc


def band_setup(pls: list[dict], band: tuple[int, int], height: int, extra: int = ACC_EXTRA) -> dict:
    """Every PL triangle of the frame through one SLP's set-up for its band: the triangle words in
    PL order, the cycles of each and in all (``cycles``), and how many were in the band."""
    words, cyc = [], []
    for pl in pls:
        w, c = set_up_triangle(pl, band, height, extra)
        words.append(w)
        cyc.append(c)
    return {"words": words, "tri_cycles": cyc, "cycles": int(sum(cyc)),
            "in_band": int(sum(1 for c in cyc if c > 2))}
