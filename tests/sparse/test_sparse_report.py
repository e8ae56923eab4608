"""The sparse report: rows carry the paper's S_k and the figure values (small sample here)."""

from __future__ import annotations

import pytest
from rasterhw.sim.registry import machines
from rasterhw.sim.report.rows import ROW_KEYS, SOURCES


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from rasterhw.sim.sparse.report import rows

    out = tmp_path_factory.mktemp("sparse_report")
    return rows(samples=100, out_dir=out, scenes=("sp8",), s_grid=(0.1, 1.8, 10.0, 23.3, 100.0, 157.0, 1000.0),
                engine="none", coupled_size=64, coupled_matrices=("2x2",), load_triangles=40,
                coupled_vp_matrices=("2x2",), stack_size=64, coupled_scene="c50", stack_scenes=("c50",),
                stack_sizes=(64,)), out
    # HDL rows: tests/sparse/test_sparse_vp_*.py; the coupled rows at a useful size: the fixture below


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
    # at 45 degrees (1)'s perimeter term is exact: the measured S_k is the paper's (k = 2, 3, 4)
    rot = [r for r in rows if "at 45° rotation" in r["quantity"]]
    assert len(rot) == 3
    for r in rot:
        assert r["measured"] == pytest.approx(r["paper"], rel=0.15)
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


@pytest.fixture(scope="module")
def coupled(tmp_path_factory):
    from pathlib import Path

    from rasterhw.sim.report.rows import make_row
    from rasterhw.sim.sparse.report import _coupled_rows

    out: list[dict] = []

    def row(fig, qty, **kw):
        out.append(make_row("sparse", fig, qty, **kw))

    d = Path(tmp_path_factory.mktemp("sparse_coupled"))
    sec = _coupled_rows(row, d, size=128, matrices=("2x2", "4x4", "8x8"), load_triangles=300,
                        vp_matrices=("4x4",), stack_size=64, scene="c50")
    return out, sec, d


def test_coupled_rows_frame_against_fifo_depth(coupled):
    rows, sec, d = coupled
    for m in ("2x2", "4x4", "8x8"):
        fr = [r for r in rows if r["quantity"].startswith(f"c50 128x128, {m}: frame cycles, FIFO depth")
              and r["figure"] == "FIFO sizing (coupled)"]
        assert len(fr) == 7 and all(r["source"] == "golden" and r["formula"] is None for r in fr)
        vals = [r["measured"] for r in fr]
        assert vals == sorted(vals, reverse=True) and vals[0] > vals[-1]
        st = [r for r in rows if r["quantity"].startswith(f"c50 128x128, {m}: broadcast stall cycles")
              and r["figure"] == "FIFO sizing (coupled)"]
        assert st[0]["measured"] > 0
        ratio = [r for r in rows if r["quantity"].startswith(f"c50 128x128, {m}: stack frame / pipeline frame")]
        assert ratio[0]["measured"] > 1 and ratio[0]["formula"] > 1
    assert (d / "sparse_fifo.png").stat().st_size > 10000 and any("sparse_fifo.png" in s for s in sec)
    for key in ("R_p = sum_i", "R_p of the coupled frame", "Q_a = T_mono", "Q_p = Q_a R_p"):
        got = [r for r in rows if key in r["quantity"]]
        assert len(got) == 3 and all(0 < r["measured"] <= 1 and 0 < r["formula"] <= 1 for r in got), key
    kp = [r for r in rows if r["figure"] == "(5) k_p/k_e"]
    assert len(kp) == 2 and all(r["measured"] > 1 for r in kp)


def test_load_is_highest_near_s_k(coupled):
    rows, _, _ = coupled
    load = [r for r in rows if r["quantity"].startswith("R_p of a frame of 300 random triangles")]
    assert len(load) == 6  # 4x4, 8x8, 16x16 at S_k and at 1000
    for near, far in zip(load[::2], load[1::2], strict=True):
        assert near["paper"] == 1.0 and far["paper"] is None
        assert near["measured"] > far["measured"] and near["formula"] > far["formula"]


def test_coupled_rows_with_the_hdl_processors(coupled):
    rows, sec, _ = coupled
    got = {r["quantity"].split(": ", 1)[1]: r for r in rows if r["figure"] == "FIFO sizing (coupled, HDL VPs)"}
    assert len(got) == 10  # 4x4: three depths x (frame, stalls, peak) + the ratio
    for D in (1, 8, 64):
        assert got[f"largest FIFO peak, FIFO depth {D} (never above D)"]["measured"] <= D
        assert got[f"frame cycles, FIFO depth {D} (video processors: the HDL's cycle model)"]["measured"] > 0
    assert got["broadcast stall cycles, FIFO depth 1"]["measured"] > 0
    assert got["frame with FIFO depth 1 / with depth 64"]["measured"] >= 1.0
    assert any("HDL video processors" in s for s in sec)


def test_stack_rows(coupled):
    rows, sec, _ = coupled
    got = [r for r in rows if r["figure"] == "(8) / stack"]
    assert len(got) == 3 and all(r["source"] == "golden" for r in got)
    assert got[0]["measured"] == 0 and got[1]["measured"] == 1
    assert 1 < got[2]["measured"] <= got[2]["formula"]
    assert any("depth first" in s for s in sec)


def test_gp_rate_rows(coupled):
    rows, _, _ = coupled
    got = [r for r in rows if r["figure"] == "FIFO sizing (GP at the matrix's rate)"]
    assert len(got) == 8 and all(r["source"] == "golden" and r["measured"] > 0 for r in got)
    server = [r["measured"] for r in got if "as servers" in r["quantity"]]
    assert server == sorted(server, reverse=True)  # deeper FIFOs never slow the frame


def test_coupled_hdl_rows_in_pysim():
    """The report's whole-matrix HDL rows (pysim: a small frame, 2x2, FIFO depths 1 and 8, both inner
    buffer depths): every counter equal to the golden coupled cycle model, R_p and Q_p from HDL frame
    time and on the measured window counts beside the formulas, sources hdl:pysim; (9) holds more
    closely with eight-entry inner FIFOs than with two-entry buffers."""
    from rasterhw.sim.sparse.report import _coupled_hdl_rows

    rows = []

    def row(fig, qty, *, paper, formula, measured, unit, source):
        rows.append({"figure": fig, "quantity": qty, "formula": formula, "measured": measured, "source": source})

    sec = _coupled_hdl_rows(row, "pysim", False)
    assert sec and all(r["source"] == "hdl:pysim" for r in rows)
    diff = [r for r in rows if "HDL minus the golden" in r["quantity"] or "counters differing" in r["quantity"]
            or "pixels differing" in r["quantity"]]
    assert len(diff) == 12 and all(r["measured"] == 0 for r in diff)
    peaks = {r["quantity"].split("FIFO depth ")[1].split(" ")[0]: r["measured"] for r in rows
             if "largest FIFO peak" in r["quantity"]}
    assert peaks["1"] == 1 and 1 <= peaks["8"] <= 8
    stall1 = next(r for r in rows if "stall cycles, FIFO depth 1" in r["quantity"])
    assert stall1["measured"] > 0
    rp = next(r for r in rows if "R_p, (10) on measured window counts" in r["quantity"])
    assert 0 < rp["measured"] <= 1 and 0 < rp["formula"] <= 1
    qp = next(r for r in rows if r["figure"] == "(12) / HDL counts")
    assert 0 < qp["measured"] <= 1
    rp_t = [r for r in rows if ": R_p from HDL frame time" in r["quantity"]]
    qp_t = [r for r in rows if "Q_p from HDL frame time" in r["quantity"]]
    assert len(rp_t) == 2 and len(qp_t) == 1
    # time-based load below the count-based one: the frame is longer than the busiest stage's tests
    assert all(0 < r["measured"] < rp["measured"] for r in rp_t[:1]) and 0 < qp_t[0]["measured"] < qp["measured"]
    nine = {r["quantity"].split(", ")[3]: r["measured"] for r in rows if r["figure"] == "(9) / HDL frame time"
            and "FIFO depth 8" in r["quantity"]}
    assert 1 <= nine["eight-entry inner FIFOs (ours"] < nine["two-entry inner buffers (ours)"]


def test_stack_against_pipeline_rows(report):
    (rows, sections), _ = report
    got = {r["quantity"]: r for r in rows if r["figure"] == "(8) / (9) stack vs pipeline"}
    lab = "c50 64x64, 4x4"
    st = got[f"{lab}: frame cycles, stack (golden = HDL stack processor), input FIFO depth 64"]["measured"]
    pv = got[f"{lab}: frame cycles, pipeline (HDL VP cycle model), input FIFO depth 64"]["measured"]
    sv = got[f"{lab}: frame cycles, pipeline as a server (9), input FIFO depth 64"]["measured"]
    assert st > pv > 0 and st > sv > 0          # one test unit against n = 4 stage units
    st4 = next(r["measured"] for q, r in got.items() if q.startswith(f"{lab}: frame cycles, stack, depth + RGB"))
    assert st4 > st
    ratio = next(r for q, r in got.items() if q.startswith(f"{lab}: stack frame / pipeline frame"))
    assert ratio["measured"] == pytest.approx(st / pv, abs=1e-4) and 1 < ratio["formula"] <= 4
    for q, r in got.items():
        if "busy / frame" in q or "unit load" in q:
            assert 0 < r["measured"] <= 1, q
    assert any("Stack-based against pipeline" in s for s in sections)


def test_stack_hdl_rows_on_pysim():
    from rasterhw.sim.sparse.report import _stack_hdl_rows

    rows = []

    def row(fig, qty, **kw):
        rows.append({"figure": fig, "quantity": qty, **kw})

    sec = _stack_hdl_rows(row, "pysim", scenes=())
    assert len(rows) == 6 and all(r["source"] == "hdl:pysim" for r in rows)
    pix, cnt, busy, pix4, cnt4, busy4 = (r["measured"] for r in rows)
    assert pix == cnt == pix4 == cnt4 == 0 and 100 < busy < busy4    # parameters cost cycles as (5) prices them
    assert sec[-1].count("| 0 | 0 of") == 2


@pytest.mark.slow   # ~20 s: two pysim matrices; the same HDL is checked quickly in test_sparse_stack_hdl.py
def test_stack_matrix_hdl_rows_on_pysim():
    from rasterhw.sim.sparse.report import _stack_matrix_hdl_rows

    rows = []

    def row(fig, qty, **kw):
        rows.append({"figure": fig, "quantity": qty, **kw})

    sec = _stack_matrix_hdl_rows(row, "pysim")
    assert len(rows) == 9 and all(r["source"] == "hdl:pysim" for r in rows)
    qa = rows.pop()   # Q_a from HDL frame time (the stack matrix against the monoprocessor with a stack)
    assert "Q_a from HDL frame time" in qa["quantity"] and 0 < qa["measured"] <= 1
    got = {r["quantity"].split(": ", 1)[1]: r["measured"] for r in rows}
    for D in (8, 1):
        pre = f"coupled matrix of HDL stack processors, input FIFO depth {D}: "
        assert got[pre + "frame cycles HDL minus golden"] == 0
        assert got[pre + "broadcast stall cycles HDL minus golden"] == 0
        assert got[pre + "pixels differing from the golden search (of 256)"] == 0
    assert "| yes |" in sec[-1] and "NO" not in sec[-1]


def test_large_matrix_rows_stay_with_their_reason():
    """The 8x8 and 16x16 matrices at 1024² in HDL: a fast run and pysim keep every row unmeasured with
    its reason and source "not run" (what measures it in ``source_when_run``; the formula column
    filled); an engine that is no HDL simulator gives none."""
    from rasterhw.sim.report.rows import NOT_RUN, make_row
    from rasterhw.sim.sparse.report import (
        LARGE_ENGINE_SKIP,
        LARGE_FAST_SKIP,
        _large_matrix_hdl_rows,
    )

    for engine, fast, why in (("verilator", True, LARGE_FAST_SKIP), ("pysim", False, LARGE_ENGINE_SKIP)):
        rows, sec = _large_matrix_hdl_rows(engine, fast=fast, progress=False)
        assert len(rows) == 14 and all(r["measured"] is None and r["reason"] == why and r["source"] == NOT_RUN
                                       and r["source_when_run"] == "hdl:verilator" for r in rows)
        assert sum("c300 1024x1024, 8x8," in r["quantity"] for r in rows) == 7
        assert sum("c300 1024x1024, 16x16," in r["quantity"] for r in rows) == 7
        rp = [r["formula"] for r in rows if "R_p from HDL frame time" in r["quantity"]]
        assert len(rp) == 4 and all(0 < f < 1 for f in rp) and rp[0] == rp[1] and rp[2] == rp[3]
        assert why in sec[-1]
        for r in rows:   # the report's own check of a row accepts them
            make_row(r["system"], r["figure"], r["quantity"], paper=r["paper"], formula=r["formula"],
                     measured=None, unit=r["unit"], source=r["source_when_run"], reason=r["reason"], run=False)
    assert _large_matrix_hdl_rows("none", fast=False, progress=False) == ([], [])


@pytest.mark.slow   # the 8x8 matrix at 1024² in Verilator: 2 min on a quiet machine, 12 min (473 s cold build) at load 20
def test_large_matrix_rows_on_verilator(monkeypatch):
    """The full report's row function on the 8x8 matrix (16x16 takes about 8 min more): every counter and
    pixel equal to the golden models, (9) within 1 % with the default processor, R_p from HDL frame time
    beside (10)."""
    import rasterhw.sim.sparse.report as rep

    monkeypatch.setattr(rep, "LARGE_MATRICES", ("8x8",))
    rows, sec = rep._large_matrix_hdl_rows("verilator", fast=False, progress=False)
    assert len(rows) == 7 and all(r["measured"] is not None and r["source"] == "hdl:verilator" for r in rows)
    diff = [r for r in rows if r["formula"] == 0]
    assert len(diff) == 3 and all(r["measured"] == 0 for r in diff)
    (nine,) = [r for r in rows if r["figure"] == "(9) / HDL frame time"]
    assert 1 <= nine["measured"] < 1.01
    rp = [r for r in rows if "R_p from HDL frame time" in r["quantity"]]
    assert 0 < rp[0]["measured"] < rp[1]["measured"] < 1 and abs(rp[0]["measured"] - rp[0]["formula"]) < 0.1
    assert "| 8x8 |" in sec[-1]
