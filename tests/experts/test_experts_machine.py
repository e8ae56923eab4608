"""EXPERTS registry entry, golden renderer and report rows."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.render import render
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim.registry import load, machines
from rasterhw.sim.report.rows import ROW_KEYS, SOURCES


def test_registered():
    m = machines()["experts"]
    (a,) = m.archs
    assert a.name == "experts" and {o.name for o in a.options} == {"aj", "model", "shadows", "sn", "pn"}
    assert load(a.render) is render
    assert callable(load(m.report)) and callable(load(m.bench))


def test_render_arch():
    r = render(build_scene("experts-solids"), 512, 512, arch="experts", aj="c", model="bit", sn=2, pn=4)
    assert r.rgb8.shape == (512, 512, 3) and r.rgb8.dtype == np.uint8
    assert r.stats["aj_pixels"] > 0 and r.stats["sn"] == 2 and r.pixels_written == 512 * 512
    n = render(build_scene("experts-solids"), 512, 512, aj="none", model="bit", sn=2, pn=4)
    assert np.count_nonzero(np.any(n.rgb8 != r.rgb8, axis=2)) > 0
    s = render(build_scene("experts-solids"), 512, 512, aj="c", model="bit", sn=2, pn=4, shadows="polygons")
    assert s.stats["shadowed_pixels"] > 0 and int(s.rgb8.sum()) < int(r.rgb8.sum())
    with pytest.raises(RasterhwError, match="shadows must be"):
        render(build_scene("experts-solids"), 512, 512, shadows="volumes")
    with pytest.raises(RasterhwError, match="aj must be"):
        render(build_scene("experts-solids"), 512, 512, aj="z")
    with pytest.raises(RasterhwError, match="at most 1023 px a side"):
        render(build_scene("experts-solids"), 2048, 512)


@pytest.mark.slow
def test_report_rows(tmp_path):
    rows, sections = load(machines()["experts"].report)(engine="pysim", progress=False, out_dir=tmp_path)
    assert rows and all(set(ROW_KEYS) <= set(r) and r["source"] in SOURCES for r in rows)
    assert all(r["measured"] is not None for r in rows)
    assert (tmp_path / "experts_fig41.png").exists() and (tmp_path / "experts_balance.png").exists()
    bal = {r["quantity"]: r["measured"] for r in rows if r["figure"] == "fig. 4.1 / text"}
    assert 4 <= bal["balance Pn (Q_s = Q_p), Fr=1000"] <= 10


@pytest.mark.parametrize("name", ["pxp", "dmm"])
def test_verilog_with_the_sim_block_name_names_the_verilog_block(name, tmp_path, capsys):
    """`rasterhw verilog pxp` (the `rasterhw sim` name) fails in one line naming experts-pxp."""
    from rasterhw.sim.cli.main import main
    with pytest.raises(SystemExit) as e:
        main(["verilog", name, "-o", str(tmp_path / "x.v")])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err
    assert f"did you mean experts-{name}?" in err
    assert not (tmp_path / "x.v").exists()
