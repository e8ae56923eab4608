"""Mapping after the merge: texture / illumination-map lookups on the surviving samples
(mapping mode), so only visible samples touch mapping memory.

Golden model of the ZB/M (seed 003); integer arithmetic with the hardware's widths
(:mod:`rasterhw.golden_model.zbm.formats`), bit for bit what the HDL computes.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm.doublez import DoubleZ
from rasterhw.golden_model.zbm.formats import (
    TEX,
    Z_EMPTY,
)

__all__ = ["default_maps", "map_samples"]


def default_maps(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A seeded 256x256 RGB texture (checker + noise) and a 256x256 illumination map."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.arange(TEX), np.arange(TEX))
    chk = ((u // 32 + v // 32) % 2).astype(np.int64)
    tex = np.stack([chk * 200 + 40, (1 - chk) * 180 + 50, rng.integers(0, 256, (TEX, TEX))], axis=-1)
    illum = (128 + 127 * np.cos(u / TEX * 2 * np.pi) * np.sin(v / TEX * np.pi)).astype(np.int64)
    return tex.astype(np.int64), np.clip(illum, 0, 255)


def map_samples(px: DoubleZ, texture: np.ndarray, illum: np.ndarray) -> tuple[DoubleZ, dict]:
    """Mapping after the merge: look up only samples that reach the output.

    A sample reaches the output if it is s0 and valid, or s1, valid, behind a non-opaque s0.
    Colour = ``(tex[vm, um] * illum[vi, ui] + 127) // 255`` per channel. Returns colour-mode
    samples and ``{"texture_lookups", "illum_lookups"}``.
    """
    tex = np.asarray(texture, np.int64)
    il = np.asarray(illum, np.int64)
    if tex.shape != (TEX, TEX, 3) or il.shape != (TEX, TEX):
        raise RasterhwError(f"ZB/M: texture must be ({TEX}, {TEX}, 3) and illum ({TEX}, {TEX}), "
                            f"got {tex.shape}, {il.shape}")
    out = px.copy()
    valid = px.z != Z_EMPTY
    need = valid.copy()
    need[..., 1] &= px.a[..., 0] < 255
    um, vm, ui, vi = (px.c[..., i] for i in range(4))
    t = tex[vm[need], um[need]]
    lit = il[vi[need], ui[need]]
    out.c[need] = 0
    out.c[..., :3][need] = (t * lit[:, None] + 127) // 255
    out.c[~need] = 0
    n = int(need.sum())
    return out, {"texture_lookups": n, "illum_lookups": n}
