"""Soak round of the SNU pixel bus (``rasterhw soak --block pixelbus``; sim/flow/soak.py runs it).

A round (1280 x 1024, Verilog RAM, the block's testbench on the Verilator engine) randomises the address pattern (uniform, scan-line runs,
columns, one bank), one or two pipelines, Z from the full 24 bits or a narrow range (ties
between the pipelines), and idle gaps before writes (none, sparse, dense); the banks' own busy
time is the back-pressure. The whole frame (RGB and Z, draw buffer) and the cycle count are
compared.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.snu.formats import N_BANKS
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.sim.snu.scene import simulate_pixelbus

__all__ = ["pixelbus_round"]

PB_W, PB_H = 1280, 1024
#: writes per pipeline kept in 65,535..131,069 so each source's stimulus memory (a build
#: parameter: writes + the end token + 1, to a power of two) is 2**17 words: one build for the
#: rounds with two pipelines, one for those with one
PB_PIPE_WRITES = (66_000, 131_000)


def pixelbus_round(rng: np.random.Generator, k: int) -> dict:
    """One random round; ``k`` (the round number) does not change what a round does."""
    npix = PB_W * PB_H
    pipes = 1 if rng.random() < 0.25 else 2
    counts = [int(rng.integers(*PB_PIPE_WRITES)) for _ in range(pipes)]
    n = sum(counts)
    pattern = str(rng.choice(["uniform", "scanline", "vertical", "one-bank"]))
    if pattern == "uniform":
        addr = rng.integers(0, npix, n)
    elif pattern == "scanline":  # runs along lines from random starts
        run = int(rng.integers(4, 200))
        starts = rng.integers(0, npix, -(-n // run))
        addr = (starts[:, None] + np.arange(run)).ravel()[:n] % npix
    elif pattern == "vertical":  # runs down columns: one bank after another, W apart
        run = int(rng.integers(4, 200))
        starts = rng.integers(0, npix, -(-n // run))
        addr = (starts[:, None] + PB_W * np.arange(run)).ravel()[:n] % npix
    else:  # one bank: the worst case for the interleave
        bank = int(rng.integers(0, N_BANKS))
        addr = rng.integers(0, npix // N_BANKS, n) * N_BANKS + bank
        addr = np.minimum(addr, npix - 1)
    zmode = str(rng.choice(["full", "narrow"]))
    z = rng.integers(0, 1 << 24, n) if zmode == "full" else rng.integers(0, 16, n)
    pipe = np.repeat(np.arange(pipes), counts)
    order = rng.permutation(n)  # the pipelines' writes interleaved in a random order
    s = PixelStream(PB_W, PB_H, addr[order].astype(np.int64), rng.integers(0, 1 << 24, n),
                    z[order].astype(np.int64), pipe[order].astype(np.int64))
    idle = float(rng.choice([0.0, 0.05, 0.5]))
    gaps = rng.integers(1, 9, n) * (rng.random(n) < idle)
    r = simulate_pixelbus(s, engine="verilator", gaps=gaps)   # frame and cycles against the golden model
    return {"pixels": npix, "mismatches": r["mismatches"], "run_s": r["run_s"],
            "settings": f"pattern={pattern} pipes={pipes} writes={n} z={zmode} idle={idle}"}
