# amaranth: UnusedElaboratable=no
"""Amaranth-pysim tests of the SNU pixel-bus bank controller and the two-pipeline bus."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator
from amaranth.utils import ceil_log2
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu import pixelbus as g
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.hdl.snu.pixelbus import PixelBus
from rasterhw.hdl.snu.pixelbus_bank import Command, PixelBusBank
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put
from rasterhw.sim.snu.scene import simulate_pixelbus
from snu_pixelbus_pysim import run_pysim

# --- bank ------------------------------------------------------------------------------


async def read_bank(ctx, dut, depth, buf):
    rgb, z = [], []
    ctx.set(dut.rd_buf, buf)
    for a in range(depth):
        ctx.set(dut.rd_addr, a)
        await ctx.tick()
        rgb.append(ctx.get(dut.rd_rgb))
        z.append(ctx.get(dut.rd_z))
    return rgb, z


def test_bank_writes_backpressure_and_z_test():
    depth, n = 12, 60
    rng = np.random.default_rng(11)
    addr = rng.integers(0, depth, n).tolist()
    rgb = rng.integers(0, 1 << 24, n).tolist()
    z = rng.integers(0, 6, n).tolist()  # small Z: ties and far (0) writes
    gap = (rng.integers(0, 3, n) * (rng.random(n) < 0.5)).tolist()
    dut = PixelBusBank(depth=depth, mem_cycle=5)
    accepted = []
    log: list = []
    res = {}

    async def drive(ctx):
        for k in range(n):
            await stream_put(ctx, dut.i, {"addr": addr[k], "rgb": rgb[k], "z": z[k]}, gap=gap[k])
            accepted.append(k)
        for _ in range(6):
            await ctx.tick()
        res["draw"] = await read_bank(ctx, dut, depth, 0)
        res["disp"] = await read_bank(ctx, dut, depth, 1)

    async def watch_ready(ctx):
        # after every transfer ready must stay low for mem_cycle - 1 clocks
        low = 0
        async for _clk, _rst, valid, ready, busy in ctx.tick().sample(dut.i.valid, dut.i.ready, dut.busy):
            if low:
                assert not ready and busy
                low -= 1
            elif valid and ready:
                low = 4

    sim = Simulator(dut)
    sim.add_clock(80e-9)
    sim.add_testbench(drive)
    sim.add_testbench(watch_ready, background=True)
    sim.add_testbench(stream_protocol_checker(dut.i, "i", log), background=True)
    sim.run()
    assert accepted == list(range(n))
    assert [(p["addr"], p["rgb"], p["z"]) for p in (_fields(x, dut) for x in log)] == list(zip(addr, rgb, z, strict=True))
    ref_rgb, ref_z = [0] * depth, [0] * depth
    for k in range(n):
        if z[k] > ref_z[addr[k]]:
            ref_z[addr[k]], ref_rgb[addr[k]] = z[k], rgb[k]
    assert res["draw"] == (ref_rgb, ref_z)
    assert res["disp"][0] == [0] * depth  # display buffer untouched


def _fields(raw, dut):
    aw = dut.addr_bits
    return {"addr": raw & ((1 << aw) - 1), "rgb": (raw >> aw) & 0xFFFFFF, "z": raw >> (aw + 24)}


def test_bank_clear_and_swap():
    depth = 10
    dut = PixelBusBank(depth=depth, mem_cycle=5)
    res = {}

    async def tb(ctx):
        for a in range(depth):
            await stream_put(ctx, dut.i, {"addr": a, "rgb": 0x100 + a, "z": 50 + a})
        assert ctx.get(dut.draw_buf) == 0
        # swap: accepted only once the last memory cycle is over, takes one clock
        await stream_put(ctx, dut.i_cmd, Command.SWAP)
        assert ctx.get(dut.draw_buf) == 1 and not ctx.get(dut.busy)
        res["after_swap"] = await read_bank(ctx, dut, depth, 1)  # display = old draw
        await stream_put(ctx, dut.i, {"addr": 3, "rgb": 0xABCDEF, "z": 10})  # Z 10 < 53: rejected
        await stream_put(ctx, dut.i, {"addr": 4, "rgb": 0x123456, "z": 99})
        for _ in range(5):
            await ctx.tick()
        res["draw2"] = await read_bank(ctx, dut, depth, 0)
        # clear: busy for exactly `depth` clocks after the accept, pixels held back meanwhile
        await stream_put(ctx, dut.i_cmd, Command.CLEAR)
        busy = 0
        ctx.set(dut.i.valid, 1)
        ctx.set(dut.i.payload, {"addr": 1, "rgb": 7, "z": 1})
        while ctx.get(dut.busy):
            assert not ctx.get(dut.i.ready)
            busy += 1
            await ctx.tick()
        ctx.set(dut.i.valid, 0)
        res["clear_clocks"] = busy
        res["cleared"] = await read_bank(ctx, dut, depth, 0)
        res["display"] = await read_bank(ctx, dut, depth, 1)

    sim = Simulator(dut)
    sim.add_clock(80e-9)
    sim.add_testbench(tb)
    sim.run()
    assert res["after_swap"] == ([0x100 + a for a in range(depth)], [50 + a for a in range(depth)])
    draw_rgb, draw_z = res["draw2"]
    assert draw_rgb == [0] * 4 + [0x123456] + [0] * 5  # fresh draw buffer: only the Z-passing write
    assert draw_z[3] == 53 and draw_z[4] == 99
    assert res["clear_clocks"] == depth
    assert res["cleared"] == ([0] * depth, [0] * depth)
    assert res["display"][0] == [0x100 + a for a in range(depth)]  # clear leaves the display buffer


def test_bank_bad_parameters():
    with pytest.raises(ValueError, match="depth"):
        PixelBusBank(depth=0)
    with pytest.raises(ValueError, match="mem_cycle"):
        PixelBusBank(depth=4, mem_cycle=1)
    with pytest.raises(ValueError, match="z_bits"):
        PixelBusBank(depth=4, z_bits=0)
    with pytest.raises(ValueError, match="ram"):
        PixelBusBank(depth=4, ram="sram")


# --- bus -------------------------------------------------------------------------------


def check_bus(stream, gaps=None):
    logs: list = []
    r = run_pysim(stream, gaps=gaps, checker_logs=logs)
    acc = g.pixelbus_accept_cycles(stream, gaps=gaps)
    assert np.array_equal(r["accept"], acc), "acceptance cycles differ from the cycle model"
    assert r["cycles"] == g.pixelbus_cycles(stream, gaps=gaps)
    rgb, z = g.pixelbus_frame(stream, accept=acc)
    assert np.array_equal(r["rgb"], rgb) and np.array_equal(r["z"], z)
    # every write transferred exactly once and in pipeline order (in-order scoreboard)
    aw = max(1, ceil_log2(stream.width * stream.height))
    for p in range(2):
        idx = np.flatnonzero(stream.pipe == p)
        want = [(int(stream.z[k]) << (24 + aw)) | (int(stream.rgb[k]) << aw) | int(stream.addr[k]) for k in idx]
        assert logs[p] == want
    return r


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("idle", ["none", "random"])
def test_bus_random_stream(seed, idle):
    rng = np.random.default_rng(seed)
    w, h, n = 20, 8, 160
    s = PixelStream(w, h, rng.integers(0, w * h, n), rng.integers(0, 1 << 24, n),
                    rng.integers(0, 8, n), rng.integers(0, 2, n))
    gaps = None if idle == "none" else rng.integers(0, 4, n) * (rng.random(n) < 0.4)
    check_bus(s, gaps)


def test_bus_one_bank_every_cycle_backpressure():
    # all writes of both pipelines to bank 0: the bus must stall, drop nothing, keep order
    rng = np.random.default_rng(4)
    w, h, n = 20, 8, 60
    addr = rng.integers(0, w * h // 5, n) * 5
    s = PixelStream(w, h, addr, rng.integers(0, 1 << 24, n), rng.integers(1, 4, n), np.tile([0, 1], n // 2))
    r = check_bus(s)
    # one write per memory cycle at best, and each pipeline only in its own slots
    assert r["cycles"] >= 5 * n


def test_bus_patterns_match_model():
    for pattern in ("scanline", "vertical"):
        s = g.pattern_stream(pattern, 20, 6, 80, seed=3)
        check_bus(s)


def test_bus_command_waits_for_idle_and_blocks_pixels():
    dut = PixelBus(width=10, height=2)
    res = {}

    async def tb(ctx):
        # a write to bank 0 at cycle 0, then offer CLEAR together with another write
        await stream_put(ctx, dut.i_pipe0, {"addr": 0, "rgb": 0xFFFFFF, "z": 9})
        ctx.set(dut.i_cmd.payload, Command.CLEAR)
        ctx.set(dut.i_cmd.valid, 1)
        ctx.set(dut.i_pipe1.payload, {"addr": 6, "rgb": 1, "z": 1})
        ctx.set(dut.i_pipe1.valid, 1)
        t0 = ctx.get(dut.cycle)
        while not ctx.get(dut.i_cmd.ready):
            assert not ctx.get(dut.i_pipe1.ready)
            await ctx.tick()
        res["cmd_wait"] = ctx.get(dut.cycle) - t0
        await ctx.tick()
        ctx.set(dut.i_cmd.valid, 0)
        n = 0
        while ctx.get(dut.busy):
            assert not ctx.get(dut.i_pipe1.ready)
            n += 1
            await ctx.tick()
        res["clear"] = n
        await ctx.tick().until(dut.i_pipe1.ready)
        ctx.set(dut.i_pipe1.valid, 0)
        for _ in range(6):
            await ctx.tick()
        out = []
        for a in range(20):
            ctx.set(dut.rd_addr, a)
            await ctx.tick()
            out.append((ctx.get(dut.rd_rgb), ctx.get(dut.rd_z)))
        res["frame"] = out

    sim = Simulator(dut)
    sim.add_clock(80e-9)
    sim.add_testbench(tb)
    sim.run()
    assert res["cmd_wait"] == 4  # the bank-0 memory cycle started in cycle 0 ends at cycle 5
    assert res["clear"] == dut.clear_cycles == 4
    frame = res["frame"]
    assert frame[0] == (0, 0)  # cleared after the first write
    assert frame[6] == (1, 1)  # the held-back write landed after the clear
    assert all(v == (0, 0) for i, v in enumerate(frame) if i != 6)


def test_bus_bad_parameters():
    with pytest.raises(ValueError, match="width"):
        PixelBus(width=0, height=4)
    with pytest.raises(ValueError, match="height"):
        PixelBus(width=4, height=-1)
    with pytest.raises(ValueError, match="smaller than 5 banks"):
        PixelBus(width=2, height=2)
    with pytest.raises(ValueError, match="mem_cycle"):
        PixelBus(width=10, height=2, mem_cycle=1)
    with pytest.raises(ValueError, match="z_bits"):
        PixelBus(width=10, height=2, z_bits=40)


def test_simulate_pixelbus_pysim():
    s = g.pattern_stream("random", 20, 8, 100, seed=9)
    r = simulate_pixelbus(s, engine="pysim")
    assert r["block"] == "pixelbus" and r["engine"] == "pysim"
    assert r["mismatches"] == 0 and r["pixels_compared"] == 160
    assert r["cycles"] == g.pixelbus_cycles(s) and r["clock_hz"] == 12.5e6
    rgb, _ = g.pixelbus_frame(s)
    assert np.array_equal(r["frame_rgb"], g.rgb_image(rgb)) and r["frame_rgb"].dtype == np.uint8


def test_simulate_pixelbus_bad_input():
    bad_addr = PixelStream(10, 2, np.array([20]), np.array([0]), np.array([1]), np.array([0]))
    with pytest.raises(RasterhwError, match="address 20"):
        simulate_pixelbus(bad_addr)
    wide_z = PixelStream(10, 2, np.array([3]), np.array([0]), np.array([1 << 24]), np.array([1]))
    with pytest.raises(RasterhwError, match="Z value"):
        simulate_pixelbus(wide_z)
    ok = PixelStream(10, 2, np.array([3]), np.array([0]), np.array([1]), np.array([1]))
    with pytest.raises(RasterhwError, match="engine"):
        simulate_pixelbus(ok, engine="modelsim")


# --- the testbenches (sim/snu/testbench.py) and their read-out adapter ---------------------------


def test_bank_testbench_reads_out_after_the_last_memory_cycle():
    from rasterhw.sim.engines import run
    from rasterhw.sim.testbench import compare, find_testbench

    tb = find_testbench("pixelbus-bank")
    p = tb.params(depth=32)
    stim = tb.stimulus_of(p, tb.stimulus(p, seed=4).source[0])   # the seed's writes, no command
    exp = tb.expect(p, stim)
    n = len(stim.words["i"]) - 1          # the writes, then the end token
    r = run(tb, p, stim, engine="pysim", expect_words={"o": 64})
    assert compare(exp, r)["mismatches"] == 0
    # back to back the bank takes one write per memory cycle: the last one's ends at n * 5, the
    # read-out starts there and gives one word a clock (the draw buffer's 32, the display buffer's 32)
    assert r.stamps["o"] == list(range(5 * n + 1, 5 * n + 1 + 64))


@pytest.mark.parametrize("pipe", [0, 1])
def test_bus_testbench_with_one_pipeline_empty(pipe):
    from rasterhw.sim.engines import run
    from rasterhw.sim.packed import as_ints
    from rasterhw.sim.snu.testbench import frame_of
    from rasterhw.sim.testbench import compare, find_testbench

    rng = np.random.default_rng(pipe)
    n = 50
    s = PixelStream(20, 8, rng.integers(0, 160, n), rng.integers(0, 1 << 24, n), rng.integers(0, 8, n),
                    np.full(n, pipe))
    tb = find_testbench("pixelbus")
    p = tb.params(width=20, height=8)
    stim = tb.stimulus_of(p, s)
    assert as_ints(stim.words[f"i_pipe{1 - pipe}"]) == [1 << (24 + 24 + 8)]     # only the end token
    exp = tb.expect(p, stim)
    r = run(tb, p, stim, engine="pysim", stall=100, seed=3, expect_words={"o": 160})
    c = compare(exp, r, cycle_exact=False)
    assert c["mismatches"] == 0 and c["cycle_mismatches"] == 0
    rgb, z = g.pixelbus_frame(s)
    assert np.array_equal(frame_of(r, 24, (8, 20))[0], rgb) and np.array_equal(frame_of(r, 24, (8, 20))[1], z)
    assert r.stamps["o"][0] - 1 >= g.pixelbus_cycles(s)     # read out only once every write has landed
