"""One place of the matrix: a video processor behind its input FIFO (the processor class every
instance of the matrix shares)."""

from __future__ import annotations

from amaranth.hdl import Const, Module, Signal
from amaranth.lib import fifo, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import MATRIX_LOG2_MAX, TRI_BITS
from rasterhw.hdl.sparse.benchread import bench_read_ports, forward_bench_read
from rasterhw.hdl.sparse.layouts import layouts
from rasterhw.hdl.sparse.stack_vp import StackProcessor
from rasterhw.hdl.sparse.vp import VideoProcessor

__all__ = ["MatrixCell", "cell_stats"]


def cell_stats(n: int) -> list[str]:
    """Names of the counters a cell shows on ``stat`` for ``stat_sel`` = 0, 1, ..."""
    return ([f"tests_{i}" for i in range(1, n + 1)] + [f"stalls_{i}" for i in range(1, n + 1)]
            + ["writes", "busy_cycles", "fifo_peak", "records"])


class MatrixCell(wiring.Component):
    """The input FIFO of a video processor and the processor (``hdl/sparse/vp.py``).

    Seed 002, fig. 1: "Память типа FIFO на входе хранит очередь описаний геометрических
    примитивов". The FIFO is built ``in_depth`` entries deep; at run time it holds at most
    ``limit`` (1..``in_depth``): ``room`` is ``level < limit``, from the registered level, so a
    pop in the cycle of a push does not make room for it. The broadcast (``hdl/sparse/matrix.py``)
    pushes ``rec`` into every cell's FIFO in the same cycle, only when every cell has room. The
    FIFO is first-word-fall-through: a record pushed at the end of cycle ``c`` is offered to the
    processor on cycle ``c + 1`` and popped at the end of the first cycle the processor's set-up
    takes it (``golden_model/sparse/vpcycles.py``, ``coupled_matrix_vp``, has the same rules).

    Members
    -------
    a, b : In(MATRIX_LOG2_MAX) — the processor's place (held constant).
    limit : In — run-time FIFO depth (1..in_depth).
    push : In(1), rec : In(BROADCAST) — the broadcast write.
    room : Out(1) — ``level < limit``.
    busy : Out(1) — a record in the FIFO or in the processor.
    rd_addr, rd_z, rd_tri — the local memory's read port (one cycle latency).
    stat_sel : In, stat : Out(32) — counter ``stat_sel`` of :func:`cell_stats`: the processor's
        per-level tests and stalls, its pixel writes, the cycles its ``busy`` was high, the largest
        FIFO level, the records it took.

    ``vp="stack"``: the processor is the stack-based one (``hdl/sparse/stack_vp.py``); its stalls
    read 0 (it never waits for an output) and ``busy_cycles`` is its own count of the cycles it
    holds a record (the take cycle, set-up and tests: ``cycles.service_times(vp="stack")``).

    ``colour``, ``kp``, ``ke``: the processor's surface parameters (R, G, B broadcast with the
    edges: ``rec`` is ``BROADCAST_RGB`` and ``rd_rgb`` reads the colour memory) and formula (5)'s
    cost of their additions, either processor (``hdl/sparse/vp.py``, ``hdl/sparse/stack_vp.py``).
    ``read_lanes`` > 0: the processor's bench read port ``rdw_addr``, ``rdw_data``
    (``hdl/sparse/benchread.py``; not the paper's, the matrix's ``wide_read``).
    """

    def __init__(self, *, n: int, p: int, q: int, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                 fifo_depth: int = 8, in_depth: int = 64, vp: str = "pipeline", colour: bool = False, kp: int = 0,
                 ke: int = 3, read_lanes: int = 0):
        if not isinstance(in_depth, int) or not 1 <= in_depth <= 1024:
            raise ValueError(f"in_depth must be an integer in 1..1024, not {in_depth!r}")
        par = dict(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, colour=colour, kp=kp, ke=ke,
                   read_lanes=read_lanes)
        if vp == "pipeline":
            self._vp = VideoProcessor(**par, fifo_depth=fifo_depth)
        elif vp == "stack":
            self._vp = StackProcessor(**par)
        else:
            raise ValueError(f"vp must be 'pipeline' or 'stack', not {vp!r}")
        self._stack = vp == "stack"
        self._n, self._in_depth, self._colour, self._lanes = n, in_depth, colour, read_lanes
        self._rec = layouts(colour)[0]
        ports = {"a": In(MATRIX_LOG2_MAX), "b": In(MATRIX_LOG2_MAX), "limit": In(range(in_depth + 1)),
                 "push": In(1), "rec": In(self._rec), "room": Out(1), "busy": Out(1),
                 "rd_addr": In(2 * n), "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS),
                 "stat_sel": In(range(len(cell_stats(n)))), "stat": Out(32)}
        if colour:
            ports["rd_rgb"] = Out(24)
        ports.update(bench_read_ports(n, z_bits, colour, read_lanes))
        super().__init__(ports)

    def elaborate(self, platform):
        m = Module()
        n = self._n
        m.submodules.vp = vp = self._vp
        m.submodules.fifo = f = fifo.SyncFIFO(width=self._rec.size, depth=self._in_depth)
        m.d.comb += [vp.a.eq(self.a), vp.b.eq(self.b), f.w_data.eq(self.rec), f.w_en.eq(self.push),
                     self.room.eq(f.level < self.limit), vp.i.payload.eq(f.r_data), vp.i.valid.eq(f.r_rdy),
                     f.r_en.eq(vp.i.ready), vp.rd_addr.eq(self.rd_addr), self.rd_z.eq(vp.rd_z),
                     self.rd_tri.eq(vp.rd_tri), self.busy.eq(vp.busy | (f.level != 0))]
        if self._colour:
            m.d.comb += self.rd_rgb.eq(vp.rd_rgb)
        forward_bench_read(m, self, vp, self._lanes)
        busy_cycles = Signal(32)
        peak = Signal(range(self._in_depth + 1))
        records = Signal(32)
        with m.If(vp.busy):
            m.d.sync += busy_cycles.eq(busy_cycles + 1)
        with m.If(f.level > peak):
            m.d.sync += peak.eq(f.level)
        with m.If(vp.i.valid & vp.i.ready):
            m.d.sync += records.eq(records + 1)
        if self._stack:
            stalls, busy_cycles = [Const(0, 32)] * n, vp.busy_cycles
        else:
            stalls = [getattr(vp, f"stalls_{i}") for i in range(1, n + 1)]
        vals = [getattr(vp, f"tests_{i}") for i in range(1, n + 1)] + stalls + [vp.writes, busy_cycles, peak, records]
        with m.Switch(self.stat_sel):
            for k, v in enumerate(vals):
                with m.Case(k):
                    m.d.comb += self.stat.eq(v)
        return m
