"""Testbenches of the ZB/M blocks (``sim/testbench.py``): what each block takes and what the golden
model says it gives; the engines (``sim/engines/``) run them."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.zbm.stimulus import random_triangles
from rasterhw.golden_model.zbm.words import edge_pair_words, segment_words
from rasterhw.sim.testbench import Expected, Stimulus, Testbench

__all__ = ["SeggenBench"]


class SeggenBench(Testbench):
    """``zbm-seggen``: edge-pair words in (``i``), every scan line's segment words out (``o``), as
    ``golden_model/zbm/seggen.py: segment_generator`` gives them. A random frame: 2..40 random
    screen triangles (seeded), as many edge pairs as the memory holds at most."""

    block = "zbm-seggen"

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        w, h = params["width"], params["height"]
        n = int(rng.integers(2, 41))
        eps = G.edge_pairs(random_triangles(rng, n, w, h, size=float(rng.uniform(3, max(4, min(w, h) / 2)))))
        while len(eps) and G.max_active_edge_pairs(eps)[0] > params["capacity"]:
            eps = eps.take(np.arange(len(eps) - 1))   # the frame must fit the memory
        return Stimulus({"i": edge_pair_words(eps)}, what=f"{n} random triangles, seed {seed}", source=eps)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        h = params["height"]
        segs = G.segment_generator(stim.source, h, width=params["width"], capacity=params["capacity"])
        return Expected({"o": [wd for y in range(h) for wd in segment_words(segs, y)]})
