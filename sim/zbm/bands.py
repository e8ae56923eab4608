"""One ZB/M frame drawn as two bands of scan lines on two simulator processes at once, stitched,
and checked bit for bit against the same frame drawn whole (issue 51, item 4).

Each band is the whole unit (the same build as the whole frame: same width, height, interleave
and input memory)
given only the edge pairs of its lines (``golden_model/zbm/band.py: edge_pair_band``: a pair
from above the band enters it on its first line, stepped there); its other lines are empty, so
the unit only reads them out. The bands run at the same time, each its own simulator process
(``SceneRun``'s workers). No overlap lines are needed: a band is a frame of its own, its pipeline
fills and drains inside its run. The split line balances the golden frame's fragments.
``own_height``: each band on a unit only as high as the band (lines renumbered from 0; one
build serves both bands when they are equally high), so no empty line is read out.

``python -m rasterhw.sim.zbm.bands --scene c300 --interleave 8`` prints the measurement as JSON
(docs/speed.md, "Item 4").
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm.band import edge_pair_band
from rasterhw.golden_model.zbm.unit import segment_fragments
from rasterhw.sim.engines.scene import run_job
from rasterhw.sim.zbm.scene import SPEED_BUILD, unit_job

__all__ = ["two_bands"]


def _split_line(eps, width: int, height: int) -> int:
    """The line before which half the frame's fragments are drawn (at least one line a band)."""
    segs = G.segment_generator(eps, height, width=width)
    per_line = np.bincount(segs.y[segment_fragments(segs)[0]], minlength=height)
    return int(np.clip(np.searchsorted(np.cumsum(per_line), per_line.sum() / 2), 1, height - 1))


def _run(job, engine: str) -> dict:
    t0 = time.perf_counter()
    d = run_job(job, engine)
    s0, s1 = job.tb.frame(job.params, d.got.words)
    return {"s0": s0, "s1": s1, "cycles": d.got.cycles, "cpu_s": d.got.cpu_s, "run_s": d.got.run_s,
            "wall_s": time.perf_counter() - t0,
            "mismatches": int(d.cmp["mismatches"]), "frames_ok": int(d.got.status.get("frames_ok", 0))}


def two_bands(scene: str = "c300", *, width: int = 512, height: int = 512, interleave: int = 8,
              engine: str = "verilator", build: dict | None = None, split: int | None = None,
              own_height: bool = False) -> dict:
    """The scene's frame whole, then as two bands at once, on ``engine``. ``own_height`` False: each
    band on the whole frame's unit (its other lines empty; split line ``split``, default: half the
    fragments each); True: each band on a unit as high as the band, its lines numbered from 0
    (split ``height // 2`` by default, so both bands share one build). Returns the cycles, the
    simulators' CPU seconds and clock-loop wall seconds (``run_s``) and each run's wall seconds,
    ``identical`` (the stitched frame's merge words equal the whole frame's, bit for bit), each
    run's ``mismatches`` against its golden frame, and ``wall_speedup`` (whole / bands)."""
    eps = G.edge_pairs(run_geometry(build_scene(scene), width, height))
    y0 = (height // 2 if own_height else _split_line(eps, width, height)) if split is None else int(split)
    if not 1 <= y0 < height:
        raise RasterhwError(f"two_bands: the split line must be in 1..{height - 1}, not {split!r}")
    kw = {"width": width, "interleave": interleave, "engine": engine}
    job = unit_job([eps], height=height, **kw)
    if engine == "verilator":   # sim zbm's build; the bands' input memories as deep as the whole frame's
        depth = max(map(len, job.stim.words.values())) + 2
        kw["build"] = {**SPEED_BUILD, "pgo": "train", "depth": depth} if build is None else build
        job = unit_job([eps], height=height, **kw)
    lines = ((0, y0), (y0, height))
    if own_height:
        bands = [unit_job([_renumbered(edge_pair_band(eps, a, b), a)], height=b - a, **kw) for a, b in lines]
    else:
        bands = [unit_job([edge_pair_band(eps, a, b)], height=height, **kw) for a, b in lines]
    if engine == "verilator":   # the builds (and their profiles), outside the timings
        for j in (job, *bands):
            _run(j, engine)
    whole = _run(job, engine)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max_workers=2) as pool:   # each run is its own simulator process
        top, bottom = pool.map(lambda j: _run(j, engine), bands)
    wall = time.perf_counter() - t0
    if own_height:
        stitched = {k: np.concatenate([top[k], bottom[k]]) for k in ("s0", "s1")}
    else:
        stitched = {k: np.concatenate([top[k][:y0], bottom[k][y0:]]) for k in ("s0", "s1")}
    identical = all(np.array_equal(stitched[k], whole[k]) for k in ("s0", "s1"))
    runs = {"whole": whole, "top": top, "bottom": bottom}
    return {"scene": scene, "width": width, "height": height, "interleave": interleave, "engine": engine,
            "split_line": y0, "own_height": own_height, "identical": identical,
            **{f"{n}_{k}": r[k] for n, r in runs.items()
               for k in ("cycles", "cpu_s", "run_s", "wall_s", "mismatches", "frames_ok")},
            "bands_wall_s": wall, "wall_speedup": whole["wall_s"] / wall,
            "cpu_ratio": (top["cpu_s"] + bottom["cpu_s"]) / whole["cpu_s"] if whole["cpu_s"] else None}


def _renumbered(eps, y0: int):
    """A band's edge pairs with its first line as line 0 (a unit as high as the band)."""
    eps.y = eps.y - y0
    return eps


if __name__ == "__main__":
    import argparse
    import json

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="c300")
    ap.add_argument("--interleave", type=int, default=8)
    ap.add_argument("--engine", default="verilator")
    ap.add_argument("--split", type=int, default=None)
    ap.add_argument("--own-height", action="store_true", help="each band on a unit as high as the band")
    a = ap.parse_args()
    print(json.dumps(two_bands(a.scene, interleave=a.interleave, engine=a.engine, split=a.split,
                               own_height=a.own_height)))
