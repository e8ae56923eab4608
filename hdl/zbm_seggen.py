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
:func:`golden_model.zbm_formats.pack_edge_pair`) in FIFO order (top lines non-decreasing);
an ``EP_HEADER`` word with ``h == 0`` (and no channel words) ends the frame. Output: the
chip segment-input records (``SEG_HEADER`` + channel ``FLIT`` words) of every line, each line
closed by an end-of-line ``SEG_HEADER`` with ``len == 0`` (see ``hdl/zbm_chip.py``).
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, enum, fifo, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model import zbm_formats as F

from .zbm_layouts import EP_CHANNEL, EP_HEADER, FLIT, SEG_HEADER

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


class _State(enum.Enum, shape=4):
    LOAD_CHECK = 0
    LOAD_WORD = 1
    LATE = 2
    APPEND = 3
    READ = 4
    COMPUTE = 5
    SEND_HDR = 6
    SEND_FLIT = 7
    STEP = 8
    EOL = 9
    FRAME_END = 10


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

    Timing (segment clock): loading an edge pair takes 9 cycles (one FIFO word per cycle, the
    paper's figure), plus 1 cycle per missed line for a pair loaded late, plus 1 to append it;
    an active pair costs READ + COMPUTE + STEP = 3 cycles, plus 1 + channels words for a
    non-empty segment (each held until the chips accept it); a line ends with one
    end-of-line word.
    """

    def __init__(self, *, width: int = F.MAX_WIDTH, height: int = F.MAX_HEIGHT,
                 capacity: int = F.AEP_CAPACITY, fifo_depth: int = 32):
        if not (isinstance(width, int) and 1 <= width <= F.MAX_WIDTH):
            raise ValueError(f"width must be 1..{F.MAX_WIDTH}, not {width!r}")
        if not (isinstance(height, int) and 1 <= height <= F.MAX_HEIGHT):
            raise ValueError(f"height must be 1..{F.MAX_HEIGHT}, not {height!r}")
        if not (isinstance(capacity, int) and 1 <= capacity <= 1024):
            raise ValueError(f"capacity must be 1..1024, not {capacity!r}")
        self._width, self._height, self._capacity = width, height, capacity
        self._fifo_depth = fifo_depth
        super().__init__({
            "i": In(stream.Signature(unsigned(EP_WORD_BITS))),
            "o": Out(stream.Signature(unsigned(F.LOOP_BITS))),
            "line": Out(9),
            "frames": Out(16),
        })

    @property
    def width(self) -> int:
        return self._width

    @property
    def height(self) -> int:
        return self._height

    @property
    def capacity(self) -> int:
        return self._capacity

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

        rec = Signal(AEP)
        y = self.line
        n_mem = Signal(range(cap + 1))       # active pairs in memory
        n_start = Signal(range(cap + 1))     # active pairs at the start of this line
        loaded = Signal(range(cap + 1))      # pairs taken from the FIFO this line
        word = Signal(range(F.EP_WORDS))
        late = Signal(10)
        r = Signal(range(cap + 1))           # read index of the emit pass
        w = Signal(range(cap + 1))           # write-back index (w <= r: in-place compaction)
        off = Signal(unsigned(24))           # Q.12 distance from the left edge to the first centre
        c = Signal(range(N_CH + 1))          # attribute channel being sent (2..)
        state = Signal(_State)
        n_attr = Mux(rec.mode == F.MODE_MAPPING, len(F.CHANNELS[F.MODE_MAPPING]),
                     len(F.CHANNELS[F.MODE_COLOUR]))

        # left-end pixel range: first centre >= edge, i.e. ceil(xq - 0.5) (golden _px_ceil)
        half_x, one_x = 1 << (F.X_FRAC - 1), 1 << F.X_FRAC

        def px_ceil(xq):
            return (xq - half_x + (one_x - 1)) >> F.X_FRAC

        xl = rec.ch[0].value
        xr = xl + rec.ch[1].value               # 57-bit: no wrap, as the golden int64 sum
        s_raw, e_raw = px_ceil(xl), px_ceil(xr)
        s_cl = Mux(s_raw < 0, 0, s_raw)
        e_cl = Mux(e_raw > self._width, self._width, e_raw)

        def step(dst, src):
            """The adders: every channel one scan line down (56-bit wrap)."""
            stmts = []
            for k in range(N_CH):
                stmts.append(dst.ch[k].value.eq(src.ch[k].value + src.ch[k].ddy))
            return stmts

        m.d.comb += [wp.en.eq(0), rp.en.eq(0)]
        m.d.comb += self.o.valid.eq(0)
        with m.Switch(state):
            # ---------------- (1) loader: pairs whose top line has been reached, while room
            with m.Case(_State.LOAD_CHECK):
                with m.If(fq.r_rdy):
                    with m.If(head.h == 0):                     # end of frame: no more pairs
                        m.d.sync += [state.eq(_State.READ), r.eq(0), w.eq(0)]
                    with m.Elif((head.y <= y) & (n_start + loaded < cap)):
                        m.d.sync += [rec.eq(0), rec.y.eq(head.y), rec.left.eq(head.h),
                                     rec.mode.eq(head.mode), word.eq(1), loaded.eq(loaded + 1)]
                        m.d.comb += fq.r_en.eq(1)
                        m.d.sync += state.eq(_State.LOAD_WORD)
                    with m.Else():
                        m.d.sync += [state.eq(_State.READ), r.eq(0), w.eq(0)]
            with m.Case(_State.LOAD_WORD):
                with m.If(fq.r_rdy):
                    m.d.comb += fq.r_en.eq(1)
                    with m.Switch(word):
                        for k in range(1, F.EP_WORDS):
                            with m.Case(k):
                                m.d.sync += [rec.ch[k - 1].value.eq(head_ch.value),
                                             rec.ch[k - 1].ddy.eq(head_ch.ddy),
                                             rec.ch[k - 1].ddx.eq(head_ch.ddx)]
                    m.d.sync += word.eq(word + 1)
                    with m.If(word == F.EP_WORDS - 1):
                        m.d.sync += [state.eq(_State.LATE), late.eq(y - rec.y)]
            with m.Case(_State.LATE):                        # R3: step down to this line
                with m.If(late == 0):
                    m.d.sync += state.eq(_State.APPEND)
                with m.Elif(rec.left <= 1):                  # ends before this line: dropped
                    m.d.sync += [state.eq(_State.LOAD_CHECK)]
                with m.Else():
                    m.d.sync += step(rec, rec)
                    m.d.sync += [rec.left.eq(rec.left - 1), late.eq(late - 1)]
            with m.Case(_State.APPEND):
                m.d.comb += [wp.en.eq(1), wp.addr.eq(n_mem), wp.data.eq(rec)]
                m.d.sync += [n_mem.eq(n_mem + 1), state.eq(_State.LOAD_CHECK)]
            # ---------------- (2) emit: read in memory order, send, step, store back if needed
            with m.Case(_State.READ):
                with m.If(r == n_mem):
                    m.d.sync += [state.eq(_State.EOL), n_mem.eq(w)]
                with m.Else():
                    m.d.comb += [rp.en.eq(1), rp.addr.eq(r)]
                    m.d.sync += [state.eq(_State.COMPUTE), r.eq(r + 1)]
            with m.Case(_State.COMPUTE):
                m.d.sync += rec.eq(rp.data)
                m.d.sync += state.eq(_State.SEND_HDR)
            with m.Case(_State.SEND_HDR):
                with m.If(e_cl > s_cl):
                    hdr = data.View(SEG_HEADER, self.o.payload)
                    m.d.comb += [self.o.valid.eq(1), hdr.y.eq(y), hdr.x.eq(s_cl),
                                 hdr.len.eq(e_cl - s_cl), hdr.mode.eq(rec.mode)]
                    with m.If(self.o.ready):
                        # Q.12 offset from the edge to the first centre (>= 0)
                        m.d.sync += [off.eq(((s_cl << F.X_FRAC) + half_x - xl) >> (F.X_FRAC - F.OFF_FRAC)),
                                     c.eq(2), state.eq(_State.SEND_FLIT)]
                with m.Else():
                    m.d.sync += state.eq(_State.STEP)
            with m.Case(_State.SEND_FLIT):
                ch = rec.ch[c]
                fl = data.View(FLIT, self.o.payload)
                m.d.comb += [self.o.valid.eq(1),
                             fl.value.eq(ch.value + ((off * ch.ddx) >> F.OFF_FRAC)),
                             fl.inc.eq(ch.ddx)]
                with m.If(self.o.ready):
                    m.d.sync += c.eq(c + 1)
                    with m.If(c == n_attr + 1):
                        m.d.sync += state.eq(_State.STEP)
            with m.Case(_State.STEP):
                stepped = Signal(AEP)
                m.d.comb += [stepped.eq(rec), stepped.left.eq(rec.left - 1)]
                m.d.comb += step(stepped, rec)
                with m.If(rec.left > 1):
                    m.d.comb += [wp.en.eq(1), wp.addr.eq(w), wp.data.eq(stepped)]
                    m.d.sync += w.eq(w + 1)
                m.d.sync += state.eq(_State.READ)
            with m.Case(_State.EOL):
                hdr = data.View(SEG_HEADER, self.o.payload)
                m.d.comb += [self.o.valid.eq(1), hdr.y.eq(y), hdr.len.eq(0)]
                with m.If(self.o.ready):
                    with m.If(y == self._height - 1):
                        m.d.sync += [state.eq(_State.FRAME_END), word.eq(0)]
                    with m.Else():
                        m.d.sync += [y.eq(y + 1), state.eq(_State.LOAD_CHECK),
                                     n_start.eq(n_mem), loaded.eq(0)]
            with m.Case(_State.FRAME_END):
                # Drop pairs never loaded (memory was full to the end: their segments are
                # lost, as in the golden model), then the end-of-frame marker; next frame.
                with m.If(fq.r_rdy):
                    m.d.comb += fq.r_en.eq(1)
                    with m.If((word == 0) & (head.h == 0)):
                        m.d.sync += [y.eq(0), n_mem.eq(0), n_start.eq(0), loaded.eq(0),
                                     self.frames.eq(self.frames + 1), state.eq(_State.LOAD_CHECK)]
                    with m.Else():
                        m.d.sync += word.eq(Mux(word == F.EP_WORDS - 1, 0, word + 1))
        return m
