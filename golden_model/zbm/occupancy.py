"""How much of a unit's segment loop holds work: the flits on the pixel processors' inputs.

Golden model of the ZB/M (seed 003), counted from the initial processors' packets (the same
function the HDL is checked against, ``initial.initial_processor``). A packet of ``n`` pixels
for a chip enters the loop at the processor owning its first pixel; each clock every flit moves
one processor on, so its ``PACKET_FLITS`` flits are on the input of ``n`` processors that write
a pixel and of one more that sees the header's ``len == 0`` and drops the packet
(``hdl/zbm/pixel.py``). Divided by ``cycles x PP_PER_CHIP x interleave`` (every processor's
clocks of a frame) it is the fraction of processor-clocks on which a processor has a flit; the
rest the HDL simulates as idle hardware.
"""

from __future__ import annotations

from rasterhw.golden_model.zbm.formats import PACKET_FLITS, PP_PER_CHIP, check_interleave
from rasterhw.golden_model.zbm.initial import initial_processor
from rasterhw.golden_model.zbm.seggen import Segments

__all__ = ["loop_occupancy"]


def loop_occupancy(segs: Segments, interleave: int, width: int, cycles: int | None = None) -> dict:
    """``{"packets", "pixels", "flit_clocks"}`` over every chip of a unit drawing ``segs``, and,
    given the frame's ``cycles``, ``"processor_clocks"`` (``cycles x 8 x interleave``) and
    ``"busy_fraction"`` (``flit_clocks / processor_clocks``)."""
    check_interleave(interleave)
    packets = pixels = 0
    for chip in range(min(interleave, width)):
        _, n, _, _, keep = initial_processor(segs.x, segs.len, segs.val, segs.inc, chip, interleave)
        packets += int(keep.sum())
        pixels += int(n[keep].sum())
    out = {"packets": packets, "pixels": pixels, "flit_clocks": PACKET_FLITS * (pixels + packets)}
    if cycles is not None:
        out["processor_clocks"] = int(cycles) * PP_PER_CHIP * interleave
        out["busy_fraction"] = out["flit_clocks"] / out["processor_clocks"] if cycles else float("nan")
    return out
