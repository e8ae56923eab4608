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

__all__ = ["Frame", "render_frame", "table_stages", "DEFAULT_EPS"]

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


def table_stages(alg: int, shadows: str) -> dict[str, tuple[str, ...]]:
    """Each table stage (labelled as :attr:`Frame.stages`) -> the trace phases it holds; the same
    grouping as the CPU-time stages of :func:`render_frame`."""
    if shadows == "none":
        return {"1 set-up": ("setup",), "2 hidden-surface removal": ("init", "hsr"),
                "3 segment build": ("segments", "split", "quantise")}
    if shadows == "polygons" and alg == 1:
        return {"1 set-up": ("setup", "shadow setup"), "2 hidden-surface removal + shadow": ("init", "hsr", "shadow"),
                "3 segment build": ("segments", "split", "quantise")}
    if shadows == "polygons":
        return {"1 set-up": ("setup", "shadow setup"), "2 hidden-surface removal": ("init", "hsr"),
                "3 shadow polygons": ("shadow",), "4 segment build": ("segments", "split", "quantise")}
    return {"1 eye hidden-surface removal": ("setup", "segments", "split", "hsr"),
            "2 light hidden-surface removal": ("light",), "3 eye->light transform": ("transform",),
            "4 buffer init": ("init", "quantise")}


def _trace_setup(tr, scene: Scene, sp) -> None:
    """Set-up loops (2.2): every vertex transformed and lit, every face tested lit or unlit,
    back-face tested and collected; clipping (Sutherland's re-entrant clipper, polygon by polygon
    and plane by plane) stays scalar."""
    nvert = int(np.asarray(scene.nverts).sum())
    tr.loop("vertex transform", nvert)
    tr.loop("vertex lighting", nvert)
    tr.loop("face lit test", scene.n_polygons)
    tr.loop("back-face test", scene.n_polygons)
    tr.loop("collect polygons", scene.n_polygons)
    tr.scalar("clip polygon x plane", 6 * int(sp.nv.size))
    tr.scalar("clip vertex x plane", 6 * int(sp.nv.sum()))


def _trace_segments(tr, sp, seg) -> None:
    """Segment building (fig. 1, lost in the OCR; 2.3.2 1)): per polygon its chains and vertex
    lines and per segment its block scalar, the polygon planes, edge blocks and dz/dx vector,
    y-list linking scalar."""
    tr.scalar("polygon chains", int(sp.nv.size))
    tr.scalar("vertex line", int(sp.nv.sum()))
    tr.loop("polygon plane", int(sp.nv.size))
    tr.scalar("segment block", seg.n)
    tr.loop("edge block", 2 * seg.n)
    tr.loop("segment dzdx", seg.n)
    tr.scalar("y-list link", seg.n)


def _trace_split(tr, before: int, after: int) -> None:
    tr.loop("segment lengths", before)
    tr.loop("select long segments", before)
    tr.loop("split piece", after)
    tr.scalar("y-list link", after)


def render_frame(scene: Scene, width: int = 512, height: int = 512, *, alg: int = 2,
                 shadows: str = "none", eps: float = DEFAULT_EPS, background=(0.0, 0.0, 0.0),
                 trace=None) -> Frame:
    """Render ``scene`` with algorithm ``alg`` (1 or 2) and ``shadows`` none|polygons|map.

    ``trace`` (a :class:`~.trace.Trace`) records the paper's loops phase by phase; recording
    reads counts only and changes no output."""
    if alg not in (1, 2):
        raise RasterhwError(f"vzbuf: algorithm must be 1 or 2, not {alg!r}")
    if shadows not in ("none", "polygons", "map"):
        raise RasterhwError(f"vzbuf: shadows must be none, polygons or map, not {shadows!r}")
    if shadows == "map" and not (isinstance(eps, (int, float)) and not isinstance(eps, bool)
                                 and np.isfinite(eps) and 0 < eps < 1):
        raise RasterhwError(f"vzbuf: shadow-map eps must be a number in (0, 1) (light depth runs 0..1; "
                            f"1 or more shadows nothing), not {eps!r}")
    if shadows != "map" and eps != DEFAULT_EPS:
        raise RasterhwError(f"vzbuf: eps is the shadow map's (--shadows map); with --shadows {shadows} it would "
                            "change nothing")
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
    if trace is not None:
        _trace_setup(trace.at("setup"), scene, sp)
        _trace_segments(trace.at("segments"), sp, seg)
    if alg == 2:
        seg, split = split_segments(seg, W)
        stats["split"] = split
        if trace is not None:
            _trace_split(trace.at("split"), split["segments_before"], split["segments_after"])
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
        if trace is not None:
            trace.at("shadow setup")
            trace.loop("silhouette test", sh["edges"])
            trace.loop("shadow quad", sh["initial"])
            trace.loop("vertex transform", 4 * sh["initial"])
            trace.loop("back-face test", sh["initial"])
            trace.loop("collect polygons", sh["initial"])
            for name in ("front", "back"):
                if sh[name] is not None:
                    trace.scalar("clip polygon x plane", 6 * int(sh[name].nv.size))
                    trace.scalar("clip vertex x plane", 6 * int(sh[name].nv.sum()))
            trace.at("segments")
            for name, s_ in zip([n for n in ("front", "back") if sh[n] is not None and sh[n].nv.size], parts,
                                strict=True):
                _trace_segments(trace, sh[name], s_)
        if alg == 2 and sseg.n:
            sseg, ssplit = split_segments(sseg, W)
            stats["shadow_split"] = ssplit
            sign = sign[ssplit["source"]]
            if trace is not None:
                _trace_split(trace.at("split"), ssplit["segments_before"], ssplit["segments_after"])
    t2 = _clock()
    buf = new_buffers(W, H)
    t_init = _clock() - t2
    if trace is not None:
        # the image memory always; a full-frame Z-buffer (algorithm 2, ray casting); the shadow
        # count buffer (shadow polygons); the light-space shadow buffer (ray casting)
        n_buf = 1 + (alg == 2 or shadows == "map") + (shadows == "polygons") + (shadows == "map")
        trace.at("init").loop("clear", W * H, times=n_buf)
    c_real, c_sh = Counters(), Counters()
    t3 = _clock()
    if trace is not None:
        trace.at("hsr")
    if shadows == "map":
        (algorithm1 if alg == 1 else algorithm2)(seg, W, H, buf, counters=c_real, trace=trace,
                                                  **({"full_frame": True} if alg == 1 else {}))
    elif alg == 1:
        algorithm1(seg, W, H, buf, counters=c_real, trace=trace)
    else:
        algorithm2(seg, W, H, buf, counters=c_real, trace=trace)
    t4 = _clock()
    visible = buf["qid"] >= 0
    shadowed = np.zeros((H, W), bool)
    t5 = t4
    if sseg is not None and sseg.n:
        if trace is not None:
            trace.at("shadow")
        (algorithm1 if alg == 1 else algorithm2)(sseg, W, H, buf, mode="shadow", sign=sign, counters=c_sh,
                                                  trace=trace)
        if trace is not None:
            trace.loop("shadow darken", W * H)
        shadowed = visible & (buf["count"] > 0)
        buf["inten"][shadowed] = ia
        t5 = _clock()
    tl = {}
    if shadows == "map":
        a = _clock()
        ls = light_space(scene, W, H)
        lsp = light_polygons(scene, W, H, ls)
        lseg = build_segments(lsp, H)
        if trace is not None:
            trace.at("light")
            nl = int(lsp.nv.size)
            trace.loop("vertex transform", int(np.asarray(scene.nverts).sum()))
            trace.loop("back-face test", scene.n_polygons)
            trace.loop("collect polygons", scene.n_polygons)
            trace.scalar("clip polygon x plane", 6 * nl)
            trace.scalar("clip vertex x plane", 6 * int(lsp.nv.sum()) if nl else 0)
            _trace_segments(trace, lsp, lseg)
        if alg == 2:
            lseg, lsplit = split_segments(lseg, W)
            if trace is not None:
                _trace_split(trace, lsplit["segments_before"], lsplit["segments_after"])
        lbuf = new_buffers(W, H)
        b = _clock()
        c_l = Counters()
        (algorithm1 if alg == 1 else algorithm2)(lseg, W, H, lbuf, mode="depth", counters=c_l, trace=trace,
                                                  **({"full_frame": True} if alg == 1 else {}))
        c = _clock()
        if trace is not None:
            trace.at("transform").loop("to light space", W * H)
        shadowed = shadow_map_test(scene, W, H, buf["depth"], visible, lbuf["depth"], ls, eps)
        buf["inten"][shadowed] = ia
        d = _clock()
        tl = {"light_setup": b - a, "light_hsr": c - b, "transform": d - c}
        stats["light"] = {"polygons": int(lsp.nv.size), "segments": lseg.n, **c_l.as_dict()}
    t6 = _clock()
    poly = np.where(visible, sp.poly[np.maximum(buf["qid"], 0)], -1)
    face = blocks.polygon.colour[np.maximum(poly, 0)]
    bg = np.asarray(background, float)
    # (no trace here: the paper writes each pixel's RGBI word in the Z test, "画像記憶に色情報を
    # 書き込む"; our float intensity buffer and this final packing pass are NumPy bookkeeping)
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
