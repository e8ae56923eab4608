"""ZB/M segment generator: input FIFO, active-edge-pair memory, adders (paper, sec. 4, fig. 4).

Paper: "The input FIFO at the top buffers between the level-1 processors and the segment
generator. The active-edge-pair memory in the middle holds the active edge pairs; the adders
and registers at the bottom update them. Active edge pairs are read in order, updated, and
only the ones still needed are stored back; the others are discarded. When one scan line
has been updated, the edge pairs that become active on the next line are taken from the FIFO."
"Segments of different edge pairs on the same scan line must be output together."

Bit-exact with ``golden_model.zbm.segment_generator`` (same per-line order: load, then emit
in memory order, step, store back the pairs still needed).

Input protocol: edge-pair records of 9 words (``EP_HEADER`` + 8 ``EP_CHANNEL``, 168 bits each,
:func:`golden_model.zbm.formats.pack_edge_pair`) in FIFO order (top lines non-decreasing);
an ``EP_HEADER`` word with ``h == 0`` (and no channel words) ends the frame. Output: the
chip segment-input records (``SEG_HEADER`` + channel ``FLIT`` words) of every line, each line
closed by an end-of-line ``SEG_HEADER`` with ``len == 0`` (see ``hdl/zbm/chip.py``).
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, fifo, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.zbm import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.zbm.layouts import (
    EP_CHANNEL,
    EP_HEADER,
    FLIT,
    GAP,
    SEG_HEADER,
    check_schedule,
    paper_lead,
)

__all__ = ["ZbmSegmentGenerator", "EP_WORD_BITS"]

EP_WORD_BITS = F.EP_WORD_BITS
N_CH = F.EP_WORDS - 1                         # x, len + up to 6 attribute channels
_CHAN = data.StructLayout({"value": signed(56), "ddy": signed(56), "ddx": signed(56)})
#: one active edge pair as the memory holds it
AEP = data.StructLayout({
    "y": unsigned(9),        # top line (used only while loading)
    "left": unsigned(10),    # lines still to emit, 1..512
    "mode": unsigned(1),
    "ch": data.ArrayLayout(_CHAN, N_CH),   # ch[0] = x, ch[1] = len (Q.40), ch[2..] attributes (Q.24)
})


class _State(enum.Enum, shape=3):
    CHECK = 0        # look at the FIFO head: load it, or read the first active pair
    LOAD = 1         # channel words 1..8 of an edge pair; the record is appended with word 8
    SEG = 2          # the pair just read (read-port data) sends its header, or is empty
    FLIT = 3         # channel flits; with the last one: write back, read the next pair
    EOL = 4          # end-of-line word
    FRAME_END = 5    # consume the end-of-frame marker
    OVERFLOW = 6     # a due pair does not fit: stalled for good (sticky ``overflow``)


@params("schedule", "width", "height", "capacity")
class ZbmSegmentGenerator(wiring.Component):
    """Edge pairs -> per-line segments for the chips of one unit.

    Parameters
    ----------
    width, height : int
        Frame size (1..512); segments are clipped to ``[0, width)``; lines 0..height-1.
    capacity : int
        Active-edge-pair memory depth (golden ``AEP_CAPACITY`` = 256; paper silent).
    fifo_depth : int
        Input FIFO depth in 168-bit words.
    schedule : str
        ``"overlap"`` (ours: a due edge pair is loaded at once, while the chips still work) or
        ``"paper"`` (sec. 6.1 cond. 4-5: a due pair is loaded only when every chip's ring gap
        ``zbm_gap`` is at most ``paper_lead(mode) + 1``, so the 9 load cycles leave the ring
        idle for exactly 9 cycles).

    Members
    -------
    i : In(stream.Signature(unsigned(168)))
        Edge-pair words into the input FIFO.
    o : Out(stream.Signature(unsigned(112)))
        Segment words to the chips (broadcast by the unit).
    line : Out(9)
        Line being generated.
    frames : Out(16)
        Frames completed.
    overflow : Out(1)
        Sticky: a line needs more active edge pairs than ``capacity``. The generator then
        stops (no word of that line is emitted; the input FIFO fills and ``i.ready`` falls)
        until reset. Nothing is ever dropped.
    zbm_gap : In(GAP) (``schedule="paper"`` only)
        The largest ring gap of the unit's chips (``ZbmChip.gap``).

    Timing (segment clock, every word held until the chips accept it): per line, 1 cycle
    (CHECK: the FIFO head is examined and, if no pair is due, the first active pair is read in
    the same cycle) + 9 per edge pair loaded (its 9 FIFO words, one per cycle, the paper's
    figure; the record is appended with the 9th word; a load that follows another overlaps
    its header word with the CHECK) + per active pair ``1 + channels`` words if its segment is
    non-empty, else 1 cycle (the pair's write-back and the read of the next pair happen with
    its last word) + 1 end-of-line word. ``golden_model.zbm.cycles.hdl_cycles`` counts this.
    """

    def __init__(self, *, width: int = F.MAX_WIDTH, height: int = F.MAX_HEIGHT,
                 capacity: int = F.AEP_CAPACITY, fifo_depth: int = 32, schedule: str = "overlap"):
        check_schedule(schedule)
        self._schedule = schedule
        if not (isinstance(width, int) and 1 <= width <= F.MAX_WIDTH):
            raise ValueError(f"width must be 1..{F.MAX_WIDTH}, not {width!r}")
        if not (isinstance(height, int) and 1 <= height <= F.MAX_HEIGHT):
            raise ValueError(f"height must be 1..{F.MAX_HEIGHT}, not {height!r}")
        if not (isinstance(capacity, int) and 1 <= capacity <= 1024):
            raise ValueError(f"capacity must be 1..1024, not {capacity!r}")
        self._width, self._height, self._capacity = width, height, capacity
        self._fifo_depth = fifo_depth
        members = {
            "i": In(stream.Signature(unsigned(EP_WORD_BITS))),
            "o": Out(stream.Signature(unsigned(F.LOOP_BITS))),
            "line": Out(9),
            "frames": Out(16),
            "overflow": Out(1),
        }
        if schedule == "paper":
            members["zbm_gap"] = In(GAP)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        cap = self._capacity
        m.submodules.fifo = fq = fifo.SyncFIFOBuffered(width=EP_WORD_BITS, depth=self._fifo_depth)
        wiring.connect(m, wiring.flipped(self.i), fq.w_stream)
        head = data.View(EP_HEADER, fq.r_data)
        head_ch = data.View(EP_CHANNEL, fq.r_data)

        m.submodules.mem = mem = Memory(shape=AEP, depth=cap, init=[])
        rp = mem.read_port()
        wp = mem.write_port()

        rec = Signal(AEP)                    # edge pair being loaded
        cur = data.View(AEP, rp.data)        # active pair being emitted (read port holds it)
        y = self.line
        n_mem = Signal(range(cap + 1))       # active pairs in memory
        word = Signal(range(F.EP_WORDS))
        r = Signal(range(cap + 1))           # read index of the emit pass (pairs read so far)
        w = Signal(range(cap + 1))           # write-back index (w <= r: in-place compaction)
        off = Signal(unsigned(24))           # Q.16 (OFF_FRAC) distance from the left edge to the first centre
        c = Signal(range(N_CH + 1))          # attribute channel being sent (2..)
        state = Signal(_State)
        n_attr = Mux(cur.mode == F.MODE_MAPPING, len(F.CHANNELS[F.MODE_MAPPING]),
                     len(F.CHANNELS[F.MODE_COLOUR]))

        # left-end pixel range: first centre >= edge, i.e. ceil(xq - 0.5) (golden _px_ceil)
        half_x, one_x = 1 << (F.X_FRAC - 1), 1 << F.X_FRAC

        def px_ceil(xq):
            return (xq - half_x + (one_x - 1)) >> F.X_FRAC

        xl = cur.ch[0].value
        xr = xl + cur.ch[1].value               # 57-bit: no wrap, as the golden int64 sum
        s_raw, e_raw = px_ceil(xl), px_ceil(xr)
        s_cl = Mux(s_raw < 0, 0, s_raw)
        e_cl = Mux(e_raw > self._width, self._width, e_raw)

        m.d.comb += [wp.en.eq(0), rp.en.eq(0)]
        m.d.comb += self.o.valid.eq(0)

        def retire():
            """The current pair is done: step it and store it back if still needed (the adders:
            every channel one line down, 56-bit wrap); read the next pair, or end the line."""
            stepped = Signal(AEP)
            m.d.comb += [stepped.eq(cur), stepped.left.eq(cur.left - 1)]
            for k in range(N_CH):
                m.d.comb += stepped.ch[k].value.eq(cur.ch[k].value + cur.ch[k].ddy)
            keep = cur.left > 1
            with m.If(keep):
                m.d.comb += [wp.en.eq(1), wp.addr.eq(w), wp.data.eq(stepped)]
            m.d.sync += w.eq(w + keep)
            with m.If(r == n_mem):
                m.d.sync += [state.eq(_State.EOL), n_mem.eq(w + keep)]
            with m.Else():
                m.d.comb += [rp.en.eq(1), rp.addr.eq(r)]
                m.d.sync += [r.eq(r + 1), state.eq(_State.SEG)]

        with m.Switch(state):
            # ---------------- (1) loader: pairs whose top line has been reached
            with m.Case(_State.CHECK):
                with m.If(fq.r_rdy):
                    with m.If((head.h != 0) & (head.y <= y)):
                        if self._schedule == "paper":   # cond. 5: load only as the ZB/M runs dry
                            lead = Mux(head.mode == F.MODE_MAPPING, paper_lead(F.MODE_MAPPING),
                                       paper_lead(F.MODE_COLOUR))
                            zbm_busy = self.zbm_gap > lead + 1
                        else:
                            zbm_busy = 0
                        with m.If(n_mem == cap):             # due but no room: cannot make line y
                            m.d.sync += [state.eq(_State.OVERFLOW), self.overflow.eq(1)]
                        with m.Elif(zbm_busy):
                            pass
                        with m.Else():
                            m.d.comb += fq.r_en.eq(1)
                            m.d.sync += [rec.eq(0), rec.y.eq(head.y), rec.left.eq(head.h),
                                         rec.mode.eq(head.mode), word.eq(1), state.eq(_State.LOAD)]
                    with m.Elif(n_mem == 0):                 # nothing due, nothing active
                        m.d.sync += state.eq(_State.EOL)
                    with m.Else():                           # emit: read the first pair now
                        m.d.comb += [rp.en.eq(1), rp.addr.eq(0)]
                        m.d.sync += [r.eq(1), w.eq(0), state.eq(_State.SEG)]
            with m.Case(_State.LOAD):
                with m.If(fq.r_rdy):
                    m.d.comb += fq.r_en.eq(1)
                    full = Signal(AEP)
                    m.d.comb += full.eq(rec)
                    with m.Switch(word):
                        for k in range(1, F.EP_WORDS):
                            with m.Case(k):
                                m.d.sync += [rec.ch[k - 1].value.eq(head_ch.value),
                                             rec.ch[k - 1].ddy.eq(head_ch.ddy),
                                             rec.ch[k - 1].ddx.eq(head_ch.ddx)]
                                if k == F.EP_WORDS - 1:
                                    m.d.comb += [full.ch[k - 1].value.eq(head_ch.value),
                                                 full.ch[k - 1].ddy.eq(head_ch.ddy),
                                                 full.ch[k - 1].ddx.eq(head_ch.ddx)]
                    m.d.sync += word.eq(word + 1)
                    with m.If(word == F.EP_WORDS - 1):       # append with the last word
                        m.d.comb += [wp.en.eq(1), wp.addr.eq(n_mem), wp.data.eq(full)]
                        m.d.sync += [n_mem.eq(n_mem + 1), state.eq(_State.CHECK)]
            # ---------------- (2) emit: in memory order, send, step, store back if needed
            with m.Case(_State.SEG):
                with m.If(e_cl > s_cl):
                    hdr = data.View(SEG_HEADER, self.o.payload)
                    m.d.comb += [self.o.valid.eq(1), hdr.y.eq(y), hdr.x.eq(s_cl),
                                 hdr.len.eq(e_cl - s_cl), hdr.mode.eq(cur.mode)]
                    with m.If(self.o.ready):
                        # Q.16 (OFF_FRAC) offset from the edge to the first centre (>= 0)
                        m.d.sync += [off.eq(((s_cl << F.X_FRAC) + half_x - xl) >> (F.X_FRAC - F.OFF_FRAC)),
                                     c.eq(2), state.eq(_State.FLIT)]
                with m.Else():                               # empty after fill rule / clipping
                    retire()
            with m.Case(_State.FLIT):
                ch = cur.ch[c]
                fl = data.View(FLIT, self.o.payload)
                m.d.comb += [self.o.valid.eq(1),
                             fl.value.eq(ch.value + ((off * ch.ddx) >> F.OFF_FRAC)),
                             fl.inc.eq(ch.ddx)]
                with m.If(self.o.ready):
                    m.d.sync += c.eq(c + 1)
                    with m.If(c == n_attr + 1):
                        retire()
            with m.Case(_State.EOL):
                hdr = data.View(SEG_HEADER, self.o.payload)
                m.d.comb += [self.o.valid.eq(1), hdr.y.eq(y), hdr.len.eq(0)]
                with m.If(self.o.ready):
                    with m.If(y == self._height - 1):
                        m.d.sync += [state.eq(_State.FRAME_END), word.eq(0)]
                    with m.Else():
                        m.d.sync += [y.eq(y + 1), state.eq(_State.CHECK)]
            with m.Case(_State.FRAME_END):
                # Every pair ends inside the frame, so the next word is the end-of-frame
                # marker; words of a malformed stream before it are skipped.
                with m.If(fq.r_rdy):
                    m.d.comb += fq.r_en.eq(1)
                    with m.If((word == 0) & (head.h == 0)):
                        m.d.sync += [y.eq(0), n_mem.eq(0),
                                     self.frames.eq(self.frames + 1), state.eq(_State.CHECK)]
                    with m.Else():
                        m.d.sync += word.eq(Mux(word == F.EP_WORDS - 1, 0, word + 1))
            with m.Case(_State.OVERFLOW):
                pass
        return m
