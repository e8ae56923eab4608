"""ZB/M pixel processor: one stop of the 112-bit segment loop, with a double-buffered
double-Z line memory.

Paper, sec. 5.4: "each pixel processor has an internal memory holding pixel information and
takes 1/8 of the chip's pixels, interleaved ... The internal memory is double-buffered; one
buffer is on the segment-loop side, the other on the merge-bus side. On the segment-loop side
it updates the segment packet by DDA and passes it to the next pixel processor; at the same
time it runs the Z-buffer hidden-surface test and updates the internal memory when needed.
On the merge-bus side it outputs the pixel information to the merge bus as the merger asks."
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.layouts import FLIT, PIXEL2, PKT_HEADER, SAMPLE, check_interleave

__all__ = ["ZbmPixelProcessor", "LoopSignature", "flit_to_sample_field", "EMPTY_PIXEL2"]

#: the clear value of a double-Z pixel: both samples "no sample"
EMPTY_PIXEL2 = {"s0": {"z": F.Z_EMPTY}, "s1": {"z": F.Z_EMPTY}}

#: One stop of the ring: a flit, its index in the packet (0 = header) and valid.
#: The ring never stalls (it is a systolic loop), so this is not a stream.
LoopSignature = wiring.Signature({
    "valid": Out(1),
    "idx": Out(range(F.PACKET_FLITS)),
    "flit": Out(unsigned(F.LOOP_BITS)),
})


def flit_to_sample_field(channel: str, value):
    """Channel value (signed Q.24, 56 bits) -> the sample field it is stored in.

    Same as ``golden_model.zbm._samples``: z, r, g, b, a round half up (``(v + 2**23) >> 24``,
    a 57-bit add so nothing wraps) and clamp to [0, Z_MAX_SAMPLE] or [0, 255]; the texel
    coordinates um, vm, ui, vi floor and wrap to TEX_BITS (the maps repeat).
    """
    if channel in ("um", "vm", "ui", "vi"):
        return (value >> F.ATTR_FRAC)[:F.TEX_BITS]
    r = (value + (1 << (F.ATTR_FRAC - 1))) >> F.ATTR_FRAC
    top = F.Z_MAX_SAMPLE if channel == "z" else (1 << F.COLOUR_BITS) - 1
    width = F.Z_BITS if channel == "z" else F.COLOUR_BITS
    return Mux(r < 0, 0, Mux(r > top, top, r[:width]))


@params("index", "interleave", "depth")
class ZbmPixelProcessor(wiring.Component):
    """One pixel processor of the segment loop.

    Parameters
    ----------
    index : int
        Position on the loop, 0..7: owns chip-local pixels ``j`` with ``j % 8 == index``.
    interleave : int
        Chips per unit (1, 2, 4, 8 or 16): chip-local pixel ``j = x // interleave``.
    width : int
        Screen width (<= ``MAX_WIDTH``); memory depth is ``ceil(width / (8 * interleave))``.

    Members
    -------
    i_loop : In(LoopSignature)
        Flit from the previous stop (or injected by the segment processor).
    o_loop : Out(LoopSignature)
        Flit to the next stop, registered: one cycle per hop. A packet whose header arrives
        with ``len == 0`` is finished and removed from the loop (valid dropped for all its flits).
    swap : In(1)
        Pulse: exchange the loop-side and merge-bus-side buffers (once per scan line).
    mb_addr : In(range(depth)), mb_rd : In(1), mb_data : Out(PIXEL2)
        Merge-bus side: ``mb_data`` is the pixel at ``mb_addr`` one cycle after ``mb_rd``;
        the read also clears the pixel (both samples empty) for the next line.

    Timing: a packet's header arrives at the pixel's owner; the memory is read with the
    header, Z-tested with flit 1 (z) and written with flit 7: read-modify-write in 8 cycles,
    and the same processor sees its next pixel of a packet at the earliest 8 cycles later.
    """

    def __init__(self, *, index: int, interleave: int = 1, width: int = F.MAX_WIDTH):
        if index not in range(F.PP_PER_CHIP):
            raise ValueError(f"index must be 0..{F.PP_PER_CHIP - 1}, not {index!r}")
        check_interleave(interleave)
        if not 1 <= width <= F.MAX_WIDTH:
            raise ValueError(f"width must be 1..{F.MAX_WIDTH}, not {width!r}")
        self._index = index
        self._interleave = interleave
        self._depth = max(1, -(-width // (F.PP_PER_CHIP * interleave)))
        super().__init__({
            "i_loop": In(LoopSignature),
            "o_loop": Out(LoopSignature),
            "swap": In(1),
            "mb_addr": In(range(self._depth)),
            "mb_rd": In(1),
            "mb_data": Out(PIXEL2),
        })

    def elaborate(self, platform):
        m = Module()
        depth = self._depth
        empty = PIXEL2.const(EMPTY_PIXEL2).as_value()
        shift = self._interleave.bit_length() - 1 + 3   # x -> chip-local -> address

        bank = Signal()          # which memory is on the loop side
        with m.If(self.swap):
            m.d.sync += bank.eq(~bank)

        mems = []
        for b in range(2):
            mem = Memory(shape=PIXEL2, depth=depth, init=[EMPTY_PIXEL2] * depth)
            m.submodules[f"mem{b}"] = mem
            mems.append((mem, mem.read_port(), mem.write_port()))

        # ---- segment-loop side
        i, o = self.i_loop, self.o_loop
        hdr = data.View(PKT_HEADER, i.flit)
        flit = data.View(FLIT, i.flit)
        live = Signal()          # this packet is still alive (its header had len >= 1)
        loop_addr = Signal(range(depth))
        loop_rd = Signal()
        is_hdr = i.valid & (i.idx == 0)
        alive_hdr = is_hdr & (hdr.len != 0)
        with m.If(is_hdr):
            m.d.sync += live.eq(hdr.len != 0)
        m.d.comb += [loop_addr.eq(hdr.x >> shift), loop_rd.eq(alive_hdr)]

        pass_ok = Mux(is_hdr, hdr.len != 0, live)
        m.d.sync += [o.valid.eq(i.valid & pass_ok), o.idx.eq(i.idx)]
        stepped_hdr = Signal(PKT_HEADER)
        m.d.comb += [stepped_hdr.eq(hdr), stepped_hdr.x.eq(hdr.x + hdr.dx), stepped_hdr.len.eq(hdr.len - 1)]
        stepped = Signal(FLIT)
        m.d.comb += [stepped.eq(flit), stepped.value.eq(flit.value + flit.inc)]
        m.d.sync += o.flit.eq(Mux(i.idx == 0, stepped_hdr.as_value(), stepped.as_value()))

        # Z test and sample assembly for the pixel this processor owns in this packet.
        addr_q = Signal(range(depth))
        mode = Signal()
        old = Signal(PIXEL2)
        new = Signal(SAMPLE)
        pos = Signal(2)          # 0: new is nearest, 1: second, 2: hidden
        rd_data = Signal(PIXEL2)
        m.d.comb += rd_data.eq(Mux(bank, mems[1][1].data, mems[0][1].data))
        with m.If(alive_hdr):
            m.d.sync += [addr_q.eq(loop_addr), mode.eq(hdr.mode)]
        cur = i.valid & live
        with m.If(cur & (i.idx == 1)):
            z = flit_to_sample_field("z", flit.value)
            m.d.sync += [old.eq(rd_data), new.eq(0), new.z.eq(z)]
            # Strict tests: on a tie the sample already stored (submitted first) stays ahead.
            m.d.sync += pos.eq(Mux(z < rd_data.s0.z, 0, Mux(z < rd_data.s1.z, 1, 2)))
        # flit k (2..7) carries r, g, b, a (colour) or um, vm, ui, vi, a (mapping); z is flit 1
        for k, (ch_c, ch_m) in enumerate(zip(("r", "g", "b", "a", None, None),
                                             ("um", "vm", "ui", "vi", "a", None), strict=True), start=2):
            with m.If(cur & (i.idx == k)):
                with m.If(mode == F.MODE_COLOUR):
                    if ch_c is not None:
                        tgt = new.a if ch_c == "a" else getattr(new, f"c{'rgb'.index(ch_c)}")
                        m.d.sync += tgt.eq(flit_to_sample_field(ch_c, flit.value))
                with m.Else():
                    if ch_m is not None:
                        tgt = new.a if ch_m == "a" else getattr(new, f"c{('um', 'vm', 'ui', 'vi').index(ch_m)}")
                        m.d.sync += tgt.eq(flit_to_sample_field(ch_m, flit.value))
        loop_we = Signal()
        loop_wdata = Signal(PIXEL2)
        m.d.comb += loop_we.eq(cur & (i.idx == F.PACKET_FLITS - 1) & (pos != 2))
        with m.If(pos == 0):
            m.d.comb += [loop_wdata.s0.eq(new), loop_wdata.s1.eq(old.s0)]
        with m.Else():
            m.d.comb += [loop_wdata.s0.eq(old.s0), loop_wdata.s1.eq(new)]

        # ---- merge-bus side: read and clear in the same cycle (read port is not transparent)
        for b, (_mem, rp, wp) in enumerate(mems):
            on_loop = bank == b
            m.d.comb += [
                rp.addr.eq(Mux(on_loop, loop_addr, self.mb_addr)),
                rp.en.eq(Mux(on_loop, loop_rd, self.mb_rd)),
                wp.addr.eq(Mux(on_loop, addr_q, self.mb_addr)),
                wp.en.eq(Mux(on_loop, loop_we, self.mb_rd)),
                wp.data.eq(Mux(on_loop, loop_wdata.as_value(), empty)),
            ]
        m.d.comb += self.mb_data.eq(Mux(bank, mems[0][1].data, mems[1][1].data))
        return m
