"""The demo's pages (sim/report/demo.py) show every machine's image and numbers, its paper
figures beside ours, the cross-machine table, and fail on a mismatch."""

from __future__ import annotations

import re

from rasterhw.sim import registry
from rasterhw.sim.report import demo
from rasterhw.sim.report.rows import parse_table

REF = {"scene": "c300", "width": 8, "height": 8, "image": "c300-reference.png", "pixels_written": 40,
       "pixels_covered": 30, "wall_s": 0.1, "fragments": 41, "polygons_in": 2, "polygons_drawn": 2}


def _summary(mismatches: int) -> dict:
    sim = {"machine": "zbm", "block": "zbm", "scene": "c300", "help": "unit", "pixels_compared": 64,
           "mismatches": mismatches, "cycles": 500, "clock_hz": 25e6, "cycles_per_s": 1e6,
           "wall_s": 1.5, "image": "c300-zbm-verilator.png"}
    arch = {"machine": "zbm", "arch": "zbm", "help": "ZB/M <model>", "pixels_written": 39,
            "differing_from_reference": 7, "wall_s": 0.2, "image": "c300-zbm.png",
            "diff_image": "c300-zbm-diff.png", "colour_note": "its own <colour>"}
    cross = [demo._cross_row(sim, REF, "hdl:verilator"),
             demo._cross_row({"machine": "vzbuf", "scene": "c300", "block": "vz2", "time_s": 0.05,
                              "source": "model:vp200", "note": "no HDL"}, REF, "model:vp200")]
    machine = {"name": "zbm", "title": "ZB/M", "status": "s", "no_hdl": None, "golden": [arch],
               "hdl_runs": [sim], "report": "reproduction/zbm.html", "report_command": "rasterhw report zbm",
               "plots": ["reproduction/zbm_table1.png"], "fpga": demo._fpga_records()[:1],
               "paper_rows": [{"figure": "table 1", "quantity": "q<1>", "paper": "3", "measured": "3",
                               "ratio": "1.000", "unit": "cycles", "source": "hdl:pysim"}]}
    return {"scene": "c300", "engine": "verilator", "reference": REF, "archs": [arch], "sims": [sim],
            "machines": [machine], "cross_machine": cross}


def test_pages_show_every_image_and_number():
    s = _summary(0)
    md, page = demo._markdown(s), demo._html(s)
    for name in ("c300-reference.png", "c300-zbm.png", "c300-zbm-verilator.png"):
        assert name in md and name in page
    for name in ("c300-zbm-diff.png", "reproduction/zbm.html", "reproduction/zbm_table1.png"):
        assert name in page
    assert "| zbm | zbm | 39 | 7 |" in md
    assert "64 pixels compared, 0 mismatches; 500 HDL cycles = 0.02 ms at 25 MHz" in md
    assert "ZB/M &lt;model&gt;" in page and "[ok]" in page      # escaped, and the verdict shown
    assert "its own &lt;colour&gt;" in page and "q&lt;1&gt;" in page
    assert "[MISMATCH]" in demo._html(_summary(3))


def test_cross_machine_rows_are_arithmetic_on_the_run():
    s = _summary(0)
    hdl, model = s["cross_machine"]
    assert hdl["cycles"] == 500 and hdl["frame_ms"] == 500 / 25e6 * 1e3
    assert hdl["polygons_per_s"] == 2 / (500 / 25e6) and hdl["covered_pixels_per_clock"] == 30 / 500
    assert hdl["source"] == "hdl:verilator"
    assert model["cycles"] is None and model["frame_ms"] == 50.0 and model["source"] == "model:vp200"
    # a run that knows its frame's clocks (parallel units counted once) is taken at its word
    assert demo._cross_row({"machine": "m", "scene": "c300", "cycles": 900, "frame_cycles": 300},
                           REF, "hdl:pysim")["cycles"] == 300
    page = demo._html(s)
    assert "model:vp200" in page and "none given" in page


def test_headline_rows_pick_declared_rows_in_order_or_measured_ones():
    rows = parse_table((demo.REPRO / "vzbuf.md").read_text())
    picked = demo.headline_rows(rows, registry.machines()["vzbuf"].headline)
    assert picked and len(picked) <= demo.HEADLINE_MAX
    assert [r["figure"] for r in picked][:3] == ["table 3"] * 3
    assert {r["source"] for r in picked[:3]} == {"model:scalar", "model:vp100", "model:vp200"}
    fallback = demo.headline_rows(rows, ())
    assert fallback and all(r["paper"] not in ("—", "") and r["measured"] not in ("—", "") for r in fallback)


def test_every_machine_has_headline_rows_in_its_committed_report():
    """At least three rows with a paper value, a measured value and a source per machine: the
    page's "paper beside us" table is never empty."""
    for m in registry.machines().values():
        rows = demo.headline_rows(parse_table((demo.REPRO / f"{m.name}.md").read_text()), m.headline)
        full = [r for r in rows if r["paper"] not in ("—", "") and r["measured"] not in ("—", "") and r["source"]]
        assert len(full) >= 3, (m.name, rows)


def test_fpga_records_name_registered_blocks_with_the_papers_clocks():
    recs = demo._fpga_records()
    assert recs and all(r["block"] in registry.blocks() for r in recs)
    done = [r for r in recs if r["finished"]]
    assert done and all(r["luts"] and r["fmax"] for r in done)
    assert any(c["paper_mhz"] for r in done for c in r["fmax"])    # at least one paper clock beside Fmax


def test_report_pages_render_tables_and_plots(tmp_path):
    text = (demo.REPRO / "zbm.md").read_text()
    demo._render_report(text, tmp_path / "zbm.html", "Reproduction: ZB/M")
    page = (tmp_path / "zbm.html").read_text()
    assert "<table>" in page and page.count("<tr>") >= len(parse_table(text))
    for p in demo._plots(text):
        assert f'src="{p}"' in page
    assert re.search(r"<title>Reproduction: ZB/M</title>", page)


def test_page_names_each_papers_reference_and_the_run_that_made_it(tmp_path):
    s = _summary(0)
    s["machines"][0]["reference"] = demo.reference("zbm")
    s["machines"][0]["docs"] = "docs/zbm.html"
    s["about"] = demo.about()
    s["sims"][0].update(build_s=117.0, run_s=57.0, wall_s=174.0)
    md, page = demo._markdown(s), demo._html(s)
    for text in (md, page):
        assert "Paper: A. Nishimura, T. Kobayashi" in text and "Scanline Z-Buffer Merger" in text
        assert "venue not in the seed text" in text and "year not in the seed text" in text
        assert f"rasterhw {s['about']['rasterhw']}" in text and f"Amaranth {s['about']['amaranth']}" in text
        assert "build 117.0 s" in text and "run 57.0 s" in text and "174.0 s wall" in text
    assert 'href="docs/zbm.html"' in page and 'href="reproduction/zbm.html"' in page
    assert 'href="summary.json"' in page and 'href="report.md"' in page
    assert s["about"]["date"][:4].isdigit()


def test_every_machine_names_its_paper_from_its_seed():
    for name in registry.machines():
        ref = demo.reference(name)
        assert ref is not None, name
        assert ref["seed"] in ("000", "001", "002", "003", "004") and ref["title_en"]
        # what the seed does not give is said, never filled in
        for key in ("venue", "year"):
            assert ref[key] is not None or f"{key} not in the seed text" in ref["line"], (name, key)
        assert ref["authors"] or "authors not in the seed text" in ref["line"]


def test_cross_machine_chart_has_a_bar_per_timed_row(tmp_path):
    s = _summary(0)
    name = demo._cross_chart(s["cross_machine"], tmp_path / "cross.svg", "c300")
    svg = (tmp_path / name).read_text()
    assert "hdl:verilator" in svg and "model:vp200" in svg
    assert demo._cross_chart([], tmp_path / "none.svg", "c300") is None


def test_wave_snapshot_draws_the_clock_counter_and_stream_ports(tmp_path):
    """A short trace (as ``--waves`` with a window writes it) drawn as SVG: one row per signal,
    a one-bit signal as a line, a vector as boxes with its value in hex."""
    from rasterhw.sim.engines.waves import VcdWindow
    from rasterhw.sim.report.wavesvg import wave_svg

    head = ("$timescale 1 ns $end\n$scope module bench $end\n$scope module top $end\n$var wire 1 ! clk $end\n"
            "$var wire 1 # o__valid $end\n$var wire 1 $ o__ready $end\n$var wire 8 % o__payload $end\n"
            "$upscope $end\n$upscope $end\n$enddefinitions $end\n")
    body = "#0\n$dumpvars\n0!\n0#\n1$\nb0 %\n$end\n" + "".join(
        f"#{10 * k + 5}\n1!\n{k % 2}#\nb{k * 17 % 256:b} %\n#{10 * k + 10}\n0!\n" for k in range(30))
    vcd = tmp_path / "run.vcd"
    w = VcdWindow(open(vcd, "w"), 2, 20, counter=True)   # noqa: SIM115 - closed by w.close()
    w.write(head + body)
    w.close()
    svg = wave_svg(vcd, tmp_path / "w.svg", title="t <1>")
    text = svg.read_text()
    assert text.startswith("<svg") and "t &lt;1&gt;" in text
    for name in ("clk", "cycle", "o__valid", "o__ready", "o__payload"):
        assert f">{name}" in text, name
    assert ">22<" in text          # o__payload = 2 * 17 = 0x22 at edge 2, the window's first
    assert text.count("<polygon") >= 17 and text.count("<line") > 30
