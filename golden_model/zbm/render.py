"""ZB/M golden model (Matsushita scan-line Z-buffer merger, seed 003): bit-accurate and float.

Stages, one function each in a module of the same block name (formats in
:mod:`rasterhw.golden_model.zbm.formats`):

``edge_pairs``          level-1 processor (software, float64 -> fixed point): triangle -> 2 edge pairs
``segment_generator``   input FIFO + active-edge-pair memory + adders: edge pairs -> segments per line
``initial_processor``   per chip: segment -> segment packet for this chip's interleave slot
``chip_scanline``       per chip: segment loop DDA + double-Z pixel memories for one scan line
``merge``               nearest 2 of 4 samples (upstream input wins ties)
``map_samples``         texture / illumination lookups after the merge (mapping mode)
``composite``           alpha-compositing of the final 2 samples
``render_zbm``          the whole machine: units (segment generator + chips) chained by merge ports

Everything from :class:`EdgePairs` on is integer arithmetic in ``int64`` with the hardware's
widths, masks and shifts, and the HDL must match it bit for bit. ``render_zbm_float`` is the ideal
twin (same coverage, attributes from the float plane equations, float double Z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles, snap
from rasterhw.golden_model.zbm.composite import composite
from rasterhw.golden_model.zbm.doublez import DoubleZ, nearest_two
from rasterhw.golden_model.zbm.edgepair import _attributes, edge_pairs
from rasterhw.golden_model.zbm.formats import (
    AEP_CAPACITY,
    MODE_COLOUR,
    MODE_MAPPING,
    SUB,
    Z_BITS,
    Z_SCALE,
    check_interleave,
)
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.merger import merge_chain
from rasterhw.golden_model.zbm.seggen import segment_generator
from rasterhw.golden_model.zbm.unit import (
    _unit_frame_fast,
    segment_fragments,
    unit_frame,
    unit_scanline,
)

__all__ = ["ZbmResult", "chain_frame", "render_zbm", "render_zbm_float", "render_scene"]


@dataclass
class ZbmResult:
    rgb8: np.ndarray          # (H, W, 3) uint8
    pixels: DoubleZ           # (H, W) final double-Z buffers after the merge chain
    unit_pixels: list         # per unit (H, W) double-Z line buffers before merging
    stats: dict


def render_zbm(tris: ScreenTriangles, *, interleave: int = 8, units: int = 1, mode: int = MODE_COLOUR,
               alpha=None, capacity: int = AEP_CAPACITY, maps=None, background=(0, 0, 0),
               per_chip: bool = False) -> ZbmResult:
    """Render with ``units`` polygon-processing units (segment generator + ``interleave`` chips).

    Triangles are dealt to units round-robin (triangle i -> unit i % units); each unit has its
    own segment generator and per-line double-Z buffers; the units' lines are merged along
    the chain (unit 0 at the head), then mapped (mapping mode) and alpha-composited.
    ``per_chip=True`` runs every chip's loop (:func:`chip_scanline`); the default uses the
    bit-identical whole-unit shortcut. Returns :class:`ZbmResult` (rgb8, final double-Z
    buffers, per-unit buffers, stats).
    """
    check_interleave(interleave)
    if not isinstance(units, (int, np.integer)) or not 1 <= units <= 256:
        raise RasterhwError(f"ZB/M: units must be an integer in 1..256, not {units!r}")
    eps = edge_pairs(tris, mode=mode, alpha=alpha)
    W, H = tris.width, tris.height
    unit_bufs, stats = [], {"units": [], "interleave": interleave, "edge_pairs": len(eps)}
    for u in range(units):
        sel = np.flatnonzero(eps.tag % units == u)
        segs = segment_generator(eps.take(sel), H, width=W, capacity=capacity)
        if per_chip:
            buf = DoubleZ.empty((H, W))
            st = {"packets": 0, "pixels": 0, "writes": 0}
            for y in range(H):
                line, s = unit_scanline(segs, y, interleave, W)
                buf.z[y], buf.a[y], buf.c[y], buf.tag[y] = line.z, line.a, line.c, line.tag
                for k in st:
                    st[k] += s[k]
        else:
            buf, st = _unit_frame_fast(segs, H, W)
        unit_bufs.append(buf)
        stats["units"].append({**segs.stats, **st})
    final = merge_chain(unit_bufs)
    stats["fragments"] = sum(s["pixels"] for s in stats["units"])
    stats["z_writes"] = sum(s["writes"] for s in stats["units"])
    shown = final
    if mode == MODE_MAPPING:
        tex, il = default_maps() if maps is None else maps
        shown, ls = map_samples(final, tex, il)
        stats.update(ls)
        # what mapping before the Z test would cost: one lookup pair per fragment
        stats["lookups_if_mapped_before_merge"] = stats["fragments"]
    return ZbmResult(composite(shown, background), final, unit_bufs, stats)


def chain_frame(eps_per_unit: list, width: int, height: int, *, capacity: int = AEP_CAPACITY,
                segments: list | None = None) -> DoubleZ:
    """The double-Z frame of a chain of units, unit ``k`` drawing ``eps_per_unit[k]`` (unit 0 at
    the head), merged along the chain: what :func:`render_zbm` computes from triangles dealt
    round-robin, for edge pairs given per unit. ``segments``: each unit's ``segment_generator``
    output for its edge pairs at this size, when the caller has them (the same arrays: the memory's
    ``capacity`` only bounds what fits, it never changes a segment)."""
    if segments is None:
        segments = [segment_generator(e, height, width=width, capacity=capacity) for e in eps_per_unit]
    if len(segments) != len(eps_per_unit):
        raise RasterhwError(f"chain_frame: {len(segments)} segment lists for {len(eps_per_unit)} units")
    return merge_chain([unit_frame(s, height, width) for s in segments])


def render_zbm_float(tris: ScreenTriangles, *, alpha=None, background=(0.0, 0.0, 0.0), segs=None) -> dict:
    """The ideal twin (colour mode): the same coverage, float64 everywhere else.

    Coverage comes from the bit-accurate segment generator (it is exact: the reference's top-left
    rule); depth and colour are the float plane equations at pixel centres; double Z is kept in
    float (strict ``<``, the earlier segment wins ties); the 2 nearest are alpha-composited in
    float.
    Returns ``{"rgb": (H, W, 3) float in [0, 1], "z": (H, W, 2) float (inf = empty),
    "tag": (H, W, 2)}``. ``segs``: ``segment_generator(edge_pairs(tris, alpha=alpha), H, width=W)``
    when the caller has it (a one-unit chain's: :func:`chain_frame`'s ``segments``).
    """
    W, H = tris.width, tris.height
    if segs is None:
        segs = segment_generator(edge_pairs(tris, alpha=alpha), H, width=W)
    xy = np.asarray(tris.xy, np.float64)
    X = snap(xy[..., 0]) / SUB
    Y = snap(xy[..., 1]) / SUB
    att = _attributes(tris, MODE_COLOUR, alpha) / np.array([Z_SCALE, 255, 255, 255, 255])
    # per triangle what every fragment of it uses (the same float operations as per fragment)
    dx1, dx2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    dy1, dy2 = Y[:, 1] - Y[:, 0], Y[:, 2] - Y[:, 0]
    det = dx1 * dy2 - dx2 * dy1
    d1, d2 = att[:, 1] - att[:, 0], att[:, 2] - att[:, 0]
    seg, k = segment_fragments(segs)
    t = segs.tag[seg]
    ex = ((segs.x[seg] + k) + 0.5) - X[t, 0]
    ey = (segs.y[seg] + 0.5) - Y[t, 0]
    w1 = (ex * dy2[t] - dx2[t] * ey) / det[t]
    w2 = (dx1[t] * ey - ex * dy1[t]) / det[t]

    def value(i, ch):   # the float plane equation of fragments i, channels ch
        ti = t[i]
        return att[ti, 0, ch] + w1[i, None] * d1[ti, ch] + w2[i, None] * d2[ti, ch]

    z = value(slice(None), slice(0, 1))[:, 0]
    pos = segs.y[seg] * W + segs.x[seg] + k
    # in emission order, strict <, the earlier segment wins ties: a fragment not nearer than
    # "empty" (inf, NaN) is never kept, the rest are the two least by (z, emission) per pixel
    near = np.flatnonzero(z < np.inf)
    pix, f, s = nearest_two(pos[near], z[near])
    f, two = near[f], s >= 0
    s = near[s[two]]
    zb = np.full((H * W, 2), np.inf)
    tg = np.full((H * W, 2), -1, np.int64)
    zb[pix, 0], tg[pix, 0] = z[f], t[f]
    zb[pix[two], 1], tg[pix[two], 1] = z[s], t[s]
    # alpha-composited where a pixel has a sample (elsewhere the background), the same float
    # operations per pixel as over the whole frame
    bg = np.asarray(background, np.float64)
    c0, c1 = value(f, slice(1, None)), np.zeros((pix.size, 4))
    c1[two] = value(s, slice(1, None))
    a0, a1 = c0[:, 3:4], c1[:, 3:4]
    back = np.where(two[:, None], a1 * c1[:, :3] + (1 - a1) * bg, bg)
    rgb = np.empty((H * W, 3))
    rgb[:] = bg
    rgb[pix] = a0 * c0[:, :3] + (1 - a0) * back
    zb, tg, rgb = zb.reshape(H, W, 2), tg.reshape(H, W, 2), rgb.reshape(H, W, 3)
    return {"rgb": rgb, "z": zb, "tag": tg}


def render_scene(scene, width: int, height: int, *, arch: str = "zbm", interleave: int = 8,
                 units: int = 1):
    """``rasterhw render --arch zbm``: geometry, then :func:`render_zbm` (bit-accurate)."""
    from rasterhw.golden_model.arch import Rendered
    from rasterhw.golden_model.pipeline import run_geometry

    tris = run_geometry(scene, width, height, z_bits=Z_BITS)
    res = render_zbm(tris, interleave=interleave, units=units)
    st = {k: v for k, v in res.stats.items() if k != "units"}
    st["pixels_covered"] = int((res.pixels.tag[..., 0] >= 0).sum())   # the nearest sample of each pixel
    return Rendered(res.rgb8, tris, int(res.stats["z_writes"]), st)
