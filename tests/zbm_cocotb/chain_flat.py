# amaranth: UnusedElaboratable=no
"""``zbm_chain_flat``: the top the cocotb unit bench (``tests/zbm_cocotb/tb_zbm_unit.v``) puts
around a chain of generated ``zbm-unit``\\s, written in Amaranth and converted like any block.

Unit 0 is the generated head ``zbm_unit`` (no merge inputs); units 1.. are the generated
``zbm_unit_tail`` (``head=False``, the same Verilog with the module renamed), chained by their
merge ports: chip slot ``c`` of unit ``k`` feeds slot ``c`` of unit ``k + 1``. The units' ports
are packed into vectors for the bench: ``i_*`` one slice per unit, ``o_*`` one slice per chip
slot of the last unit, ``cycles`` / ``frames`` / ``overflow`` one slice per unit (``overflow`` 0
for units built without one).
"""

from __future__ import annotations

from amaranth import ClockSignal, Elaboratable, Instance, Module, ResetSignal, Signal
from rasterhw.golden_model.zbm import formats as F

__all__ = ["ChainFlat"]


class ChainFlat(Elaboratable):
    """``units`` instances of the generated units (``interleave`` merge slots each) with their
    ports packed; ``ports`` lists the top's ports after the clocks and resets."""

    def __init__(self, *, interleave: int, units: int, has_overflow: bool):
        I, U, EW, MW = interleave, units, F.EP_WORD_BITS, F.PIXEL2.width  # noqa: E741
        self._interleave, self._units, self._has_overflow = interleave, units, has_overflow
        self.i_valid = Signal(U, name="i_valid")
        self.i_ready = Signal(U, name="i_ready")
        self.i_payload = Signal(EW * U, name="i_payload")
        self.o_valid = Signal(I, name="o_valid")
        self.o_ready = Signal(I, name="o_ready")
        self.o_payload = Signal(MW * I, name="o_payload")
        self.cycles = Signal(32 * U, name="cycles")
        self.frames = Signal(16 * U, name="frames")
        self.overflow = Signal(U, name="overflow")
        self.ports = [self.i_valid, self.i_ready, self.i_payload, self.o_valid, self.o_ready, self.o_payload,
                      self.cycles, self.frames, self.overflow]

    def elaborate(self, platform):
        m = Module()
        I, U, EW, MW = self._interleave, self._units, F.EP_WORD_BITS, F.PIXEL2.width  # noqa: E741
        # merge links between unit k and k + 1, per slot
        links = [[(Signal(name=f"m{k}_{c}_v"), Signal(name=f"m{k}_{c}_r"), Signal(MW, name=f"m{k}_{c}_p"))
                  for c in range(I)] for k in range(U - 1)]
        for k in range(U):
            ports = {"i_clk": ClockSignal("sync"), "i_rst": ResetSignal("sync"),
                     "i_merge_clk": ClockSignal("merge"), "i_merge_rst": ResetSignal("merge"),
                     "i_i__valid": self.i_valid[k], "o_i__ready": self.i_ready[k],
                     "i_i__payload": self.i_payload[EW * k:EW * (k + 1)],
                     "o_cycles": self.cycles[32 * k:32 * (k + 1)], "o_frames": self.frames[16 * k:16 * (k + 1)]}
            if self._has_overflow:
                ports["o_overflow"] = self.overflow[k]
            for c in range(I):
                if k == U - 1:
                    v, r, p = self.o_valid[c], self.o_ready[c], self.o_payload[MW * c:MW * (c + 1)]
                else:
                    v, r, p = links[k][c]
                ports.update({f"o_o_merge__{c}__valid": v, f"i_o_merge__{c}__ready": r,
                              f"o_o_merge__{c}__payload": p})
                if k > 0:
                    v, r, p = links[k - 1][c]
                    ports.update({f"i_i_merge__{c}__valid": v, f"o_i_merge__{c}__ready": r,
                                  f"i_i_merge__{c}__payload": p})
            m.submodules[f"u{k}"] = Instance("zbm_unit" if k == 0 else "zbm_unit_tail", **ports)
        if not self._has_overflow:
            m.d.comb += self.overflow.eq(0)
        return m
