"""Table 1 of the paper measured on our scenes: polygons, segments, mean extents, pixels.

Definitions (table 1 notes 2-5): *processed polygons* survive back-face removal and clipping;
*segments* are counted before algorithm 2's splitting (the table has one row for both
algorithms); *pixels processed* are the pixels Z-tested (every span pixel of every segment:
the reference rasteriser's fragments); *area per polygon* = pixels / processed polygons;
shadow rows count the shadow polygons (front and back) the same way.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.vzbuf.blocks import setup
from rasterhw.golden_model.vzbuf.segments import (
    SegmentBlock,
    build_segments,
    extents,
    spans_at,
    split_segments,
)
from rasterhw.golden_model.vzbuf.shadows import shadow_polygons

__all__ = ["segment_pixels", "table1"]


def segment_pixels(seg: SegmentBlock, width: int) -> int:
    """Pixels inside the spans of every line of every segment (closed form per line)."""
    if seg.n == 0:
        return 0
    nl = seg.yend - seg.y0 + 1
    idx = np.repeat(np.arange(seg.n), nl)
    rows = seg.y0[idx] + (np.arange(idx.size) - np.repeat(np.cumsum(nl) - nl, nl))
    lo, hi = spans_at(seg, idx, rows, width)
    return int(np.maximum(hi - lo + 1, 0).sum())


def _block(sp, height, width) -> dict:
    seg = build_segments(sp, height)
    xl, yl = extents(seg, width)
    px = segment_pixels(seg, width)
    npoly = int(np.unique(sp.poly).size)
    split, info = split_segments(seg, width)
    return {"polygons": npoly, "segments": seg.n, "segments_split": split.n,
            "mean_x": float(xl.mean()) if seg.n else 0.0, "mean_y": float(yl.mean()) if seg.n else 0.0,
            "pixels": px, "area_per_polygon": px / npoly if npoly else 0.0,
            "pixels_after_split": segment_pixels(split, width)}


def table1(scene: Scene, width: int = 512, height: int = 512, *, shadows: bool = True) -> dict:
    """The quantities of table 1 for one scene (shadow rows need a ground polygon)."""
    sp = setup(scene, width, height)
    real = _block(sp, height, width)
    out = {"initial polygons": scene.n_polygons, "processed polygons": real["polygons"],
           "segments": real["segments"], "segments after split": real["segments_split"],
           "mean length x": real["mean_x"], "mean length y": real["mean_y"],
           "pixels processed": real["pixels"], "area per polygon": real["area_per_polygon"]}
    assert real["pixels_after_split"] == real["pixels"], "splitting must keep every pixel once"
    rows = _line_occupancy(sp, height)
    out["empty lines"] = int((rows == 0).sum())
    if shadows:
        try:
            sh = shadow_polygons(scene, width, height)
        except RasterhwError:
            return out
        parts = [_block(sh[n], height, width) for n in ("front", "back") if sh[n] is not None and sh[n].nv.size]
        segs = sum(p["segments"] for p in parts)
        px = sum(p["pixels"] for p in parts)
        npoly = sum(p["polygons"] for p in parts)
        out.update({
            "initial shadow polygons": sh["initial"], "processed shadow polygons": npoly,
            "shadow segments": segs,
            "shadow mean length x": sum(p["mean_x"] * p["segments"] for p in parts) / segs if segs else 0.0,
            "shadow mean length y": sum(p["mean_y"] * p["segments"] for p in parts) / segs if segs else 0.0,
            "shadow pixels processed": px, "shadow area per polygon": px / npoly if npoly else 0.0,
        })
    return out


def _line_occupancy(sp, height) -> np.ndarray:
    seg = build_segments(sp, height)
    occ = np.zeros(height + 1, np.int64)
    np.add.at(occ, seg.y0, 1)
    np.add.at(occ, seg.yend + 1, -1)
    return np.cumsum(occ)[:height]
