"""Mapping after the merge, measured in HDL (``hdl/zbm/mapper.py`` then ``hdl/zbm/compositor.py``
in one Amaranth pysim run): mapping-memory accesses per frame against mapping every rasterised
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
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.words import pixel2_words

__all__ = ["scene_uv", "run_mapper_pysim", "mapping_golden", "mapping_accesses"]


def scene_uv(tris):
    """The triangles with planar screen-space (u, v) = (x / width, y / height)."""
    xy = np.asarray(tris.xy, float)
    uv = np.clip(xy / np.array([tris.width, tris.height], float), 0.0, 1.0)
    return dataclasses.replace(tris, uv=uv)


def run_mapper_pysim(words: list[int], texture, illum, *, background=(0, 0, 0)) -> tuple[list[int], dict]:
    """Words through ``ZbmMapper`` -> ``ZbmCompositor`` at full rate (no gaps, output always ready).

    Returns the mapper's output words and ``{cycles, texture_lookups, illum_lookups, rgb}``
    (``rgb``: the compositor's pixels, ``r | g << 8 | b << 16``)."""
    from amaranth import Module
    from amaranth.lib import wiring
    from amaranth.sim import Simulator
    from rasterhw.hdl.zbm.compositor import ZbmCompositor
    from rasterhw.hdl.zbm.mapper import ZbmMapper

    m = Module()
    m.submodules.mapper = mapper = ZbmMapper(texture=texture, illum=illum)
    m.submodules.comp = comp = ZbmCompositor(background=tuple(int(v) for v in background))
    wiring.connect(m, mapper.o, comp.i)
    sim = Simulator(m)
    sim.add_clock(1e-8)
    got: list[int] = []
    rgb: list[int] = []
    out: dict = {}

    async def bench(ctx):
        ctx.set(comp.o.ready, 1)
        k = 0
        cycles = 0
        while len(rgb) < len(words):
            if k < len(words):
                ctx.set(mapper.i.valid, 1)
                ctx.set(mapper.i.payload.as_value(), words[k])
            else:
                ctx.set(mapper.i.valid, 0)
            _, _, rdy, mv, mr, mp, v, p = await ctx.tick().sample(
                mapper.i.ready, mapper.o.valid, mapper.o.ready, mapper.o.payload, comp.o.valid, comp.o.payload)
            cycles += 1
            if k < len(words) and rdy:
                k += 1
            if mv and mr:
                got.append(mp.as_value().value)
            if v:
                rgb.append(p.as_value().value)
        await ctx.tick()
        out.update(cycles=cycles, texture_lookups=ctx.get(mapper.texture_lookups),
                   illum_lookups=ctx.get(mapper.illum_lookups), rgb=rgb)

    sim.add_testbench(bench)
    sim.run()
    return got, out


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
    got, hw = run_mapper_pysim(pixel2_words(g["merged"]), tex, il)
    bad = int(np.count_nonzero(np.array(got, dtype=object) != np.array(pixel2_words(g["mapped"]), dtype=object)))
    img = np.asarray(g["rgb8"], np.int64).reshape(-1, 3)
    want_rgb = img[:, 0] | img[:, 1] << 8 | img[:, 2] << 16
    bad_rgb = int(np.count_nonzero(np.asarray(hw["rgb"], np.int64) != want_rgb))
    if bad or bad_rgb or hw["texture_lookups"] != g["texture_lookups"]:
        raise RasterhwError(f"ZB/M mapper: {bad} words / {bad_rgb} pixels differ, lookups "
                            f"{hw['texture_lookups']} != {g['texture_lookups']}")
    frags = g["lookups_if_mapped_before_merge"]
    return {"scene": scene, "width": width, "height": height, "mismatches": bad, "pixel_mismatches": bad_rgb,
            "texture_lookups": int(hw["texture_lookups"]), "illum_lookups": int(hw["illum_lookups"]),
            "lookups_if_mapped_before_merge": frags, "saved": 1 - hw["texture_lookups"] / frags,
            "cycles": hw["cycles"], "engine": "pysim"}
