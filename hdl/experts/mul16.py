"""The paper's multiplier: one 16 x 16 unsigned array, signed operands as sign and magnitude.

Seed 000, 3.2: the SLP "乗算器、および逆数表(ROMによる)を装備した" and the PXP "SLP同様、乗算器を装備
している", in a machine whose "SLP、PXPの基本演算データ幅は16ビットである". :func:`sm_mul` is that
multiplier as both processors use it under ``--datapath paper``: ``a * b`` for ``|a|, |b| <= 65535``
(a pixel or line offset in Q10.6, an increment or dz/dx, di/dx as a 16-bit two's complement word,
``|-32768| = 32768``), the magnitudes multiplied by one ``$mul`` of two 16-bit operands and the
32-bit product negated when the signs differ, so it equals the signed product exactly.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, signed
from rasterhw.golden_model.experts.formats import WORD

__all__ = ["sm_mul"]


def sm_mul(m: Module, a, b, name: str = "mul") -> Signal:
    """``a * b`` (signed, ``|a|, |b| < 2**16``) through one 16 x 16 unsigned multiplier."""
    na, nb = Signal(name=f"{name}_na"), Signal(name=f"{name}_nb")
    ma, mb = Signal(WORD, name=f"{name}_ma"), Signal(WORD, name=f"{name}_mb")
    pu = Signal(2 * WORD, name=f"{name}_pu")
    p = Signal(signed(2 * WORD + 2), name=name)
    m.d.comb += [na.eq(a < 0), nb.eq(b < 0), ma.eq(Mux(na, -a, a)), mb.eq(Mux(nb, -b, b)),
                 pu.eq(ma * mb), p.eq(Mux(na ^ nb, -pu, pu))]
    return p
