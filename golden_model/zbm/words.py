"""ZB/M word packing: the one place golden values become the words the HDL ports carry.

Every bench (Amaranth pysim, cocotb, the plain-Verilator runs) builds its stimulus and reads
its results through these functions; the word layouts themselves are defined once in
:mod:`rasterhw.golden_model.zbm.formats`.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F

__all__ = ["merge_rows", "merge_words", "split_merge_words", "doublez_words", "edge_pair_rows", "edge_pair_words",
           "packets", "pixel2_words", "rows_to_samples", "segment_words", "words_to_doublez"]


def edge_pair_words(eps: G.EdgePairs) -> list[int]:
    """All edge pairs' 9 loader words, then the end-of-frame marker (EP_HEADER h = 0)."""
    return [w for i in range(len(eps)) for w in eps.words(i)] + [F.EP_HEADER.pack(y=0, h=0)]


_SLOT_MASK = np.int64((1 << F.SLOT_BITS) - 1)
_SLOT_BYTES = F.SLOT_BITS // 8                 # 7: a 56-bit slot is whole bytes
_EP_BYTES = F.EP_WORD_BITS // 8                # 21


def edge_pair_rows(eps: G.EdgePairs) -> np.ndarray:
    """:func:`edge_pair_words` (the specification; ``tests/zbm/test_zbm_words_rows.py`` holds the
    two equal) as packed rows (``sim/packed.py``: ``(9 E + 1, 21)`` uint8, each 168-bit
    word big-endian), built column by column: no Python int per word (22,786 ``Layout.pack``
    calls for c300's 2,848 edge pairs). A value that does not fit its field is left to
    :func:`edge_pair_words`, which raises the field's one-line error."""
    n, c = len(eps), eps.val.shape[1]
    names = ("x", "len") + F.CHANNELS[eps.mode]
    slot_lo, slot_hi = -(1 << (F.SLOT_BITS - 1)), (1 << (F.SLOT_BITS - 1)) - 1
    # (E, 9, 3): per word its three 56-bit slots, bits 0.., 56.., 112..
    slots = np.zeros((n, F.EP_WORDS, 3), np.int64)
    slots[:, 0, 0] = eps.y | (eps.h << 9) | (eps.mode << 19)          # EP_HEADER: y (9), h (10), mode (1)
    slots[:, 1, :2] = np.stack([eps.x, eps.dxdy], -1)
    slots[:, 2, :2] = np.stack([eps.len, eps.dlendy], -1)
    slots[:, 3:3 + c] = np.stack([eps.val, eps.ddy, eps.ddx], -1)
    head = [(eps.y, 9), (eps.h, 10)]
    chans = slots[:, 1:3 + c]
    if n and (len(names) != 2 + c or eps.mode not in (0, 1) or any(v.min() < 0 or v.max() >> b for v, b in head)
              or chans.min() < slot_lo or chans.max() > slot_hi):
        edge_pair_words(eps)   # raises the specification's one-line error
        raise AssertionError("edge_pair_rows: a check the specification does not make")
    be = (slots & _SLOT_MASK).astype(">u8").view(np.uint8).reshape(n, F.EP_WORDS, 3, 8)[..., 8 - _SLOT_BYTES:]
    rows = np.zeros((n * F.EP_WORDS + 1, _EP_BYTES), np.uint8)   # the last row: the end-of-frame marker (0)
    rows[:-1] = be[:, :, ::-1].reshape(-1, _EP_BYTES)            # the top slot's bytes first
    return rows


def segment_words(segs: G.Segments, y: int) -> list[int]:
    """Line ``y``'s segments as words on the chip's segment input port, then end-of-line."""
    out = []
    for s in range(*segs.line(y).indices(len(segs.y))):
        chans = [{"value": int(a), "inc": int(b)} for a, b in zip(segs.val[s], segs.inc[s], strict=True)]
        out += F.pack_segment({"y": y, "x": int(segs.x[s]), "len": int(segs.len[s]), "mode": segs.mode}, chans)
    return out + [F.SEG_HEADER.pack(y=y, len=0)]


def packets(segs: G.Segments, y: int, chip: int, interleave: int) -> list[list[int]]:
    """The initial processor's packets (8 flits each) for one chip, from the golden function."""
    sl = segs.line(y)
    px, n, v, inc_i, keep = G.initial_processor(segs.x[sl], segs.len[sl], segs.val[sl], segs.inc[sl],
                                                chip, interleave)
    out = []
    for s in np.flatnonzero(keep):
        flits = [F.PKT_HEADER.pack(x=int(px[s]), len=int(n[s]), y=y, mode=segs.mode, dx=interleave)]
        flits += [F.FLIT.pack(value=int(a), inc=int(b)) for a, b in zip(v[s], inc_i[s], strict=True)]
        out.append(flits + [0] * (F.PACKET_FLITS - len(flits)))
    return out


def pixel2_words(buf: G.DoubleZ) -> list[int]:
    """Golden double-Z pixels -> PIXEL2 integers (s0 in bits 0..63, s1 in 64..127)."""
    w = buf.words()
    return merge_words(w[..., 0], w[..., 1])


def doublez_words(px: G.DoubleZ) -> tuple[np.ndarray, np.ndarray]:
    """Double-Z pixels -> (s0, s1) uint64 sample words: the merge word is ``s1 << 64 | s0``."""
    w = px.words()
    return w[..., 0].astype(np.uint64), w[..., 1].astype(np.uint64)


def words_to_doublez(s0: np.ndarray, s1: np.ndarray) -> G.DoubleZ:
    """(s0, s1) uint64 sample words -> DoubleZ (tags unknown: -1): ``formats.unpack_samples`` with the
    fields after z read as whole bytes of the little-endian words (a: bits 24..31, c[i]: 32 + 8 i ..;
    the SAMPLE layout, checked here), one pass over both samples."""
    w = np.stack([np.asarray(s0, np.uint64), np.asarray(s1, np.uint64)], axis=-1)
    b = np.ascontiguousarray(w, dtype="<u8").view(np.uint8).reshape(w.shape + (8,))
    z = (w & np.uint64(F.Z_EMPTY)).astype(np.int64)
    return G.DoubleZ(z, b[..., 3].astype(np.int64), b[..., 4:8].astype(np.int64), np.full(w.shape, -1, np.int64))


# words_to_doublez reads the sample's fields after z as bytes: the layout it assumes
if [(f.name, F.SAMPLE.offsets[f.name], f.width) for f in F.SAMPLE.fields] != [
        ("z", 0, 24), ("a", 24, 8), ("c0", 32, 8), ("c1", 40, 8), ("c2", 48, 8), ("c3", 56, 8)]:
    raise RuntimeError("words_to_doublez: the SAMPLE layout changed; its byte reads must follow it")


_SAMPLE_BITS = F.SAMPLE.width
_SAMPLE_MASK = (1 << _SAMPLE_BITS) - 1


def merge_words(s0, s1) -> list[int]:
    """(s0, s1) sample words (any shape, uint64) -> merge-bus words ``s1 << 64 | s0`` (PIXEL2),
    flattened in C order."""
    return [int(a) | (int(b) << _SAMPLE_BITS)
            for a, b in zip(np.ravel(s0).tolist(), np.ravel(s1).tolist(), strict=True)]


def merge_rows(s0, s1) -> np.ndarray:
    """:func:`merge_words` as packed rows (``sim/packed.py``): ``(N, 16)`` uint8, each
    PIXEL2 word ``s1 << 64 | s0`` big-endian, flattened in C order; no Python int per word."""
    return np.stack([np.ravel(s1), np.ravel(s0)], -1).astype(">u8").view(np.uint8)


def rows_to_samples(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Packed PIXEL2 rows (:func:`merge_rows`' form) -> their (s0, s1) uint64 sample words."""
    w = np.ascontiguousarray(rows, np.uint8).view(">u8").reshape(-1, 2)
    return w[:, 1].astype(np.uint64), w[:, 0].astype(np.uint64)


def split_merge_words(words) -> tuple[np.ndarray, np.ndarray]:
    """Merge-bus words (PIXEL2 integers, any shape) -> (s0, s1) uint64 arrays of that shape."""
    v = np.asarray(words, dtype=object)
    s0 = np.vectorize(lambda x: int(x) & _SAMPLE_MASK, otypes=[np.uint64])(v) if v.size else v.astype(np.uint64)
    s1 = np.vectorize(lambda x: int(x) >> _SAMPLE_BITS, otypes=[np.uint64])(v) if v.size else v.astype(np.uint64)
    return s0, s1
