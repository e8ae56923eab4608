"""A test's own pysim loop of the SNU pixel bus (not a user path): every write's acceptance clock,
which the tests hold to the golden cycle model write by write, and the Python stream checker's log
of each pipeline port. The scene runs use the block's testbench on the generic engines
(``sim/snu/scene.py: simulate_pixelbus``)."""

from __future__ import annotations

import numpy as np
from amaranth.sim import Simulator
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.hdl.snu.pixelbus import PixelBus
from rasterhw.sim.engines.harness import stream_protocol_checker, stream_put


def run_pysim(
    stream: PixelStream,
    *,
    gaps: np.ndarray | None = None,
    readback: bool = True,
    mem_cycle: int = 5,
    n_banks: int = 5,
    checker_logs: list | None = None,
) -> dict:
    """Run ``stream`` through ``PixelBus`` in pysim.

    Returns ``{"cycles", "accept": (N,) cycle of each write's transfer, "rgb", "z"}``
    (``rgb``/``z`` (H, W) int64 read back through the read port, draw buffer, if
    ``readback``).  ``checker_logs``, if a list, receives two lists of the payloads each
    pipeline stream transferred, from :func:`stream_protocol_checker`.
    """
    dut = PixelBus(width=stream.width, height=stream.height, z_bits=stream.z_bits,
                   n_banks=n_banks, mem_cycle=mem_cycle)
    n = len(stream)
    gap = np.zeros(n, dtype=np.int64) if gaps is None else np.asarray(gaps, dtype=np.int64)
    accept = np.full(n, -1, dtype=np.int64)
    ports = [dut.i_pipe0, dut.i_pipe1]
    idx = [np.flatnonzero(stream.pipe == p) for p in range(2)]
    addr, rgb, z = stream.addr.tolist(), stream.rgb.tolist(), stream.z.tolist()
    done = [False, False]
    out: dict = {}

    def driver(p):
        async def tb(ctx):
            for k in idx[p].tolist():
                await stream_put(ctx, ports[p], {"addr": addr[k], "rgb": rgb[k], "z": z[k]}, gap=int(gap[k]))
                # stream_put returns one clock after the transfer
                accept[k] = ctx.get(dut.cycle) - 1
            done[p] = True

        return tb

    async def main(ctx):
        while not all(done):
            await ctx.tick()
        while ctx.get(dut.busy):
            await ctx.tick()
        out["cycles"] = int(ctx.get(dut.cycle))
        if readback:
            size = stream.width * stream.height
            rb_rgb = np.zeros(size, dtype=np.int64)
            rb_z = np.zeros(size, dtype=np.int64)
            ctx.set(dut.rd_buf, 0)
            for a in range(size):
                ctx.set(dut.rd_addr, a)
                await ctx.tick()  # synchronous read: data for `a` in the next clock
                rb_rgb[a] = ctx.get(dut.rd_rgb)
                rb_z[a] = ctx.get(dut.rd_z)
            out["rgb"] = rb_rgb.reshape(stream.height, stream.width)
            out["z"] = rb_z.reshape(stream.height, stream.width)

    sim = Simulator(dut)
    sim.add_clock(80e-9)
    for p in range(2):
        sim.add_testbench(driver(p))
        if checker_logs is not None:
            log: list = []
            checker_logs.append(log)
            sim.add_testbench(stream_protocol_checker(ports[p], f"i_pipe{p}", log), background=True)
    sim.add_testbench(main)
    sim.run()
    out["accept"] = accept
    return out
