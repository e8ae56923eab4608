"""Pysim tests of the mapping-after-merge stage (hdl/zbm/mapper.py) against golden map_samples."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.stimulus import random_doublez
from rasterhw.golden_model.zbm.words import pixel2_words
from rasterhw.hdl.zbm.mapper import ZbmMapper
from rasterhw.sim.engines.harness import run_stream

pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


def run_mapper(words, tex, il, *, seed=0, p_stall=0.3, p_gap=0.3):
    dut = ZbmMapper(texture=tex, illum=il)
    out = {}

    async def counters(ctx):
        out["tex"], out["il"] = ctx.get(dut.texture_lookups), ctx.get(dut.illum_lookups)

    got = run_stream(dut, words, seed=seed, p_stall=p_stall, p_gap=p_gap, after=counters)
    return got, out


def test_div255_round_exact():
    from rasterhw.hdl.zbm.mapper import div255_round

    x = np.arange(255 * 255 + 1)
    assert np.array_equal(div255_round(x), (x + 127) // 255)


def test_mapper_matches_map_samples():
    """Random double-Z pixels (empty, translucent and opaque fronts), random stalls and gaps."""
    rng = np.random.default_rng(7)
    px = random_doublez(rng, 300)
    tex, il = default_maps(3)
    want, stats = map_samples(px, tex, il)
    got, counts = run_mapper(pixel2_words(px), tex, il)
    assert got == pixel2_words(want)
    assert counts["tex"] == counts["il"] == stats["texture_lookups"] > 0
    assert stats["texture_lookups"] < 2 * np.count_nonzero(px.z[:, 0] != F.Z_EMPTY) + 1


def test_mapper_bad_maps():
    with pytest.raises(ValueError, match="texture must be"):
        ZbmMapper(texture=np.zeros((4, 4, 3)), illum=np.zeros((256, 256)))


def test_mapping_driver_full_rate():
    """sim/zbm/mapping_hdl.run_mapping (MappingBench on the generic pysim engine): mapper ->
    compositor, one pixel per clock, latency 2 + 2, the same words as map_samples and the same
    pixels as composite (testbench.compare on both output ports)."""
    from rasterhw.golden_model.zbm.composite import composite
    from rasterhw.sim.zbm.mapping_hdl import run_mapping

    px = random_doublez(np.random.default_rng(2), 40)
    tex, il = default_maps(1)
    want, stats = map_samples(px, tex, il)
    hw = run_mapping(px, want, composite(want), tex, il)
    assert hw["mismatches"] == 0 and hw["words_compared"] == 80
    assert hw["texture_lookups"] == stats["texture_lookups"] and hw["illum_lookups"] == stats["illum_lookups"]
    assert hw["cycles"] == 40 + 2 + 2
    assert hw["run"].words["o_map"] == pixel2_words(want)
    img = composite(want).astype(np.int64)
    assert hw["run"].words["o"] == [int(v) for v in img[:, 0] | img[:, 1] << 8 | img[:, 2] << 16]
    wrong = run_mapping(px, want, np.zeros_like(composite(want)), tex, il)   # the check can fail
    assert wrong["ports"]["o"]["mismatches"] > 0 and wrong["ports"]["o_map"]["mismatches"] == 0
