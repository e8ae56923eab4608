"""The timing-free Verilator chip bench (``rasterhw.sim.zbm.fast``, no cocotb): one 64x16
chip (interleave 2, chip 0, random triangles and random upstream pixels) must produce the
golden merged scan lines bit for bit, in the same number of segment-clock cycles as the
cocotb chip bench (``run_chip_bench`` with equal in-phase clocks, no gaps, no back-pressure).
Cold: two Verilator builds (this one at g++ -O1, ~11 s; the cocotb one ~30 s); later runs reuse build/."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm.stimulus import random_doublez, random_triangles
from rasterhw.sim.zbm import fast as ZF
from rasterhw.sim.zbm.chip_bench import chip_stimulus, run_chip_bench

pytestmark = pytest.mark.cocotb

W, H, ILV, CHIP = 64, 16, 2, 0


def _stimulus(seed: int = 5):
    tris = random_triangles(np.random.default_rng(seed), 40, W, H, size=10)
    segs = G.segment_generator(G.edge_pairs(tris), H, width=W)
    npx = -(-(W - CHIP) // ILV)
    up = random_doublez(np.random.default_rng(seed + 1), H * npx)
    up = G.DoubleZ(up.z.reshape(H, npx, 2), up.a.reshape(H, npx, 2), up.c.reshape(H, npx, 2, 4),
                   up.tag.reshape(H, npx, 2))
    return chip_stimulus(segs, H, up, chip=CHIP, interleave=ILV, width=W)


@pytest.mark.heavy
def test_fast_chip_matches_golden_and_cocotb_cycles():
    seg_w, up_w, exp = _stimulus()
    assert len(seg_w) > H   # some segments, not only end-of-line records
    fast = ZF.run_chip_fast(seg_w, up_w, lines=H, chip=CHIP, interleave=ILV, width=W, repeat=2, opt="-O1")
    assert int(np.count_nonzero((fast["s0"] != exp[0]) | (fast["s1"] != exp[1]))) == 0
    assert fast["lines"] == (2 * H) % (1 << 16) and fast["cycles"] > 0
    ref = run_chip_bench(seg_w, up_w, lines=H, chip=CHIP, interleave=ILV, width=W, sim="verilator",
                           ratio=(5, 5), stall=0, repeat=2, phase=0, expect=exp)
    assert np.array_equal(ref["s0"], exp[0]) and np.array_equal(ref["s1"], exp[1])
    assert fast["cycles"] == ref["cycles"]
