"""Mapping after the merge, measured in HDL (``hdl/zbm/mapper.py`` then ``hdl/zbm/compositor.py``
in one run of :class:`MappingBench` on the generic engine, pysim): mapping-memory accesses per frame against mapping every rasterised
sample (paper, sec. 3.3), and the final alpha-composited image (sec. 5.2).

The scenes carry no texture coordinates; ``scene_uv`` gives them a planar screen-space mapping
(u = x / width, v = y / height: one texture over the frame), stated once here and in docs/zbm.md.
The mapper is fed the golden merged words of each chip slot's chain (``render_zbm(mode=MAPPING)``;
the unit HDL that produces them is checked word for word elsewhere) and its output is compared
with ``map_samples`` word for word; the compositor's RGB output with ``composite`` pixel for pixel.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from amaranth import Module
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.words import pixel2_words
from rasterhw.hdl.broadcast import StreamBroadcast
from rasterhw.hdl.zbm.compositor import RGB, ZbmCompositor
from rasterhw.hdl.zbm.layouts import PIXEL2
from rasterhw.hdl.zbm.mapper import ZbmMapper
from rasterhw.sim.engines import run as run_engine
from rasterhw.sim.testbench import Expected, Stimulus, Testbench, compare

__all__ = ["MappingBench", "mapping_accesses", "mapping_golden", "run_mapping", "scene_uv"]


def scene_uv(tris):
    """The triangles with planar screen-space (u, v) = (x / width, y / height)."""
    xy = np.asarray(tris.xy, float)
    uv = np.clip(xy / np.array([tris.width, tris.height], float), 0.0, 1.0)
    return dataclasses.replace(tris, uv=uv)


class _Mapping(wiring.Component):
    """``ZbmMapper`` -> ``ZbmCompositor``, the mapper's words also on ``o_map`` (a
    :class:`~rasterhw.hdl.broadcast.StreamBroadcast` between the two: no added latency when both are
    ready), the composited pixels on ``o``."""

    def __init__(self, texture, illum, background) -> None:
        self.mapper = ZbmMapper(texture=texture, illum=illum)
        self.comp = ZbmCompositor(background=tuple(int(v) for v in background))
        super().__init__({"i": In(stream.Signature(PIXEL2)), "o_map": Out(stream.Signature(PIXEL2)),
                          "o": Out(stream.Signature(RGB))})

    def elaborate(self, platform):
        m = Module()
        m.submodules.mapper, m.submodules.comp = self.mapper, self.comp
        m.submodules.split = split = StreamBroadcast(PIXEL2, n=2)
        wiring.connect(m, wiring.flipped(self.i), self.mapper.i)
        wiring.connect(m, self.mapper.o, split.i)
        wiring.connect(m, split.o[0], self.comp.i)
        wiring.connect(m, split.o[1], wiring.flipped(self.o_map))
        wiring.connect(m, self.comp.o, wiring.flipped(self.o))
        return m


class MappingBench(Testbench):
    """The mapper and the compositor of one frame (``zbm-mapper`` -> ``zbm-compositor``, not registered
    blocks of their own) on the generic engines: merged PIXEL2 words in (``i``), the mapped words
    (``o_map``) and the composited pixels (``o``, ``r | g << 8 | b << 16``) out; the lookup counters
    as status values. ``params``: ``texture``, ``illum`` (the maps), ``background``."""

    block = "zbm-mapping"
    outputs = ("o_map", "o")

    def params(self, **given) -> dict:
        return {"background": (0, 0, 0), **given}

    def dut(self, params: dict):
        return _Mapping(params["texture"], params["illum"], params["background"])

    def status(self, dut, params: dict) -> dict:
        return {"texture_lookups": dut.mapper.texture_lookups, "illum_lookups": dut.mapper.illum_lookups}

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        merged, mapped, rgb8 = stim.source
        img = np.asarray(rgb8, np.int64).reshape(-1, 3)
        return Expected({"o_map": pixel2_words(mapped),
                         "o": (img[:, 0] | img[:, 1] << 8 | img[:, 2] << 16).tolist()})


def run_mapping(merged, mapped, rgb8, texture, illum, *, engine: str = "pysim", background=(0, 0, 0)) -> dict:
    """The merged frame ``merged`` (DoubleZ) through :class:`MappingBench` on ``engine`` at full rate
    (no gaps, outputs always ready), compared with the golden ``mapped`` words and composited
    ``rgb8`` (``testbench.compare``). Returns ``{"mismatches", "words_compared", "cycles",
    "texture_lookups", "illum_lookups", "run"}``."""
    tb = MappingBench()
    p = tb.params(texture=texture, illum=illum, background=background)
    stim = Stimulus({"i": pixel2_words(merged)}, source=(merged, mapped, rgb8))
    exp = tb.expect(p, stim)
    got = run_engine(tb, p, stim, engine=engine, expect_words={k: len(v) for k, v in exp.words.items()})
    cmp = compare(exp, got)
    return {"mismatches": cmp["mismatches"], "ports": cmp["ports"], "words_compared": sum(map(len, exp.words.values())),
            "cycles": got.cycles, **got.status, "run": got}


def mapping_golden(scene: str, *, width: int = 512, height: int = 512, interleave: int = 8) -> dict:
    """The golden side of :func:`mapping_accesses`: the merged mapping-mode frame, its mapped
    samples, lookups after the merge (``map_samples``) and before it (one per rasterised sample)."""
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.pipeline import run_geometry

    tris = scene_uv(run_geometry(load_scene(scene), width, height))
    res = G.render_zbm(tris, interleave=interleave, mode=F.MODE_MAPPING)
    tex, il = default_maps()
    want, stats = map_samples(res.pixels, tex, il)
    return {"scene": scene, "width": width, "height": height, "interleave": interleave,
            "merged": res.pixels, "mapped": want, "rgb8": res.rgb8, "maps": (tex, il),
            "texture_lookups": int(stats["texture_lookups"]), "illum_lookups": int(stats["illum_lookups"]),
            "lookups_if_mapped_before_merge": int(res.stats["fragments"])}


def mapping_accesses(scene: str, *, width: int = 512, height: int = 512, interleave: int = 8,
                     golden: dict | None = None) -> dict:
    """Texture + illumination lookups of one frame, mapped after the merge (HDL mapper, pysim)
    and before it (every rasterised sample, the golden fragment count); the HDL's mapped words
    and composited pixels are checked against ``map_samples`` and ``composite``. ``golden``: the
    frame's :func:`mapping_golden`, if already computed."""
    g = golden or mapping_golden(scene, width=width, height=height, interleave=interleave)
    tex, il = g["maps"]
    hw = run_mapping(g["merged"], g["mapped"], g["rgb8"], tex, il)
    bad, bad_rgb = hw["ports"]["o_map"]["mismatches"], hw["ports"]["o"]["mismatches"]
    if bad or bad_rgb or hw["texture_lookups"] != g["texture_lookups"]:
        raise RasterhwError(f"ZB/M mapper: {bad} words / {bad_rgb} pixels differ, lookups "
                            f"{hw['texture_lookups']} != {g['texture_lookups']}")
    frags = g["lookups_if_mapped_before_merge"]
    return {"scene": scene, "width": width, "height": height, "mismatches": bad, "pixel_mismatches": bad_rgb,
            "texture_lookups": int(hw["texture_lookups"]), "illum_lookups": int(hw["illum_lookups"]),
            "lookups_if_mapped_before_merge": frags, "saved": 1 - hw["texture_lookups"] / frags,
            "cycles": hw["cycles"], "engine": "pysim", "words_compared": hw["words_compared"]}
