"""The SNU frame end to end (sim/snu/scene.py): producer gaps from the i860 model, the golden
schedule, and (marker cocotb: plain Verilator) the pixel-bus HDL drawing a whole frame with
clear and swap, bit for bit and clock for clock against the golden model."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.snu import i860
from rasterhw.golden_model.snu.gouraud import scan_convert, setup_spans
from rasterhw.golden_model.snu.render import render
from rasterhw.sim.snu import scene as F


def _tris(name="sp27", w=80, h=64):
    return run_geometry(build_scene(name), w, h, z_bits=24, z_far_is_zero=True)


def test_producer_gaps_follow_the_model():
    tris = _tris()
    s = scan_convert(tris)
    cpu = i860.I860()
    p = F.producer_gaps(tris, s, cpu)
    sc = i860.scan_clocks(cpu)
    ratio = cpu.clock_hz / 12.5e6
    assert p["ratio"] == ratio == 3.2
    g = p["gaps"]
    assert g.shape == (len(s),) and g.min() >= 0
    # a pixel that continues its span waits only for the inner loop: ceil(4 / 3.2) - 1 = 1
    spans = setup_spans(tris)
    first = np.zeros(len(s), dtype=bool)
    first[(np.cumsum(spans["n"]) - spans["n"])[spans["n"] > 0]] = True
    assert np.all(g[~first] == int(np.ceil(sc["pixel"] / ratio)) - 1)
    # a span's first pixel also pays at least the outer loop of its line
    first[[np.flatnonzero(s.pipe == q)[0] for q in (0, 1)]] = False  # their gap is the fill
    heads = np.flatnonzero(first)
    assert np.all(g[heads] >= int(np.ceil((sc["pixel"] + sc["span"]) / ratio)) - 1)
    # each pipeline's first write carries the geometry fill (the three groups' clocks)
    assert all(fw >= sum(p["group_clocks"]) for fw in p["first_work"])
    assert p["group_clocks"] == [74 + 43, 64 + 72, 24 + 39 + 21]  # docs/snu_geometry.md, assembler
    # sp27 at 80 x 64 has ~1-pixel triangles: the scan converter would outrun the traversal
    # processor (one triangle per pipeline per 216 clocks); 100-pixel triangles never do
    assert p["geometry_starves"]
    big = _tris("snu-100px", 1280, 1024)
    assert not F.producer_gaps(big, scan_convert(big))["geometry_starves"]
    assert all(t > 0 for t in p["scan_s"])


def test_golden_schedule():
    tris = _tris()
    s = scan_convert(tris)
    p = F.producer_gaps(tris, s)
    sch = F.golden_schedule(s, p["gaps"], p["first_work"], ratio=p["ratio"])
    assert sch["t_start"] == F.clear_cycles(80, 64) + F.RELEASE_DELAY == 1024 + 2
    assert sch["accept"].min() >= sch["t_start"]
    assert sch["t_swap"] == sch["t_pixels_done"] + 1 and sch["cycles"] == sch["t_swap"] + 1
    assert F.clear_cycles(1280, 1024) == 262_144


def test_frame_stimulus_word_layout():
    """A frame write on the engine (``FrameBench.stimulus_of``): packed big-endian rows of
    ``{end, gap[15:0], z[23:0], rgb[23:0], addr}`` (64 x 64: 12 address bits, 77 bits in 10 bytes),
    then the end token (``end`` alone); one pipeline empty: its end token only."""
    from rasterhw.golden_model.snu.pixelstream import PixelStream
    from rasterhw.sim.snu.testbench import FrameBench

    tb = FrameBench()
    p = tb.params(width=64, height=64)
    s = PixelStream(64, 64, addr=np.array([0x123]), rgb=np.array([0xABCDEF]), z=np.array([0x010203]),
                    pipe=np.array([0]))
    w = tb.stimulus_of(p, s, np.array([0x1234]), schedule={}).words
    assert w["i_pipe0"].shape == (2, 10)
    assert w["i_pipe0"][0].tobytes() == (0x1234 << 60 | 0x010203 << 36 | 0xABCDEF << 12 | 0x123).to_bytes(10, "big")
    assert w["i_pipe0"][1].tobytes() == (1 << 76).to_bytes(10, "big")
    assert [r.tobytes() for r in w["i_pipe1"]] == [(1 << 76).to_bytes(10, "big")]


@pytest.mark.cocotb
def test_frame_on_verilator_equals_golden():
    scene = build_scene("sp27")
    r = F.frame_run(scene, 80, 64)
    f = r["frame"]
    assert r["mismatches"] == 0 and f["schedule_mismatches"] == 0 and r["cycle_mismatches"] == 0
    assert f["schedule_hdl"] == f["schedule_golden"]
    assert r["pixels_compared"] == 80 * 64 and r["writes"] == f["pixel_writes"] > 3000
    # the displayed frame is the SNU golden render (clear, then the stream, then swap)
    assert np.array_equal(r["frame_rgb"], render(scene, 80, 64).rgb8)
    assert f["inner_loop"]["total"] == 8
    assert 0 < f["bus_share_of_frame"] < 1
    assert f["frame_s"] == r["cycles"] / 12.5e6


@pytest.mark.cocotb
@pytest.mark.slow
@pytest.mark.skipif(os.environ.get("SNU_HEADLINE") != "1", reason="2-3 minutes: set SNU_HEADLINE=1")
def test_headline_frame_cli(tmp_path):
    """`rasterhw sim pixelbus --scene snu-100k --engine verilator --json`: the whole frame
    (10 M writes; a Verilator build plus ~1-2 minutes, so only with SNU_HEADLINE=1)."""
    r = subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", "sim", "pixelbus", "--scene", "snu-100k",
                        "--engine", "verilator", "--json", "-o", str(tmp_path / "f.png")],
                       capture_output=True, text=True, timeout=1800)
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads(r.stdout)
    assert res["mismatches"] == 0 and res["pixels_compared"] == 1_310_720
    assert res["writes"] == 10_000_134 and res["frame"]["triangles"] == 100_000
    assert res["frame"]["schedule_hdl"] == res["frame"]["schedule_golden"]


def _frame_inputs(name, w, h):
    from rasterhw.golden_model.snu import pixelbus as g

    tris = _tris(name, w, h)
    s = scan_convert(tris)
    p = F.producer_gaps(tris, s)
    sch = F.golden_schedule(s, p["gaps"], p["first_work"], ratio=p["ratio"])
    return s, p, sch, g.pixelbus_frame(s, accept=sch["accept"])


def test_frame_adapter_on_pysim_equals_golden():
    """The frame on the pysim engine (FrameBench: clear, 16-bit producer gaps, swap, read-out):
    the schedule and the displayed frame are the golden model's."""
    s, p, sch, (rgb, z) = _frame_inputs("sp27", 24, 16)
    assert len(s) > 100 and int(p["gaps"].max()) > 255          # gaps the engine's 8 bits could not carry
    r = F.run_frame_engine(s, p["gaps"], sch, engine="pysim")
    assert r["mismatches"] == 0
    assert [r[k] for k in ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")] == \
        [sch[k] for k in ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")]
    assert np.array_equal(r["rgb"], rgb) and np.array_equal(r["z"], z)


def test_the_frame_run_length_is_held_on_the_engine():
    """``frame_job`` holds the run's length (the last read-out word's edge + 1: the golden
    schedule's ``cycles`` + the frame's words + 1) as ``cycle_mismatches``, an integer on every
    engine (it was None on Verilator); one clock off is counted, and counted in ``mismatches``."""
    from dataclasses import replace

    from rasterhw.sim.engines.scene import Done, run_job
    from rasterhw.sim.testbench import compare

    s, p, sch, _ = _frame_inputs("sp27", 24, 16)
    job = F.frame_job(s, p["gaps"], sch)
    d = run_job(job, "pysim")
    assert d.cmp["cycle_mismatches"] == 0 and d.got.cycles == job.expect.cycles == sch["cycles"] + 24 * 16 + 1
    off = compare(replace(job.expect, cycles=job.expect.cycles + 1), d.got)
    assert off["cycle_mismatches"] == 1 and off["mismatches"] == 0
    assert F.frame_words(Done(job, d.got, off))["mismatches"] == 1


@pytest.mark.cocotb
def test_frame_on_the_engine_is_golden_clock_for_clock():
    """The generic Verilator engine with the frame adapter: every schedule number (clear, release,
    pixels done, swap, frame length) the golden schedule's and the displayed frame (RGB and Z) the
    golden frame. (It was also held equal to the dedicated bench ``tb_pixelbus_fast.v``, retired
    once the engine ran the frame; the golden schedule is what that bench was checked against.)"""
    s, p, sch, (rgb, z) = _frame_inputs("sp27", 80, 64)
    e = F.run_frame_engine(s, p["gaps"], sch)
    keys = ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")
    assert e["mismatches"] == 0 and [e[k] for k in keys] == [sch[k] for k in keys]
    assert sch["t_start"] == F.clear_cycles(80, 64) + F.RELEASE_DELAY and sch["t_swap"] == sch["t_pixels_done"] + 1
    assert np.array_equal(e["rgb"], rgb) and np.array_equal(e["z"], z)
