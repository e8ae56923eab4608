"""The ZB/M testbenches' own stimulus helpers (the engines run the benches: tests/test_engines.py)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_segments
from rasterhw.golden_model.zbm.words import packets
from rasterhw.sim.testbench import find_testbench
from rasterhw.sim.zbm.testbench import pixel_visits


def test_pixel_visits_cover_every_pixel_of_a_packet_once():
    rng = np.random.default_rng(3)
    for interleave, chip in ((1, 0), (2, 1), (8, 5)):
        segs = random_segments(rng, 12, 64, F.MODE_MAPPING)
        for pkt in packets(segs, 0, chip, interleave):
            hdr = F.PKT_HEADER.unpack(pkt[0])
            seen = []
            for k in range(F.PP_PER_CHIP):
                for v in pixel_visits(pkt, k, interleave):
                    h = F.PKT_HEADER.unpack(v[0])
                    hop = (h["x"] - hdr["x"]) // interleave
                    assert (h["x"] // interleave) % F.PP_PER_CHIP == k and h["len"] == hdr["len"] - hop
                    for a, b in zip(pkt[1:], v[1:], strict=True):   # every channel stepped hop times
                        fa, fb = F.FLIT.unpack(a), F.FLIT.unpack(b)
                        assert fb == {"value": int(F.wrap(fa["value"] + hop * fa["inc"])), "inc": fa["inc"]}
                    seen.append(hop)
            assert sorted(seen) == list(range(hdr["len"]))


def test_loop_and_pixel_benches_end_every_line_and_expect_whole_lines():
    for block, params in (("zbm-loop", {"interleave": 4, "width": 40}),
                          ("zbm-pixel", {"index": 2, "interleave": 2, "width": 64})):
        tb = find_testbench(block)
        p = tb.params(**params)
        stim = tb.stimulus(p, seed=4)
        _, _, lines = stim.source
        eol = [w for w in stim.words["i"] if F.PKT_HEADER.unpack(w & ((1 << F.LOOP_BITS) - 1))["len"] == 0]
        assert len(eol) == lines >= 4 and stim.words["i"][-1] == eol[-1]
        per_line = -(-40 // 4) if block == "zbm-loop" else -(-64 // (8 * 2))
        assert len(tb.expect(p, stim).words["o"]) == lines * per_line
