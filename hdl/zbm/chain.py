"""ZB/M second level: units chained by their merge ports (a simulation top, no ports of its own)."""

from __future__ import annotations

from amaranth import Module
from amaranth.lib import wiring
from rasterhw.hdl.zbm.unit import ZbmUnit

__all__ = ["ZbmChain"]


class ZbmChain(wiring.Component):
    """Units chained head to tail: ``units[k].o_merge[c]`` drives ``units[k+1].i_merge[c]``.

    The paper's second level of parallelism (section 2: "images are composed scan line by scan
    line by Z-merge"). ``units[0]`` should be built with ``head=True``; the last unit's
    ``o_merge`` ports carry the composed lines. Used as the top of pysim benches.

    Parameters
    ----------
    units : list of ZbmUnit, all with the same interleave.
    """

    def __init__(self, units: list[ZbmUnit]):
        if not units:
            raise ValueError("a chain needs at least one unit")
        if len({u.interleave for u in units}) != 1:
            raise ValueError("chained units must have the same interleave")
        self._units = list(units)
        super().__init__({})

    @property
    def units(self) -> list[ZbmUnit]:
        return list(self._units)

    def elaborate(self, platform):
        m = Module()
        for k, u in enumerate(self._units):
            m.submodules[f"u{k}"] = u
        for a, b in zip(self._units, self._units[1:], strict=False):
            for c in range(a.interleave):
                wiring.connect(m, a.o_merge[c], b.i_merge[c])
        return m
