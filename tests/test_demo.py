"""The demo's pages (sim/report/demo.py) show every machine's image and numbers and fail on a mismatch."""

from __future__ import annotations

from rasterhw.sim.report import demo


def _summary(mismatches: int) -> dict:
    return {"scene": "c300", "engine": "verilator",
            "reference": {"scene": "c300", "width": 8, "height": 8, "image": "c300-reference.png",
                          "pixels_written": 40, "wall_s": 0.1, "fragments": 41, "polygons_in": 2,
                          "polygons_drawn": 1},
            "archs": [{"machine": "zbm", "arch": "zbm", "help": "ZB/M <model>", "pixels_written": 39,
                       "differing_from_reference": 7, "wall_s": 0.2, "image": "c300-zbm.png"}],
            "sims": [{"machine": "zbm", "block": "zbm", "scene": "c300", "help": "unit", "pixels_compared": 64,
                      "mismatches": mismatches, "cycles": 500, "clock_hz": 25e6, "cycles_per_s": 1e6,
                      "wall_s": 1.5, "image": "c300-zbm-verilator.png"}]}


def test_pages_show_every_image_and_number():
    s = _summary(0)
    md, page = demo._markdown(s), demo._html(s)
    for name in ("c300-reference.png", "c300-zbm.png", "c300-zbm-verilator.png"):
        assert name in md and name in page
    assert "| zbm | zbm | 39 | 7 |" in md
    assert "64 pixels compared, 0 mismatches; 500 HDL cycles = 0.02 ms at 25 MHz" in md
    assert "ZB/M &lt;model&gt;" in page and "[ok]" in page      # escaped, and the verdict shown
    assert "[MISMATCH]" in demo._html(_summary(3))
