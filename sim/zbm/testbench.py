"""Testbenches of the ZB/M blocks (``sim/testbench.py``): what each block takes and what the golden
model says it gives; the engines (``sim/engines/``) run them."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import first_triangles, random_doublez, random_triangles
from rasterhw.golden_model.zbm.words import (
    doublez_words,
    edge_pair_words,
    merge_words,
    segment_words,
)
from rasterhw.sim.testbench import Expected, Stimulus, Testbench

__all__ = ["MergerBench", "SeggenBench", "UnitBench"]


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


class UnitBench(Testbench):
    """``zbm-unit`` (the head unit of a chain): edge-pair words in (``i``), every chip's merge-bus
    words out (``o_merge[c]``, chip ``c`` owning columns ``c, c + I, ...``, line by line), the
    double-Z samples of ``golden_model/zbm/render.py: render_zbm``. The merge clock runs with the
    segment clock (the two-clock ratios stay with the cocotb bench). A random frame: 2..40 random
    screen triangles (seeded), the first ones that fit the active-edge-pair memory."""

    block = "zbm-unit"
    domains = ("sync", "merge")
    port_domains = {"o_merge": "merge"}

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        return tuple(f"o_merge[{c}]" for c in range(params["interleave"]))

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        w, h = params["width"], params["height"]
        n = int(rng.integers(2, 41))
        tris = random_triangles(rng, n, w, h, size=float(rng.uniform(3, max(4, min(w, h) / 2))))
        while len(tris.xy) > 1 and G.max_active_edge_pairs(G.edge_pairs(tris))[0] > params["capacity"]:
            tris = first_triangles(tris, len(tris.xy) - 1)
        return Stimulus({"i": edge_pair_words(G.edge_pairs(tris))}, what=f"{len(tris.xy)} random triangles, "
                        f"seed {seed}", source=tris)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        i = params["interleave"]
        g0, g1 = doublez_words(G.render_zbm(stim.source, interleave=i).pixels)
        return Expected({f"o_merge[{c}]": merge_words(g0[:, c::i], g1[:, c::i]) for c in range(i)})


class MergerBench(Testbench):
    """``zbm-merger`` (the chip's merger, its PIXEL2 word): own double-Z words in on the segment
    side (``i_own``), the upstream chip's on the merge side (``i_merge``), the nearest two of the
    four samples of each pair out (``o_merge``), as ``golden_model/zbm/merger.py: merge`` (upstream
    first on equal Z). Random pixels with Z ties and empty samples (``random_doublez``). Both
    clocks run together here; the free-running unrelated clocks are the proof's
    (``sim/zbm/proof.py``) and the cocotb bench's."""

    block = "zbm-merger"
    inputs = ("i_own", "i_merge")
    outputs = ("o_merge",)
    domains = ("sync", "merge")
    port_domains = {"i_merge": "merge", "o_merge": "merge"}

    def params(self, **given) -> dict:
        p = super().params(**given)
        if (p["z_bits"], p["colour_bits"]) != (F.Z_BITS, F.COLOUR_BITS):
            raise RasterhwError("zbm-merger testbench: the golden words are the full PIXEL2 "
                                f"(z_bits {F.Z_BITS}, colour_bits {F.COLOUR_BITS})")
        return p

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        n = int(rng.integers(60, 200))
        own, up = random_doublez(rng, n), random_doublez(rng, n)
        return Stimulus({"i_own": merge_words(*doublez_words(own)), "i_merge": merge_words(*doublez_words(up))},
                        what=f"{n} random pixel pairs, seed {seed}", source=(own, up))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        own, up = stim.source
        return Expected({"o_merge": merge_words(*doublez_words(G.merge(up, own)))})
