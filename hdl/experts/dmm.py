"""EXPERTS DMM/P: the double message memory between an SLP and one PXP.

Paper (seed 000, 3.2): "DMM(Double Message Memory)と呼ぶ2重系の共有メモリを用いた ... DMM/PはSLPと
各PXP間のASL等の授受において、上位プロセッサによる書込みと下位プロセッサによる読み出しと並行して同時に
行なう。DMMは、物理的には下位のプロセッサ1台に1組ずつ装備" -- two banks, one per PXP: the SLP
writes line k+1's ASL into one bank while the PXP reads line k from the other.

Swap handshake: the writer fills its bank with one line (segments, then a ``last`` token) and
then moves to the other bank, which it may write only once the reader has released it; the reader
plays a full bank out (segments, then the ``last`` token) and releases it. Overflow: a line with
more than ``depth`` segments sets the sticky ``overflow`` flag and the writer stops accepting
(``i.ready`` low until reset) -- never a silent drop. ``depth`` default 256: the worst line of
``experts-2000`` holds 151 segments (line 47; ``rasterhw report experts``).
"""

from __future__ import annotations

from amaranth import Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rasterhw.hdl.experts.pxp import seg_layout

__all__ = ["ExpertsDmm"]

BANKS = 2   # the double buffer: one bank filled while the other is read (a bit each in ``full``)


class ExpertsDmm(wiring.Component):
    """Double-banked ASL buffer, SLP side ``i`` -> PXP side ``o``.

    Parameters
    ----------
    depth : int
        Segments per bank (2..4096).

    Members
    -------
    i : In(stream.Signature(seg_layout()))
        From the SLP: one line's segments, then a ``last`` token.
    o : Out(stream.Signature(seg_layout()))
        To the PXP: the same, a line at a time, in order.
    overflow : Out(1)
        Sticky: a line had more than ``depth`` segments; ``i`` is stalled for good.
    full : Out(2)
        Which banks hold a complete line (for the testbench and the SLP's counters).

    Throughput: two cycles per segment out (read, then offer); a bank swap costs nothing extra.
    """

    def __init__(self, *, depth: int = 256):
        if isinstance(depth, bool) or not isinstance(depth, int) or not 2 <= depth <= 4096:
            raise ValueError(f"depth must be an integer in 2..4096, not {depth!r}")
        self._depth = depth
        super().__init__({
            "i": In(stream.Signature(seg_layout())),
            "o": Out(stream.Signature(seg_layout())),
            "overflow": Out(1),
            "full": Out(BANKS),
        })

    @property
    def depth(self) -> int:
        return self._depth

    def elaborate(self, platform):
        m = Module()
        d = self._depth
        aw = (2 * d - 1).bit_length()
        pw = d.bit_length()
        m.submodules.mem = mem = Memory(shape=seg_layout(), depth=2 * d, init=[])
        wr = mem.write_port()
        rd = mem.read_port(transparent_for=())

        wbank = Signal()
        wptr = Signal(pw)
        rbank = Signal()
        rptr = Signal(pw)
        cnt = [Signal(pw, name=f"cnt{b}") for b in range(2)]
        full = Signal(BANKS)
        m.d.comb += self.full.eq(full)
        wfull = Signal()
        m.d.comb += wfull.eq(full.bit_select(wbank, 1))
        set_full, clr_full = self._writer(m, wr, d=d, aw=aw, wbank=wbank, wptr=wptr, cnt=cnt, wfull=wfull)
        self._reader(m, rd, aw=aw, pw=pw, rbank=rbank, rptr=rptr, cnt=cnt, full=full, clr_full=clr_full)
        m.d.sync += full.eq((full | set_full) & ~clr_full)
        return m

    def _writer(self, m, wr, *, d, aw, wbank, wptr, cnt, wfull):
        """The writer (SLP side, "上位プロセッサによる書込み"): one word of ``i`` a cycle into bank
        ``wbank`` at ``wptr``; the ``last`` token records the line's count in ``cnt`` and sets the
        bank full (``set_full``, returned with the reader's ``clr_full``); a segment that does not
        fit is not taken (``overflow``)."""
        at_end = Signal()
        m.d.comb += at_end.eq(wptr == d)
        # a segment that does not fit is not taken: it stays on ``i`` and ``overflow`` rises
        m.d.comb += [wr.en.eq(0), wr.addr.eq((wbank << (aw - 1)) | wptr), wr.data.eq(self.i.payload),
                     self.i.ready.eq(~wfull & ~self.overflow & (~at_end | self.i.payload.last))]
        with m.If(self.i.valid & ~wfull & at_end & ~self.i.payload.last):
            m.d.sync += self.overflow.eq(1)
        set_full = Signal(BANKS)
        clr_full = Signal(BANKS)
        with m.If(self.i.valid & self.i.ready):
            with m.If(self.i.payload.last):
                m.d.sync += [wptr.eq(0), wbank.eq(~wbank)]
                with m.If(wbank):
                    m.d.comb += set_full.eq(0b10)
                    m.d.sync += cnt[1].eq(wptr)
                with m.Else():
                    m.d.comb += set_full.eq(0b01)
                    m.d.sync += cnt[0].eq(wptr)
            with m.Else():
                m.d.comb += wr.en.eq(1)
                m.d.sync += wptr.eq(wptr + 1)
        return set_full, clr_full

    def _reader(self, m, rd, *, aw, pw, rbank, rptr, cnt, full, clr_full):
        """The reader (PXP side, "下位プロセッサによる読み出し"): a full bank ``rbank`` played out on
        ``o``, two cycles a word (the read, then the offer), then the ``last`` token; the bank is
        released (``clr_full``) when the token is taken."""
        rcnt = Signal(pw)
        with m.If(rbank):
            m.d.comb += rcnt.eq(cnt[1])
        with m.Else():
            m.d.comb += rcnt.eq(cnt[0])
        rfull = Signal()
        m.d.comb += rfull.eq(full.bit_select(rbank, 1))
        offering = Signal()
        token = Signal()
        m.d.comb += [rd.addr.eq((rbank << (aw - 1)) | rptr), rd.en.eq(0)]
        tok = Signal(seg_layout())
        m.d.comb += tok.last.eq(1)
        m.d.comb += [self.o.valid.eq(offering), self.o.payload.eq(rd.data)]
        with m.If(token):
            m.d.comb += self.o.payload.eq(tok)
        with m.If(~offering):
            with m.If(rfull):
                m.d.comb += rd.en.eq(rptr < rcnt)
                m.d.sync += [offering.eq(1), token.eq(rptr >= rcnt)]
        with m.Elif(self.o.ready):
            m.d.sync += offering.eq(0)
            with m.If(token):
                m.d.sync += [rptr.eq(0), rbank.eq(~rbank), token.eq(0)]
                with m.If(rbank):
                    m.d.comb += clr_full.eq(0b10)
                with m.Else():
                    m.d.comb += clr_full.eq(0b01)
            with m.Else():
                m.d.sync += rptr.eq(rptr + 1)
