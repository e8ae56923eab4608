"""ZB/M word packing: the one place golden values become the words the HDL ports carry.

Every bench (Amaranth pysim, cocotb, the plain-Verilator runs) builds its stimulus and reads
its results through these functions; the word layouts themselves are defined once in
:mod:`rasterhw.golden_model.zbm.formats`.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm import formats as F

__all__ = ["merge_words", "split_merge_words", "doublez_words", "edge_pair_words", "packets", "pixel2_words", "segment_words",
           "words_to_doublez"]


def edge_pair_words(eps: G.EdgePairs) -> list[int]:
    """All edge pairs' 9 loader words, then the end-of-frame marker (EP_HEADER h = 0)."""
    return [w for i in range(len(eps)) for w in eps.words(i)] + [F.EP_HEADER.pack(y=0, h=0)]


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
    """(s0, s1) uint64 sample words -> DoubleZ (tags unknown: -1)."""
    d = G.DoubleZ.empty(s0.shape)
    for k, w in enumerate((s0, s1)):
        z, a, c = F.unpack_samples(w)
        d.z[..., k], d.a[..., k], d.c[..., k, :] = z, a, c
    return d


_SAMPLE_BITS = F.SAMPLE.width
_SAMPLE_MASK = (1 << _SAMPLE_BITS) - 1


def merge_words(s0, s1) -> list[int]:
    """(s0, s1) sample words (any shape, uint64) -> merge-bus words ``s1 << 64 | s0`` (PIXEL2),
    flattened in C order."""
    return [int(a) | (int(b) << _SAMPLE_BITS)
            for a, b in zip(np.ravel(s0).tolist(), np.ravel(s1).tolist(), strict=True)]


def split_merge_words(words) -> tuple[np.ndarray, np.ndarray]:
    """Merge-bus words (PIXEL2 integers, any shape) -> (s0, s1) uint64 arrays of that shape."""
    v = np.asarray(words, dtype=object)
    s0 = np.vectorize(lambda x: int(x) & _SAMPLE_MASK, otypes=[np.uint64])(v) if v.size else v.astype(np.uint64)
    s1 = np.vectorize(lambda x: int(x) >> _SAMPLE_BITS, otypes=[np.uint64])(v) if v.size else v.astype(np.uint64)
    return s0, s1
