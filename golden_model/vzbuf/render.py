"""One frame through the vector Z-buffer machine, stage by stage, timed as the paper's tables.

Stages (the paper's numbering per table):

* tables 2, 3 (no shadows): 1 set-up, 2 hidden-surface removal, 3 segment-block building
  ("セグメント・ブロックの作成処理等"; algorithm 2's splitting is in it, and so is the final
  RGBI quantisation, "等");
* table 4 (algorithm 1, shadow polygons): 1 set-up (with the shadow polygons), 2 hidden-surface
  removal and shadow polygons, 3 segment building (real and shadow);
* table 5 (algorithm 2, shadow polygons): 1 set-up, 2 hidden-surface removal, 3 shadow
  polygons, 4 segment building;
* tables 6, 7 (ray casting): 1 eye-space hidden-surface removal, 2 light-space hidden-surface
  removal, 3 eye -> light transform, 4 buffer initialisation. The tables have no set-up or
  segment stage, so the eye set-up and its segments are counted in 1 and the light-space
  transform and its segments in 2 (our reading of "等").

Times are CPU seconds (``time.process_time``), buffers in memory, no disk I/O (3.1 a, b).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.vzbuf.blocks import blocks_from_scene, quantise_rgbi, setup
from rasterhw.golden_model.vzbuf.hsr import Counters, algorithm1, algorithm2, new_buffers
from rasterhw.golden_model.vzbuf.segments import build_segments, concat_segments, split_segments
from rasterhw.golden_model.vzbuf.shadows import (
    light_polygons,
    light_space,
    shadow_map_test,
    shadow_polygons,
)

__all__ = ["Frame", "render_frame", "DEFAULT_EPS"]

#: shadow-map epsilon in light depth units (the light frame maps the scene's depth to [0, 1])
DEFAULT_EPS = 5e-3


@dataclass
class Frame:
    depth: np.ndarray
    qid: np.ndarray
    poly: np.ndarray          # scene polygon per pixel, -1 = background
    inten: np.ndarray         # intensity after shadowing
    shadowed: np.ndarray      # bool (H, W)
    rgb8: np.ndarray
    i7: np.ndarray
    sp: object                # ScreenPolygons of the real polygons
    stages: dict              # stage name -> CPU seconds, in the table's order
    stats: dict = field(default_factory=dict)


def _clock():
    return time.process_time()


def render_frame(scene: Scene, width: int = 512, height: int = 512, *, alg: int = 2,
                 shadows: str = "none", eps: float = DEFAULT_EPS, background=(0.0, 0.0, 0.0)) -> Frame:
    """Render ``scene`` with algorithm ``alg`` (1 or 2) and ``shadows`` none|polygons|map."""
    if alg not in (1, 2):
        raise RasterhwError(f"vzbuf: algorithm must be 1 or 2, not {alg!r}")
    if shadows not in ("none", "polygons", "map"):
        raise RasterhwError(f"vzbuf: shadows must be none, polygons or map, not {shadows!r}")
    if shadows == "map" and not (isinstance(eps, (int, float)) and not isinstance(eps, bool)
                                 and np.isfinite(eps) and eps > 0):
        raise RasterhwError(f"vzbuf: shadow-map eps must be a finite number > 0, not {eps!r}")
    st: dict[str, float] = {}
    stats: dict = {}
    W, H = width, height
    t0 = _clock()
    blocks = blocks_from_scene(scene, W, H, background=background)
    sp = setup(scene, W, H, blocks)
    ia = blocks.control.ia
    sh = None
    if shadows == "polygons":
        sh = shadow_polygons(scene, W, H)
    t1 = _clock()
    seg = build_segments(sp, H)
    stats["segments"] = seg.n
    split = None
    if alg == 2:
        seg, split = split_segments(seg, W)
        stats["split"] = split
    sseg = None
    if sh is not None:
        parts, signs = [], []
        for name, sg in (("front", 1), ("back", -1)):
            if sh[name] is not None and sh[name].nv.size:
                s = build_segments(sh[name], H)
                parts.append(s)
                signs.append(np.full(s.n, sg, np.int64))
        sseg = concat_segments(parts)
        sign = np.concatenate(signs) if signs else np.zeros(0, np.int64)
        stats["shadow_segments"] = sseg.n
        if alg == 2 and sseg.n:
            sseg, ssplit = split_segments(sseg, W)
            stats["shadow_split"] = ssplit
            sign = sign[ssplit["source"]]
    t2 = _clock()
    buf = new_buffers(W, H)
    t_init = _clock() - t2
    c_real, c_sh = Counters(), Counters()
    t3 = _clock()
    if shadows == "map":
        (algorithm1 if alg == 1 else algorithm2)(seg, W, H, buf, counters=c_real,
                                                  **({"full_frame": True} if alg == 1 else {}))
    elif alg == 1:
        algorithm1(seg, W, H, buf, counters=c_real)
    else:
        algorithm2(seg, W, H, buf, counters=c_real)
    t4 = _clock()
    visible = buf["qid"] >= 0
    shadowed = np.zeros((H, W), bool)
    t5 = t4
    if sseg is not None and sseg.n:
        (algorithm1 if alg == 1 else algorithm2)(sseg, W, H, buf, mode="shadow", sign=sign, counters=c_sh)
        shadowed = visible & (buf["count"] > 0)
        buf["inten"][shadowed] = ia
        t5 = _clock()
    tl = {}
    if shadows == "map":
        a = _clock()
        ls = light_space(scene, W, H)
        lsp = light_polygons(scene, W, H, ls)
        lseg = build_segments(lsp, H)
        if alg == 2:
            lseg, _ = split_segments(lseg, W)
        lbuf = new_buffers(W, H)
        b = _clock()
        c_l = Counters()
        (algorithm1 if alg == 1 else algorithm2)(lseg, W, H, lbuf, mode="depth", counters=c_l,
                                                  **({"full_frame": True} if alg == 1 else {}))
        c = _clock()
        shadowed = shadow_map_test(scene, W, H, buf["depth"], visible, lbuf["depth"], ls, eps)
        buf["inten"][shadowed] = ia
        d = _clock()
        tl = {"light_setup": b - a, "light_hsr": c - b, "transform": d - c}
        stats["light"] = {"polygons": int(lsp.nv.size), "segments": lseg.n, **c_l.as_dict()}
    t6 = _clock()
    poly = np.where(visible, sp.poly[np.maximum(buf["qid"], 0)], -1)
    face = blocks.polygon.colour[np.maximum(poly, 0)]
    bg = np.asarray(background, float)
    rgb3, i7, rgb8 = quantise_rgbi(face, buf["inten"])
    rgb8[~visible] = np.clip(np.floor(bg * 255 + 0.5), 0, 255).astype(np.uint8)
    t7 = _clock()
    setup_s, seg_s, hsr_s, sh_s, q_s = t1 - t0, t2 - t1, t4 - t3, t5 - t4, t7 - t6
    if shadows == "none":
        st = {"1 set-up": setup_s, "2 hidden-surface removal": hsr_s + t_init, "3 segment build": seg_s + q_s}
    elif shadows == "polygons" and alg == 1:
        st = {"1 set-up": setup_s, "2 hidden-surface removal + shadow": hsr_s + sh_s + t_init,
              "3 segment build": seg_s + q_s}
    elif shadows == "polygons":
        st = {"1 set-up": setup_s, "2 hidden-surface removal": hsr_s + t_init, "3 shadow polygons": sh_s,
              "4 segment build": seg_s + q_s}
    else:
        st = {"1 eye hidden-surface removal": setup_s + seg_s + hsr_s,
              "2 light hidden-surface removal": tl["light_setup"] + tl["light_hsr"],
              "3 eye->light transform": tl["transform"], "4 buffer init": t_init + q_s}
    stats["counters"] = c_real.as_dict()
    if c_sh.ztests:
        stats["shadow_counters"] = c_sh.as_dict()
    stats["polygons_processed"] = int(np.unique(sp.poly).size)
    stats["pixels_real"] = c_real.elements
    stats["pixels_shadow"] = c_sh.elements
    if sh is not None:
        stats["shadow_initial"] = sh["initial"]
        stats["shadow_processed"] = sum(int(np.unique(sh[n].poly).size) for n in ("front", "back")
                                        if sh[n] is not None)
    return Frame(depth=buf["depth"], qid=buf["qid"], poly=poly, inten=buf["inten"], shadowed=shadowed,
                 rgb8=rgb8, i7=i7, sp=sp, stages=st, stats=stats)
