"""What an EXPERTS processor's elaborated HDL has: its multipliers and their operand widths.

Counted from the design Amaranth elaborates (its RTLIL, ``amaranth.back.rtlil.convert``), not typed:
every ``$mul`` cell whose two operands are both signals is a multiplier (a ``$mul`` by a constant,
e.g. ``2 * wdt``, is a shift or an adder, not a multiplier, and is not counted). ``bits`` is the
widest operand of any multiplier: what a "16-bit basic operation width" means for a multiplier
("SLP、PXPの基本演算データ幅は16ビットである", seed 000 3.2), a 16 x 16 multiplier giving its
32-bit product.

:func:`frame_census` counts the processors ``rasterhw sim experts`` chains at either datapath
(``formats.DATAPATHS``): the SLP's set-up (``experts-slp-setup``), the SLP's list work
(``experts-slp``), and the frame's PXP: the coherent span PXP (``experts-pxp-coherent``) or the span
PXP (``experts-pxp-span``); at ``datapath="paper"`` each has one multiplier, shared by its resolve
side and its drain's A.J. blend.
Its ``datapath_bits`` is the widest multiplier operand over them, ``multipliers`` the most
multipliers in one processor.
"""

from __future__ import annotations

import re

__all__ = ["multipliers", "census", "frame_census"]

_CELL = re.compile(r"^\s*cell \$mul \S+\n(.*?)^\s*end\n", re.S | re.M)
_CONST = re.compile(r"^\d+'[01xz-]+$")


def multipliers(component) -> list[tuple[int, int]]:
    """The ``(A width, B width)`` of every multiplier of ``component``'s elaborated design."""
    from amaranth.back import rtlil
    out = []
    for body in _CELL.findall(rtlil.convert(component)):
        par = dict(re.findall(r"parameter \\(\w+) (\S+)", body))
        con = dict(re.findall(r"connect \\([AB]) (.+)", body))
        if not any(_CONST.match(con.get(p, "").strip()) for p in "AB"):
            out.append((int(par["A_WIDTH"]), int(par["B_WIDTH"])))
    return out


def census(component) -> dict:
    """``multipliers`` (count), ``bits`` (widest operand, 0 without one) and ``widths`` of one design."""
    ms = multipliers(component)
    return {"multipliers": len(ms), "bits": max((max(a, b) for a, b in ms), default=0), "widths": ms}


def frame_census(datapath: str, *, pxp_datapath: str, width: int = 512, height: int = 512, aj: str = "c",
                 pxp: str = "span") -> dict:
    """The chained frame's processors, each elaborated and counted (:func:`census`): the SLP's
    set-up and list work at ``datapath``, the frame's PXP (``pxp``: ``"span"``, ``experts-pxp-span``,
    or ``"coherent"``, ``experts-pxp-coherent``) at ``pxp_datapath`` (what the driver builds).
    Returns ``per_block`` (block -> census),
    ``datapath_bits`` (widest multiplier operand of them all), ``multipliers`` (most in one
    processor), ``source`` ``"hdl:elaborated"``."""
    from rasterhw.golden_model.experts.formats import DATAPATHS
    from rasterhw.hdl.experts.pxp_coherent import ExpertsPxpCoherent
    from rasterhw.hdl.experts.pxp_span import ExpertsPxpSpan
    from rasterhw.hdl.experts.slp import ExpertsSlp
    from rasterhw.hdl.experts.slp_setup import ExpertsSlpSetup
    ex = DATAPATHS[datapath].acc_extra
    per = {"experts-slp-setup": census(ExpertsSlpSetup(height=height, acc_extra=ex)),
           "experts-slp": census(ExpertsSlp(width=width, lines=height, acc_extra=ex)),
           f"experts-pxp-{pxp}": census({"span": ExpertsPxpSpan, "coherent": ExpertsPxpCoherent}[pxp](
               width=width, aj=aj, datapath=pxp_datapath))}
    return {"datapath": datapath, "per_block": per, "datapath_bits": max(c["bits"] for c in per.values()),
            "multipliers": max(c["multipliers"] for c in per.values()), "source": "hdl:elaborated"}
