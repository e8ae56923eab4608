"""Report rows and bench entries: shape and sources (one small scene; the full run is a command)."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.vzbuf.paper import COLS, T1, TABLES
from rasterhw.sim.report.rows import ROW_KEYS, SOURCES


def test_paper_tables_obey_their_identities():
    # area per polygon = pixels / processed polygons, the identity that fixes c200 and c100
    for n in COLS:
        assert abs(T1["pixels processed"][n] / T1["processed polygons"][n] - T1["area per polygon"][n]) < 0.06
    assert T1["processed polygons"]["c200"] == 593 and T1["processed polygons"]["c100"] == 298
    # totals within the paper's own rounding (a few printed totals are off by more; none here)
    for n in ("c300", "c50"):
        st = TABLES["table 5"]["VP200"]
        assert abs(sum(st[k][n] for k in "1234") - st["total"][n]) <= 1


@pytest.mark.slow
def test_report_rows_shape(tmp_path):
    from rasterhw.sim.vzbuf.report import rows

    out, sections = rows(scenes=("sp8",), out_dir=tmp_path)
    assert out and sections
    for r in out:
        assert set(ROW_KEYS) <= set(r) and (r["source"] in SOURCES or r["source"].startswith(("model:", "fit:")))
        assert r["measured"] is not None
    q = {r["quantity"] for r in out}
    assert "sp8: vz2 pixels whose visible polygon differs from the reference" in q
    assert (tmp_path / "vzbuf_tables.png").exists()
