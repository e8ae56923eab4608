"""The sparse report: rows carry the paper's S_k and the figure values (small sample here)."""

from __future__ import annotations

import pytest
from rasterhw.sim.registry import machines
from rasterhw.sim.report import ROW_KEYS, SOURCES


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from rasterhw.sim.sparse.report import rows

    out = tmp_path_factory.mktemp("sparse_report")
    return rows(samples=100, out_dir=out, scenes=("sp8",), s_grid=(0.1, 1.8, 10.0, 23.3, 100.0, 157.0, 1000.0),
                engine="none"), out  # HDL rows: tests/sparse/test_sparse_vp_*.py


def test_rows_well_formed(report):
    (rows, sections), out = report
    assert rows and sections
    for r in rows:
        assert set(ROW_KEYS) <= set(r) and r["source"] in SOURCES and r["measured"] is not None
    for fn in ("sparse_fig3.png", "sparse_fig4.png", "sparse_fig5_6.png"):
        assert (out / fn).stat().st_size > 10000
        assert any(fn in s for s in sections)


def test_s_k_formula_rows(report):
    (rows, _), _ = report
    sk = [r for r in rows if r["quantity"].startswith("S_") and "exact test" in r["quantity"]]
    assert len(sk) == 4
    for r in sk:
        if r["paper"] == 0:
            assert abs(r["formula"]) <= 0.05
        else:
            assert r["formula"] == pytest.approx(r["paper"], rel=0.01)


def test_figure_rows(report):
    (rows, _), _ = report
    for key in ("p_p", "Q_a"):
        got = [r for r in rows if r["quantity"].startswith(f"{key}(S=1000)")]
        assert len(got) == 4
    peaks = [r for r in rows if r["quantity"].startswith("peak R_p")]
    assert len(peaks) == 3 and all(r["formula"] >= 0.95 for r in peaks)


def test_registered():
    m = machines()["sparse"]
    assert m.report == "rasterhw.sim.sparse.report:rows"
    assert m.archs[0].name == "sparse" and m.archs[0].options[0].default == "4x4"


def test_arch_render_matches_reference():
    import numpy as np
    from rasterhw.golden_model.errors import RasterhwError
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import rasterise
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.sparse.render import render

    r = render(build_scene("sp8"), 256, 256, arch="sparse", matrix="2x2")
    ref = rasterise(run_geometry(build_scene("sp8"), 256, 256))
    assert np.array_equal(r.rgb8, ref.to_rgb8())
    assert r.pixels_written == ref.pixels_written
    with pytest.raises(RasterhwError):
        render("sp8", 500, 500, arch="sparse", matrix="4x4")
