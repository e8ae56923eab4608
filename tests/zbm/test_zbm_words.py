"""ZB/M word packing and stimulus helpers (golden_model/zbm/words.py, stimulus.py)."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import random_segments
from rasterhw.golden_model.zbm.words import packets


def test_packets_follow_initial_processor():
    rng = np.random.default_rng(1)
    segs = random_segments(rng, 10, 64)
    for interleave in F.INTERLEAVES:
        for chip in range(interleave):
            for pkt in packets(segs, 0, chip, interleave):
                h = F.PKT_HEADER.unpack(pkt[0])
                assert len(pkt) == F.PACKET_FLITS and h["len"] >= 1 and h["x"] % interleave == chip
