"""ZB/M cycles on real scenes: where the paper's 5 x 5 edge-pair assumption does (not) hold.

The paper's Table 1 (seed 003, sec. 6.1) assumes every polygon becomes 2 edge pairs of 5 lines
x 5 pixels. This module runs real scenes through the golden geometry pipeline
(:func:`.pipeline.run_geometry`), the level-1 edge-pair split (:func:`.zbm.edge_pairs`) and the
event-level cycle model (:func:`rasterhw.golden_model.zbm.cycles.event_cycles`) and reports, per scene and
interleave: edge pairs per polygon, lines per edge pair, the segment-length distribution,
cycles per edge pair and polygons/s at 25 MHz.

Two level-1 variants (``level``):

``"triangle"``  what :func:`.zbm.edge_pairs` emits: the pipeline fans every polygon into
                triangles and each triangle is split at its middle vertex (<= 2 pairs per
                triangle, so a quad gives up to 4).
``"polygon"``   the paper's level 1, "each polygon is expanded into edge pairs" (cond. 1):
                :func:`polygon_edge_pairs` cuts the triangle pairs of one polygon at all of the
                polygon's vertex rows and joins the pieces that abut on the fan diagonals, so a
                convex polygon gives one pair per band between distinct vertex rows (a triangle
                or the zbm-5x5 diamond: 2). Coverage is identical (the joined pair's left and
                right edges are the outer edges of the chain, bit for bit); the attribute
                values of a joined pair are the leftmost piece's, so the joined stream is for
                **counting cycles**, not for rendering.

Polygons/s = drawn polygons x clock / cycles, reported without and with the paper's factor 2
for skew between neighbouring chips (cond. 7; not in the event model, rule R5), both from the
segment-loop cycles (``loop_cycles``, what Table 1 counts) and from the frame cycles including
the merge-bus readout of every line (``frame_cycles``, rule R4).

``python -m rasterhw.golden_model.zbm.scene_cycles [scene or .obj/.ply ...]`` prints the
table quoted in ``docs/zbm_area.md``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.zbm import EdgePairs, edge_pairs, segment_generator
from rasterhw.golden_model.zbm import cycles as zbm_cycles
from rasterhw.golden_model.zbm.cycles import (
    CLOCK_HZ,
    PAPER_TABLE1_KPOLYS,
    event_cycles,
    formula_cycles_per_edge_pair,
)
from rasterhw.golden_model.zbm.formats import (
    INTERLEAVES,
    MAX_HEIGHT,
    MAX_WIDTH,
    check_interleave,
    wrap,
)

__all__ = ["LEVELS", "SEG_LEN_BINS", "polygon_edge_pairs", "scene_edge_pairs", "scene_rows",
           "scene_table", "format_table"]

LEVELS = ("polygon", "triangle")
#: segment-length histogram bins: [lo, hi) in pixels
SEG_LEN_BINS = (1, 2, 4, 6, 8, 16, 32, 64, MAX_WIDTH + 1)
#: two pieces abut if the right edge of one and the left edge of the next differ by at most this
#: (Q.40 units = 2**-30 px). Stepping a pair down m <= 511 lines adds at most m units of floor
#: error, so the same fan diagonal computed in two triangles agrees to < 512 units.
ABUT_TOL = 1 << 10


def polygon_edge_pairs(eps: EdgePairs, poly_id: np.ndarray) -> EdgePairs:
    """Triangle-level edge pairs -> polygon-level edge pairs (the paper's level 1).

    Parameters
    ----------
    eps : EdgePairs
        From :func:`.zbm.edge_pairs`; ``eps.tag`` is the triangle index.
    poly_id : (T,) int
        Source polygon of every triangle (``ScreenTriangles.poly_id``).

    Every pair is cut at all line boundaries (tops and bottoms) of its polygon's pairs; a piece
    starting ``m`` lines below its pair's top is stepped exactly as the segment generator steps
    (``x += m dx/dy`` with the 56-bit wrap, likewise len and the attributes). Pieces of one
    polygon on the same lines are sorted by x; a piece whose left edge meets the previous
    piece's right edge (within :data:`ABUT_TOL`, and with the same slope when it spans more than
    one line) is joined to it. Returns the joined pairs in FIFO order (top line, then polygon).
    """
    n = len(eps)
    poly_id = np.asarray(poly_id, np.int64)
    if n == 0:
        return eps
    if eps.tag.max() >= poly_id.size or eps.tag.min() < 0:
        raise RasterhwError("polygon_edge_pairs: poly_id does not cover every edge pair's triangle")
    poly = poly_id[eps.tag]
    top, bot = eps.y, eps.y + eps.h
    # the set of boundaries of every polygon, as sorted unique (poly, line) keys
    key = np.unique(np.concatenate([poly * (MAX_HEIGHT + 1) + top, poly * (MAX_HEIGHT + 1) + bot]))
    kp, kl = key // (MAX_HEIGHT + 1), key % (MAX_HEIGHT + 1)
    first = np.searchsorted(key, poly * (MAX_HEIGHT + 1) + top)
    last = np.searchsorted(key, poly * (MAX_HEIGHT + 1) + bot)      # index of the bottom key
    cnt = last - first
    src = np.repeat(np.arange(n), cnt)
    b = np.arange(src.size) - np.repeat(np.cumsum(cnt) - cnt, cnt) + first[src]
    assert np.all(kp[b] == poly[src]) and np.all(kp[b + 1] == poly[src])
    y0, y1 = kl[b], kl[b + 1]
    m = (y0 - eps.y[src])[:, None]
    x = wrap(eps.x[src] + m[:, 0] * eps.dxdy[src])
    ln = wrap(eps.len[src] + m[:, 0] * eps.dlendy[src])
    val = wrap(eps.val[src] + m * eps.ddy[src])
    h = y1 - y0
    # sort pieces: polygon, top line, left edge, right edge
    o = np.lexsort((x + ln, x, y0, poly[src]))
    src, y0, h, x, ln, val = src[o], y0[o], h[o], x[o], ln[o], val[o]
    p = poly[src]
    dxl = eps.dxdy[src]
    dxr = eps.dxdy[src] + eps.dlendy[src]
    same = (p[1:] == p[:-1]) & (y0[1:] == y0[:-1])
    meet = np.abs(x[1:] - (x[:-1] + ln[:-1])) <= ABUT_TOL
    slope = (h[1:] == 1) | (dxl[1:] == dxr[:-1])
    join = np.concatenate([[False], same & meet & slope])
    run = np.cumsum(~join) - 1
    starts = np.flatnonzero(~join)
    ends = np.append(starts[1:], src.size) - 1
    x_m, x_e = x[starts], x[ends] + ln[ends]
    out = {"y": y0[starts], "h": h[starts], "x": x_m, "dxdy": dxl[starts], "len": x_e - x_m,
           "dlendy": dxr[ends] - dxl[starts], "val": val[starts], "ddy": eps.ddy[src[starts]],
           "ddx": eps.ddx[src[starts]], "tag": eps.tag[src[starts]]}
    assert run[-1] + 1 == starts.size
    # one-line pieces carry dx/dy = 0 in the triangle stream; keep that convention
    one = out["h"] == 1
    out["dxdy"] = np.where(one, 0, out["dxdy"])
    out["dlendy"] = np.where(one, 0, out["dlendy"])
    fo = np.lexsort((out["tag"], out["y"]))
    return EdgePairs(**{k: np.asarray(v[fo], np.int64) for k, v in out.items()}, mode=eps.mode)


def _load(scene) -> Scene:
    if isinstance(scene, Scene):
        return scene
    from rasterhw.golden_model.meshio import load_scene

    return load_scene(str(scene))


def scene_edge_pairs(scene, *, level: str = "polygon", width: int = MAX_WIDTH,
                     height: int = MAX_HEIGHT) -> tuple[EdgePairs, ScreenTriangles]:
    """Scene (name, .obj/.ply path or :class:`Scene`) -> (edge pairs at ``level``, triangles)."""
    if level not in LEVELS:
        raise RasterhwError(f"level must be one of {LEVELS}, not {level!r}")
    from rasterhw.golden_model.pipeline import run_geometry

    tris = run_geometry(_load(scene), width, height)
    eps = edge_pairs(tris)
    if level == "polygon":
        eps = polygon_edge_pairs(eps, tris.poly_id)
    return eps, tris


def _seg_stats(lens: np.ndarray) -> dict:
    if lens.size == 0:
        return {"seg_len_mean": 0.0, "seg_len_p10": 0, "seg_len_p50": 0, "seg_len_p90": 0,
                "seg_len_max": 0, "seg_len_hist": {}}
    hist, _ = np.histogram(lens, bins=SEG_LEN_BINS)
    names = [f"{lo}" if hi - lo == 1 else f"{lo}-{hi - 1}" for lo, hi in zip(SEG_LEN_BINS[:-1], SEG_LEN_BINS[1:],
                                                                               strict=True)]
    return {"seg_len_mean": float(lens.mean()), "seg_len_p10": int(np.percentile(lens, 10)),
            "seg_len_p50": int(np.percentile(lens, 50)), "seg_len_p90": int(np.percentile(lens, 90)),
            "seg_len_max": int(lens.max()),
            "seg_len_hist": {k: int(v) for k, v in zip(names, hist, strict=True)}}


def scene_rows(scene, *, interleaves: Iterable[int] = INTERLEAVES, level: str = "polygon",
               width: int = MAX_WIDTH, height: int = MAX_HEIGHT, clock_hz: float = CLOCK_HZ,
               skew: float = 2.0, hdl: bool = False) -> list[dict]:
    """One row per interleave for one scene at one level (see :func:`scene_table`)."""
    interleaves = tuple(interleaves)
    for i in interleaves:
        check_interleave(i)
    sc = _load(scene)
    eps, tris = scene_edge_pairs(sc, level=level, width=width, height=height)
    segs = segment_generator(eps, height, width=width)
    drawn = int(np.unique(tris.poly_id).size)
    n_eps = len(eps)
    lens = segs.len
    base = {"scene": sc.name, "level": level, "polygons": int(sc.n_polygons), "polygons_drawn": drawn,
            "triangles": tris.n_triangles, "edge_pairs": n_eps,
            "edge_pairs_per_polygon": n_eps / max(drawn, 1),
            "lines_per_edge_pair": float(eps.h.mean()) if n_eps else 0.0,
            "segments": int(lens.size), "empty_segments": int(segs.empty.sum()),
            "segments_per_edge_pair": lens.size / max(n_eps, 1),
            "pixels": int(lens.sum()), **_seg_stats(lens)}
    rows = []
    for i in interleaves:
        e = event_cycles(eps, height, width=width, interleave=i)
        loop, frame = int(e["loop_cycles"]), int(e["frame_cycles"])
        kp = lambda c, s=1.0: drawn * clock_hz / c / s / 1e3 if c else math.inf  # noqa: E731
        rows.append({**base, "interleave": i,
                     "len_chip_mean": float((-(-lens // i)).mean()) if lens.size else 0.0,
                     "loop_cycles": loop, "frame_cycles": frame,
                     "cycles_per_edge_pair": loop / max(n_eps, 1),
                     "cycles_per_polygon": loop / max(drawn, 1),
                     "kpolys_loop": kp(loop), "kpolys_loop_skew": kp(loop, skew),
                     "kpolys_frame": kp(frame), "kpolys_frame_skew": kp(frame, skew),
                     "paper_cycles_per_edge_pair": formula_cycles_per_edge_pair(i),
                     "paper_kpolys": PAPER_TABLE1_KPOLYS[i]})
        if hdl:
            # cycle-exact model of hdl/zbm/unit.py (whole frame, merge readout included)
            hc = int(zbm_cycles.hdl_cycles(eps, height, width=width, interleave=i)["cycles"])
            rows[-1].update({"hdl_cycles": hc, "hdl_cycles_per_edge_pair": hc / max(n_eps, 1),
                             "kpolys_hdl": kp(hc)})
    return rows


def scene_table(scenes=("zbm-5x5", "c300", "sp27"), interleaves=(1, 2, 4, 8, 16), *,
                levels: Iterable[str] = ("polygon",), width: int = MAX_WIDTH, height: int = MAX_HEIGHT,
                clock_hz: float = CLOCK_HZ, hdl: bool = False) -> list[dict]:
    """Cycles per edge pair and polygons/s of one ZB/M unit on real scenes.

    Parameters
    ----------
    scenes : built-in scene names, .obj/.ply paths or :class:`Scene` objects.
    interleaves : chips per unit (1, 2, 4, 8, 16).
    levels : ``"polygon"`` (the paper's level 1, default) and/or ``"triangle"``.
    width, height : frame (<= 512 x 512, the ZB/M line memories).

    Returns
    -------
    list of dict, one per (scene, level, interleave): scene facts (``polygons_drawn``,
    ``edge_pairs``, ``edge_pairs_per_polygon``, ``lines_per_edge_pair``, ``segments``,
    ``seg_len_mean``/``p10``/``p50``/``p90``/``max``/``hist``) and per interleave
    ``len_chip_mean``, ``loop_cycles``, ``frame_cycles``, ``cycles_per_edge_pair``,
    ``kpolys_loop`` (K polygons/s from the loop cycles), ``kpolys_loop_skew`` (same / 2, the
    paper's cond. 7, comparable to Table 1), ``kpolys_frame``/``kpolys_frame_skew`` (including
    the merge readout), and the paper's formula and Table 1 values for the interleave.
    With ``hdl=True`` also ``hdl_cycles`` (``zbm.cycles.hdl_cycles``: the cycle-exact model of
    ``hdl/zbm/unit.py``, whole frame incl. merge readout, ~1 s per row), its per-pair value and
    ``kpolys_hdl``.
    """
    if isinstance(scenes, (str, Scene)):
        scenes = (scenes,)
    rows = []
    for s in scenes:
        for lv in levels:
            rows += scene_rows(s, interleaves=interleaves, level=lv, width=width, height=height,
                               clock_hz=clock_hz, hdl=hdl)
    return rows


def format_table(rows: list[dict]) -> str:
    """Markdown tables: scene facts, then cycles / edge pair and K polygons/s per interleave."""
    seen, facts = set(), []
    for r in rows:
        k = (r["scene"], r["level"])
        if k not in seen:
            seen.add(k)
            facts.append(r)
    out = ["| scene | level | polygons drawn | edge pairs | pairs / polygon | lines / pair | segments "
           "| segs / pair | seg len mean | p10 / p50 / p90 / max |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in facts:
        out.append(f"| {r['scene']} | {r['level']} | {r['polygons_drawn']} | {r['edge_pairs']} | "
                   f"{r['edge_pairs_per_polygon']:.2f} | {r['lines_per_edge_pair']:.2f} | {r['segments']} | "
                   f"{r['segments_per_edge_pair']:.2f} | {r['seg_len_mean']:.2f} | "
                   f"{r['seg_len_p10']} / {r['seg_len_p50']} / {r['seg_len_p90']} / {r['seg_len_max']} |")
    out += ["", "| scene | level | seg len histogram (" + ", ".join(facts[0]["seg_len_hist"]) + " px) |",
            "|---|---|---|"]
    for r in facts:
        tot = max(r["segments"], 1)
        out.append(f"| {r['scene']} | {r['level']} | "
                   + ", ".join(f"{100 * v / tot:.0f}%" for v in r["seg_len_hist"].values()) + " |")
    hdl = "hdl_cycles" in rows[0]
    out += ["", "| scene | level | I | len_chip mean | cycles / pair (paper 5x5) | K poly/s loop | "
            "loop / 2 (paper) | frame | frame / 2 |" + (" HDL cycles / pair | HDL K poly/s |" if hdl else ""),
            "|---|---|---|---|---|---|---|---|---|" + ("---|---|" if hdl else "")]
    for r in rows:
        out.append(f"| {r['scene']} | {r['level']} | {r['interleave']} | {r['len_chip_mean']:.2f} | "
                   f"{r['cycles_per_edge_pair']:.1f} ({r['paper_cycles_per_edge_pair']}) | "
                   f"{r['kpolys_loop']:.1f} | {r['kpolys_loop_skew']:.1f} ({r['paper_kpolys']}) | "
                   f"{r['kpolys_frame']:.1f} | {r['kpolys_frame_skew']:.1f} |"
                   + (f" {r['hdl_cycles_per_edge_pair']:.1f} | {r['kpolys_hdl']:.1f} |" if hdl else ""))
    return "\n".join(out)


def _main(argv: list[str]) -> None:  # pragma: no cover - prints the tables in docs/zbm_area.md
    scenes = argv or ["zbm-5x5", "c300", "sp27"]
    print(format_table(scene_table(scenes, levels=("polygon",), hdl=True)))
    print()
    print(format_table(scene_table(scenes, levels=("triangle",))))


if __name__ == "__main__":  # pragma: no cover
    _main(sys.argv[1:])
