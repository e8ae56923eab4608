"""Mapping after the merge, measured in HDL (``hdl/zbm/mapper.py`` in Amaranth pysim): mapping-
memory accesses per frame against mapping every rasterised sample (paper, sec. 3.3).

The scenes carry no texture coordinates; ``scene_uv`` gives them a planar screen-space mapping
(u = x / width, v = y / height: one texture over the frame), stated once here and in docs/zbm.md.
The mapper is fed the golden merged words of each chip slot's chain (``render_zbm(mode=MAPPING)``;
the unit HDL that produces them is checked word for word elsewhere) and its output is compared
with ``map_samples`` word for word.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.words import pixel2_words

__all__ = ["scene_uv", "run_mapper_pysim", "mapping_accesses"]


def scene_uv(tris):
    """The triangles with planar screen-space (u, v) = (x / width, y / height)."""
    xy = np.asarray(tris.xy, float)
    uv = np.clip(xy / np.array([tris.width, tris.height], float), 0.0, 1.0)
    return dataclasses.replace(tris, uv=uv)


def run_mapper_pysim(words: list[int], texture, illum) -> tuple[list[int], dict]:
    """Words through ``ZbmMapper`` at full rate (no gaps, output always ready)."""
    from amaranth.sim import Simulator
    from rasterhw.hdl.zbm.mapper import ZbmMapper

    dut = ZbmMapper(texture=texture, illum=illum)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    got: list[int] = []
    out: dict = {}

    async def bench(ctx):
        ctx.set(dut.o.ready, 1)
        k = 0
        cycles = 0
        while len(got) < len(words):
            if k < len(words):
                ctx.set(dut.i.valid, 1)
                ctx.set(dut.i.payload.as_value(), words[k])
            else:
                ctx.set(dut.i.valid, 0)
            _, _, rdy, v, p = await ctx.tick().sample(dut.i.ready, dut.o.valid, dut.o.payload)
            cycles += 1
            if k < len(words) and rdy:
                k += 1
            if v:
                got.append(p.as_value().value)
        await ctx.tick()
        out.update(cycles=cycles, texture_lookups=ctx.get(dut.texture_lookups),
                   illum_lookups=ctx.get(dut.illum_lookups))

    sim.add_testbench(bench)
    sim.run()
    return got, out


def mapping_accesses(scene: str, *, width: int = 512, height: int = 512, interleave: int = 8) -> dict:
    """Texture + illumination lookups of one frame, mapped after the merge (HDL) and before it
    (every rasterised sample, the golden fragment count)."""
    from rasterhw.golden_model.meshio import load_scene
    from rasterhw.golden_model.pipeline import run_geometry

    tris = scene_uv(run_geometry(load_scene(scene), width, height))
    res = G.render_zbm(tris, interleave=interleave, mode=F.MODE_MAPPING)
    tex, il = default_maps()
    want, stats = map_samples(res.pixels, tex, il)
    got, hw = run_mapper_pysim(pixel2_words(res.pixels), tex, il)
    bad = int(np.count_nonzero(np.array(got, dtype=object) != np.array(pixel2_words(want), dtype=object)))
    if bad or hw["texture_lookups"] != stats["texture_lookups"]:
        raise RasterhwError(f"ZB/M mapper: {bad} words differ / lookups {hw} != {stats}")
    frags = int(res.stats["fragments"])
    return {"scene": scene, "width": width, "height": height, "mismatches": bad,
            "texture_lookups": int(hw["texture_lookups"]), "illum_lookups": int(hw["illum_lookups"]),
            "lookups_if_mapped_before_merge": frags, "saved": 1 - hw["texture_lookups"] / frags,
            "cycles": hw["cycles"], "engine": "pysim"}
