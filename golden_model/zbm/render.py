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
from rasterhw.golden_model.zbm.doublez import DoubleZ, arrival_layers
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
from rasterhw.golden_model.zbm.unit import _unit_frame_fast, segment_fragments, unit_scanline

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
    return merge_chain([_unit_frame_fast(s, height, width)[0] for s in segments])


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
    zb = np.full((H * W, 2), np.inf)
    cb = np.zeros((H * W, 2, 4))
    tg = np.full((H * W, 2), -1, np.int64)
    seg, k = segment_fragments(segs)
    t = segs.tag[seg]
    xc = (segs.x[seg] + k) + 0.5
    yc = segs.y[seg] + 0.5
    x0, y0 = X[t], Y[t]
    det = (x0[:, 1] - x0[:, 0]) * (y0[:, 2] - y0[:, 0]) - (x0[:, 2] - x0[:, 0]) * (y0[:, 1] - y0[:, 0])
    w1 = ((xc - x0[:, 0]) * (y0[:, 2] - y0[:, 0]) - (x0[:, 2] - x0[:, 0]) * (yc - y0[:, 0])) / det
    w2 = ((x0[:, 1] - x0[:, 0]) * (yc - y0[:, 0]) - (xc - x0[:, 0]) * (y0[:, 1] - y0[:, 0])) / det
    at = att[t]
    v = at[:, 0] + w1[:, None] * (at[:, 1] - at[:, 0]) + w2[:, None] * (at[:, 2] - at[:, 0])
    pos = segs.y[seg] * W + segs.x[seg] + k
    for ly in arrival_layers(pos):   # in emission order: strict <, the earlier segment wins ties
        p, z, vv, tt = pos[ly], v[ly, 0], v[ly, 1:], t[ly]
        f = z < zb[p, 0]
        sc = (~f) & (z < zb[p, 1])
        pf, psc = p[f], p[sc]
        zb[pf, 1], cb[pf, 1], tg[pf, 1] = zb[pf, 0], cb[pf, 0], tg[pf, 0]
        zb[pf, 0], cb[pf, 0], tg[pf, 0] = z[f], vv[f], tt[f]
        zb[psc, 1], cb[psc, 1], tg[psc, 1] = z[sc], vv[sc], tt[sc]
    zb, cb, tg = zb.reshape(H, W, 2), cb.reshape(H, W, 2, 4), tg.reshape(H, W, 2)
    bg = np.asarray(background, np.float64)
    v0 = np.isfinite(zb[..., 0])[..., None]
    v1 = np.isfinite(zb[..., 1])[..., None]
    a0, a1 = cb[..., 0, 3:4], cb[..., 1, 3:4]
    back = np.where(v1, a1 * cb[..., 1, :3] + (1 - a1) * bg, bg)
    rgb = np.where(v0, a0 * cb[..., 0, :3] + (1 - a0) * back, bg)
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
