"""Stream words as packed bytes: a stimulus of millions of words without a Python int per word.

A port's words in a :class:`~rasterhw.sim.testbench.Stimulus` are either a list of ints or a
*packed* array: ``(N, k)`` uint8, one row per word, the word's value big-endian in ``k`` bytes
(``k`` = the payload's bytes, rounded up). :func:`pack_fields` makes one from NumPy columns (a
70-bit pixel write does not fit a NumPy integer, so the fields are shifted into two 64-bit
limbs); :func:`records` prepends each word's idle gap and gives the bytes the Verilator engine's
sources read with ``$fread`` (``rasterhw_stream_source``, ``BINARY=1``); :func:`as_ints` turns
either form into ints (pysim, small runs).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["as_bytes", "as_ints", "pack_fields", "records"]

_LIMB = 64
_U = np.uint64


def _nbytes(bits: int) -> int:
    return max(1, -(-bits // 8))


def pack_fields(fields: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """``fields``: ``(values, bits)`` columns, the most significant first (each ``0 <= values <
    2**bits``, ``bits`` <= 64, at most 128 bits in all) -> the words ``{fields...}`` packed,
    ``(N, ceil(total / 8))`` uint8 big-endian (a view of a ``(N, 16)`` array)."""
    total = sum(b for _, b in fields)
    if total > 2 * _LIMB or any(not 0 < b <= _LIMB for _, b in fields):
        raise RasterhwError(f"pack_fields: fields of 1..64 bits, 128 bits in all, not {[b for _, b in fields]}")
    n = len(fields[0][0]) if fields else 0
    limbs = np.zeros((n, 2), ">u8")   # {hi, lo}, big-endian: the bytes are the packed word
    hi, lo = np.zeros(n, _U), np.zeros(n, _U)
    used = 0   # bits packed so far; hi stays zero while they fit lo
    for values, b in fields:
        v = np.asarray(values)
        if v.shape != (n,):
            raise RasterhwError(f"pack_fields: a column of shape {v.shape}, expected ({n},)")
        if n and (int(v.min()) < 0 or (b < _LIMB and int(v.max()) >> b)):
            raise RasterhwError(f"pack_fields: a value does not fit {b} bits")
        v = v.view(_U) if v.dtype == np.int64 else v.astype(_U)   # non-negative: the same bits
        if b == _LIMB:
            hi, lo = lo, v.copy()
        else:
            if used + b > _LIMB:
                hi <<= _U(b)
                hi |= lo >> _U(_LIMB - b)
            lo <<= _U(b)
            lo |= v
        used += b
    limbs[:, 0], limbs[:, 1] = hi, lo
    return limbs.view(np.uint8)[:, 16 - _nbytes(total):]


def as_bytes(words, bits: int) -> np.ndarray:
    """A port's words (ints or packed) as packed ``(N, ceil(bits / 8))`` uint8 rows."""
    k = _nbytes(bits)
    if isinstance(words, np.ndarray):
        if words.ndim != 2 or words.dtype != np.uint8 or words.shape[1] != k:
            raise RasterhwError(f"packed words must be (N, {k}) uint8 for {bits} bits, not {words.dtype} {words.shape}")
        return words
    if bits <= _LIMB:
        return pack_fields([(np.asarray(words, dtype=_U), bits)]) if len(words) else np.zeros((0, k), np.uint8)
    return np.frombuffer(b"".join(int(w).to_bytes(k, "big") for w in words), np.uint8).reshape(len(words), k)


def as_ints(words) -> list[int]:
    """A port's words (ints or packed rows) as a list of ints."""
    if not isinstance(words, np.ndarray):
        return list(words)
    raw, k = words.tobytes(), words.shape[1]
    return [int.from_bytes(raw[i:i + k], "big") for i in range(0, len(raw), k)]


def records(payload: np.ndarray, bits: int, gaps, gap_bits: int) -> np.ndarray:
    """Packed ``payload`` words of ``bits`` bits with each word's gap on top: ``(N, R)`` uint8, the
    value ``gap << bits | word`` big-endian in ``R = ceil((gap_bits + bits) / 8)`` bytes (what
    ``$fread`` fills a ``gap_bits + bits``-wide memory word from)."""
    n, k = payload.shape
    g = np.asarray(gaps, dtype=np.int64)
    if g.shape != (n,):
        raise RasterhwError(f"records: {g.size} gaps for {n} words")
    if n and (g.min() < 0 or g.max() >= 1 << gap_bits):
        raise RasterhwError(f"gaps must lie in 0..{(1 << gap_bits) - 1}")
    if n and bits % 8 and int(payload[:, 0].max()) >> (bits % 8):
        raise RasterhwError(f"records: a word does not fit {bits} bits")
    r = _nbytes(gap_bits + bits)
    out = np.zeros((n, r), np.uint8)
    out[:, r - k:] = payload
    # the gap starts at bit `bits`: byte `bits // 8` from the right, shifted by `bits % 8`
    v = g.astype(_U) << _U(bits % 8)
    for j in range(_nbytes(gap_bits + bits % 8)):
        col = r - 1 - (bits // 8 + j)
        if col >= 0:
            out[:, col] |= ((v >> _U(8 * j)) & _U(255)).astype(np.uint8)
    return out
