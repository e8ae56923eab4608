"""cocotb benches: ZB/M units (tb_zbm_unit.v) and one ZB/M chip (tb_zbm_chip.v).

Driven by ``unit_bench.run_unit_bench`` / ``chip_bench.run_chip_bench`` (this folder), which writes the
stimulus, the golden result and the plusargs (clock ratio, back-pressure, seed); run them
with ``pytest tests/zbm/test_zbm_cocotb.py``.  The designs run free on Verilog-side clocks;
Python only waits for ``finished`` unless ZBM_CHECK_PROTOCOL=1, which adds the stream
checker of ``cocotb_tests/common.py`` on every stream (each clock; small runs) feeding
in-order scoreboards.  The Verilog checkers (cocotb_tests/harness.v) run always.

Environment: ZBM_OUT (dump written by the wrapper; result.json goes beside it),
ZBM_EXPECT (.npz with the golden (s0, s1) words and the stimulus), ZBM_CHECK_PROTOCOL.
"""

from __future__ import annotations

import json
import os
from collections import deque
from pathlib import Path

import cocotb
import numpy as np
from cocotb.triggers import RisingEdge
from rasterhw.golden_model.zbm.words import merge_words

from cocotb_tests.common import start_checker, to_int


def _read_dump(path: str) -> list[int]:
    lines = [ln.strip() for ln in Path(path).read_text().split("\n")]
    return [int(ln, 16) for ln in lines if ln and not ln.startswith("//") and not ln.startswith("@")]


class Scoreboard:
    """In-order scoreboard: expected words are popped as the DUT delivers them."""

    def __init__(self, name: str, expected: list[int]):
        self.name = name
        self.queue = deque(expected)
        self.n = 0

    def check(self, got: list[int]) -> None:
        for w in got:
            assert self.queue, f"{self.name}: transfer {self.n} ({w:#x}) beyond the expected {self.n} words"
            want = self.queue.popleft()
            assert w == want, f"{self.name}: transfer {self.n} is {w:#x}, expected {want:#x}"
            self.n += 1
        assert not self.queue, f"{self.name}: {len(self.queue)} expected words never arrived"


def _write_result(dut, **extra) -> dict:
    meta = {"cycles": to_int(dut.cycles), "proto_errors": to_int(dut.proto_errors),
            "timeout": bool(to_int(dut.timeout)), **extra}
    Path(os.environ["ZBM_OUT"]).with_name("result.json").write_text(json.dumps(meta))
    return meta


def _line_report(got: np.ndarray, want: np.ndarray) -> str:
    bad_lines = np.flatnonzero((got != want).any(axis=1))
    if not bad_lines.size:
        return ""
    y = int(bad_lines[0])
    x = int(np.flatnonzero(got[y] != want[y])[0])
    return (f"{bad_lines.size} scan lines differ; first: line {y}, pixel {x}: "
            f"{int(got[y, x]):#034x} != golden {int(want[y, x]):#034x}")


@cocotb.test()
async def zbm_unit_frame(dut):
    """Edge pairs -> chain of units -> every merged scan line vs the golden model."""
    exp = np.load(os.environ["ZBM_EXPECT"]) if os.environ.get("ZBM_EXPECT") else None
    check = os.environ.get("ZBM_CHECK_PROTOCOL") == "1"
    logs_in: list[list[int]] = []
    logs_out: list[list[int]] = []
    if check:
        assert exp is not None, "ZBM_CHECK_PROTOCOL=1 needs ZBM_EXPECT"
        units, interleave = int(exp["units"]), int(exp["interleave"])
        for k in range(units):
            logs_in.append([])
            p = dut.player[k]
            start_checker(dut.clk, p.v, p.r, p.p, name=f"i[{k}]", log=logs_in[k], reset=dut.rst)
        for c in range(interleave):
            logs_out.append([])
            s = dut.slot[c]
            start_checker(dut.mclk, s.v, s.r, s.p, name=f"o_merge[{c}]", log=logs_out[c], reset=dut.mrst)
    await RisingEdge(dut.finished)
    meta = _write_result(dut, frames_ok=bool(to_int(dut.frames_ok)), overflow=bool(to_int(dut.overflow)))
    dut._log.info("unit bench: %s", meta)
    assert not meta["overflow"], "a unit's active-edge-pair memory overflowed"
    assert not meta["timeout"], f"watchdog fired at {meta['cycles']} cycles"
    assert meta["proto_errors"] == 0, f"{meta['proto_errors']} stream-rule violations (Verilog checkers)"
    assert meta["frames_ok"], "a segment generator did not finish exactly one frame"
    if exp is None:
        # no golden frame: only a speed run, which compares the dump in Python itself, may do this
        assert os.environ.get("ZBM_SPEED_RUN") == "1", "no ZBM_EXPECT: nothing to compare against"
        return
    s0, s1 = exp["s0"], exp["s1"]
    h, w = s0.shape
    if check:
        stim = [int(x, 16) for x in exp["stim"]]
        idx = exp["index"]
        for k, log in enumerate(logs_in):
            base, n = int(idx[2 * k]), int(idx[2 * k + 1])
            # the stimulus words carry the gap above the payload
            want = [x & ((1 << 168) - 1) for x in stim[base:base + n]]
            Scoreboard(f"i[{k}]", want).check(log)
        interleave = len(logs_out)
        for c, log in enumerate(logs_out):
            Scoreboard(f"o_merge[{c}]", merge_words(s0[:, c::interleave], s1[:, c::interleave])).check(log)
    got = np.array(_read_dump(os.environ["ZBM_OUT"]), dtype=object)
    assert got.size == h * w, f"dump has {got.size} words, expected {h * w}"
    want = np.array(merge_words(s0, s1), dtype=object)
    msg = _line_report(got.reshape(h, w), want.reshape(h, w))
    assert not msg, msg


@cocotb.test()
async def zbm_chip_lines(dut):
    """Segments + upstream pixels -> one chip -> every merged scan line vs the golden model."""
    exp = np.load(os.environ["ZBM_EXPECT"]) if os.environ.get("ZBM_EXPECT") else None
    check = os.environ.get("ZBM_CHECK_PROTOCOL") == "1"
    logs = {"i_seg": [], "i_merge": [], "o_merge": []}
    if check:
        start_checker(dut.clk, dut.seg_v, dut.seg_r, dut.seg_p, name="i_seg", log=logs["i_seg"], reset=dut.rst)
        start_checker(dut.mclk, dut.up_v, dut.up_r, dut.up_p, name="i_merge", log=logs["i_merge"], reset=dut.mrst)
        start_checker(dut.mclk, dut.o_v, dut.o_r, dut.o_p, name="o_merge", log=logs["o_merge"], reset=dut.mrst)
    await RisingEdge(dut.finished)
    meta = _write_result(dut, lines=to_int(dut.lines))
    dut._log.info("chip bench: %s", meta)
    assert not meta["timeout"], f"watchdog fired at {meta['cycles']} cycles"
    assert meta["proto_errors"] == 0, f"{meta['proto_errors']} stream-rule violations (Verilog checkers)"
    if exp is None:
        # no golden frame: only a speed run, which compares the dump in Python itself, may do this
        assert os.environ.get("ZBM_SPEED_RUN") == "1", "no ZBM_EXPECT: nothing to compare against"
        return
    s0, s1 = exp["s0"], exp["s1"]
    rep = int(exp["repeat"])
    lines = s0.shape[0]
    assert meta["lines"] == lines * rep, f"chip swapped {meta['lines']} lines, expected {lines * rep}"
    if check:
        seg = [int(x, 16) for x in exp["seg"]] * rep
        up = [int(x, 16) for x in exp["up"]] * rep
        Scoreboard("i_seg", seg).check(logs["i_seg"])
        Scoreboard("i_merge", up).check(logs["i_merge"])
        Scoreboard("o_merge", merge_words(s0, s1) * rep).check(logs["o_merge"])
    got = np.array(_read_dump(os.environ["ZBM_OUT"]), dtype=object).reshape(s0.shape)
    want = np.array(merge_words(s0, s1), dtype=object).reshape(s0.shape)
    msg = _line_report(got, want)
    assert not msg, msg
