"""Shared stimulus for the ZB/M pysim tests: random segments, packets, golden line buffers.

(Imported by the other ``test_zbm_*_pysim.py`` files; its own tests check the helpers.)"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model import zbm_formats as F


def random_segments(rng: np.random.Generator, n: int, width: int, mode: int = F.MODE_COLOUR,
                    y: int = 0) -> G.Segments:
    """``n`` random segments on line ``y`` with overlapping depths (Z ties included)."""
    C = len(F.CHANNELS[mode])
    x = rng.integers(0, width, n)
    ln = np.minimum(rng.integers(1, 24, n), width - x)
    val = np.zeros((n, C), np.int64)
    inc = np.zeros((n, C), np.int64)
    val[:, 0] = rng.integers(0, 40, n) << F.ATTR_FRAC          # depths that collide often
    inc[:, 0] = rng.integers(-3 << F.ATTR_FRAC, 3 << F.ATTR_FRAC, n) * rng.integers(0, 2, n)
    val[:, 1:] = rng.integers(-40 << F.ATTR_FRAC, 300 << F.ATTR_FRAC, (n, C - 1))   # clamps too
    inc[:, 1:] = rng.integers(-20 << F.ATTR_FRAC, 20 << F.ATTR_FRAC, (n, C - 1))
    if n:
        val[0, 0] = -(5 << F.ATTR_FRAC)                            # z clamps at 0
        val[-1, 0] = (1 << 48) - 1                                 # and at Z_MAX_SAMPLE
    z1 = np.zeros(n, np.int64)
    return G.Segments(np.full(n, y), x, ln, val, inc, np.arange(n), np.arange(n),
                      np.array([0] * (y + 1) + [n]), z1, z1, z1, mode)


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
    return [int(a) | (int(b) << 64) for a, b in w.reshape(-1, 2)]


def test_packets_follow_initial_processor():
    rng = np.random.default_rng(1)
    segs = random_segments(rng, 10, 64)
    for interleave in F.INTERLEAVES:
        for chip in range(interleave):
            for pkt in packets(segs, 0, chip, interleave):
                h = F.PKT_HEADER.unpack(pkt[0])
                assert len(pkt) == F.PACKET_FLITS and h["len"] >= 1 and h["x"] % interleave == chip


def segment_words(segs: G.Segments, y: int) -> list[int]:
    """Line ``y``'s segments as words on the chip's segment input port, then end-of-line."""
    out = []
    for s in range(*segs.line(y).indices(len(segs.y))):
        chans = [{"value": int(a), "inc": int(b)} for a, b in zip(segs.val[s], segs.inc[s], strict=True)]
        out += F.pack_segment({"y": y, "x": int(segs.x[s]), "len": int(segs.len[s]), "mode": segs.mode}, chans)
    return out + [F.SEG_HEADER.pack(y=y, len=0)]


def random_doublez(rng: np.random.Generator, n: int) -> G.DoubleZ:
    """Random upstream merge-input pixels (s0 nearer or equal; some empty)."""
    d = G.DoubleZ.empty((n,))
    z = np.sort(rng.integers(0, 40, (n, 2)), axis=1)
    z[rng.random((n, 2)) < 0.3] = F.Z_EMPTY
    d.z[:] = np.sort(z, axis=1)
    d.a[:] = rng.integers(0, 256, (n, 2))
    d.c[:] = rng.integers(0, 256, (n, 2, 4))
    d.a[d.z == F.Z_EMPTY] = 0
    d.c[d.z == F.Z_EMPTY] = 0
    return d


def multi_line_segments(rng: np.random.Generator, counts: list[int], width: int,
                        mode: int = F.MODE_COLOUR) -> G.Segments:
    """Random segments on lines 0..len(counts)-1 (``counts[y]`` on line y)."""
    parts = [random_segments(rng, c, width, mode, y=0) for c in counts]
    cat = {k: np.concatenate([getattr(p, k) for p in parts]) for k in ("x", "len", "val", "inc")}
    ys = np.concatenate([np.full(c, y) for y, c in enumerate(counts)]).astype(np.int64)
    n = ys.size
    line_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    z1 = np.zeros(len(counts), np.int64)
    return G.Segments(ys, cat["x"], cat["len"], cat["val"], cat["inc"], np.arange(n), np.arange(n),
                      line_start, z1, z1, z1, mode)


def random_triangles(rng: np.random.Generator, n: int, width: int, height: int, size: float = 12.0):
    """``n`` random screen triangles (some partly off screen) as ScreenTriangles."""
    from rasterhw.golden_model.screen import ScreenTriangles

    c = rng.uniform([-4, -4], [width + 4, height + 4], (n, 1, 2))
    xy = c + rng.uniform(-size, size, (n, 3, 2))
    z = rng.uniform(0.1, 0.9, (n, 3))
    return ScreenTriangles(width=width, height=height, xy=xy, z=z,
                           zq=np.round(z * ((1 << 24) - 1)).astype(np.int64),
                           colour=rng.uniform(0, 1, (n, 3, 3)), poly_id=np.arange(n),
                           uv=rng.uniform(0, 1, (n, 3, 2)))


def edge_pair_words(eps: G.EdgePairs) -> list[int]:
    """All edge pairs' 9 loader words, then the end-of-frame marker (EP_HEADER h = 0)."""
    return [w for i in range(len(eps)) for w in eps.words(i)] + [F.EP_HEADER.pack(y=0, h=0)]
