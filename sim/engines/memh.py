"""Reading ``$writememh`` dumps into NumPy in one pass (the benches' frame dumps: up to millions of
words, where a Python ``int(word, 16)`` per word costs seconds)."""

from __future__ import annotations

import binascii
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["read_memh", "memh_uint64"]


def read_memh(path: str | Path, n: int | None = None) -> np.ndarray:
    """The words of a ``$writememh`` dump as big-endian bytes, ``(words, bytes)`` uint8.

    The usual dump (one word per line, all lines as wide, no comments or ``@`` addresses) is
    decoded as one array in C; anything else goes line by line (comments and addresses skipped,
    short words zero-extended). ``n``: the number of words expected. A word with X or Z digits,
    or a count other than ``n``, is a :class:`RasterhwError` naming the file.
    """
    raw = Path(path).read_bytes()
    k = raw.find(b"\n")
    if k > 0 and len(raw) % (k + 1) == 0 and raw[k::k + 1] == b"\n" * (len(raw) // (k + 1)) \
            and b"/" not in raw and b"@" not in raw:
        digits = np.frombuffer(raw, np.uint8).reshape(-1, k + 1)[:, :k]
    else:
        lines = [ln.strip() for ln in raw.split(b"\n")]
        lines = [ln for ln in lines if ln and not ln.startswith((b"//", b"@"))]
        k = max((len(ln) for ln in lines), default=1)
        digits = np.frombuffer(b"".join(ln.rjust(k, b"0") for ln in lines), np.uint8).reshape(-1, k)
    if k % 2:   # whole bytes: one leading zero digit
        digits = np.concatenate([np.full((digits.shape[0], 1), ord("0"), np.uint8), digits], axis=1)
    if n is not None and digits.shape[0] != n:
        raise RasterhwError(f"{path}: {digits.shape[0]} words, expected {n}")
    try:
        return np.frombuffer(binascii.unhexlify(digits.tobytes()), np.uint8).reshape(digits.shape[0], -1)
    except binascii.Error:
        raise RasterhwError(f"{path}: the dump holds X or Z bits (or is not hex)") from None


def memh_uint64(b: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Bytes ``lo:hi`` (at most 8, big-endian) of every word of :func:`read_memh` as uint64."""
    if not 0 < hi - lo <= 8:
        raise ValueError(f"a uint64 holds 1..8 bytes, not {hi - lo}")
    pad = np.zeros((b.shape[0], 8), np.uint8)
    pad[:, 8 - (hi - lo):] = b[:, lo:hi]
    return pad.view(">u8")[:, 0].astype(np.uint64)
