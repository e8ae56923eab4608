"""ZB/M's first-level processors on the shared i860 model (golden_model/zbm/i860.py): the two
table 2 columns from the schedules, the polygon mix as an argument, bad input."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.i860 import I860, schedule
from rasterhw.golden_model.zbm import i860 as z


def test_columns_come_from_the_schedules():
    r = z.polygon_clocks()
    st = r["per_stage"]
    # C: every stage compiled; assembler: only transform and perspective hand-scheduled
    assert r["C"] == sum(v["compiler"] for v in st.values())
    assert r["assembler"] == (st["transform"]["assembler"] + st["perspective"]["assembler"]
                              + sum(st[s]["compiler"] for s in ("clip", "setup_triangle", "setup_edge_pair")))
    for s, v in st.items():
        assert v["assembler"] < v["compiler"], s  # pipelining never loses here
    assert r["clock_hz"] == z.CLOCK_HZ == 33.3e6
    assert r["assembler_polygons_per_s"] == pytest.approx(33.3e6 / r["assembler"])


def test_mix_moves_the_rate():
    tri = z.polygon_clocks(vertices=3, triangles=1, edge_pairs=2)
    quad = z.polygon_clocks(vertices=4, triangles=2, edge_pairs=3)
    assert quad["C"] > tri["C"] and quad["assembler"] > tri["assembler"]
    mapping = z.polygon_clocks(channels="mapping")
    assert mapping["C"] > tri["C"]  # six attribute channels, not five


def test_stage_clocks_are_the_schedule():
    cpu = I860(clock_hz=z.CLOCK_HZ)
    for s in z.STAGES:
        for mode in ("compiler", "assembler"):
            assert z.stage_clocks(s, cpu, mode=mode) == schedule(z.stage_program(s), cpu, mode)["clocks"]


def test_bad_input():
    with pytest.raises(RasterhwError, match="unknown stage"):
        z.stage_program("shade")
    with pytest.raises(RasterhwError, match="mode must be"):
        z.stage_program("transform", mode="phong")
    with pytest.raises(RasterhwError, match="vertices"):
        z.polygon_clocks(vertices=-1)
    with pytest.raises(RasterhwError, match="schedule must be"):
        z.stage_clocks("clip", mode="fortran")
