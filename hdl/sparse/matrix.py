"""The p x q matrix of video processors: the broadcast into every processor's input FIFO, held
back by the fullest, the interleaved read-out, and the bench's parallel read-out."""

from __future__ import annotations

from amaranth.hdl import Cat, ClockSignal, Instance, Module, ResetSignal, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.hdl.sparse.benchread import check_lanes, lane_bits
from rasterhw.hdl.sparse.cell import MatrixCell, cell_stats
from rasterhw.hdl.sparse.layouts import layouts

__all__ = ["CELL_MODULE", "Matrix", "make_matrix"]

#: the Verilog module name of :class:`MatrixCell` when the matrix instantiates it by name
CELL_MODULE = "sparse_cell"


class Matrix(wiring.Component):
    """``p x q`` :class:`~rasterhw.hdl.sparse.cell.MatrixCell` s (input FIFO + video processor)
    behind one broadcast.

    Seed 002: the geometry processor "выдает описания геометрических примитивов всем
    видеопроцессорам матрицы в режиме Broadcast. Описания определяют очереди на входах растровых
    процессоров". A record on ``i`` is pushed into every processor's input FIFO in the cycle in
    which every FIFO has room (``i.ready``, from the registered levels and the run-time ``limit``);
    the fullest FIFO -- the slowest processor -- holds the broadcast back. The geometry processor's
    rate is the source's (ours: the paper gives none; the drivers offer a record every cycle).

    The video controller reads pixel ``(x, y)`` of the full ``p*2**n x q*2**n`` raster from
    processor ``(x mod p, y mod q)`` at sparse address ``(y div q) * 2**n + x div p`` ("как единая
    память с расслоением по двум координатным осям").

    ``cells="inline"`` elaborates every cell (pysim); ``cells="instance"`` instantiates the Verilog
    module :data:`CELL_MODULE` by name, ``p*q`` times, so the generated Verilog holds one processor
    module however large the matrix (the cell's Verilog is generated once, separately:
    ``MatrixCell`` of the same parameters converted with that name). ``vp="stack"``: every cell's
    processor is the stack-based one (``hdl/sparse/stack_vp.py``) instead of the pipeline.
    ``colour``, ``kp``, ``ke``: every processor's surface parameters and their cost (formula (5));
    with ``colour`` the broadcast carries ``BROADCAST_RGB`` and ``rd_rgb`` reads the interleaved
    colour memories (R | G << 8 | B << 16, 0 where empty) beside ``rd_z`` / ``rd_tri``.

    Members
    -------
    i : In(stream BROADCAST).
    limit : In — run-time input FIFO depth (1..in_depth).
    rd_x, rd_y : In — full-raster pixel to read; rd_z, rd_tri : Out — its depth and triangle one
        cycle later (empty: ``z = 2**z_bits``, ``tri = 2**TRI_BITS - 1``).
    rd_addr : In(2n - log2 read_lanes); rd_words : Out — only with ``wide_read=True``: the bench's
        parallel read-out (not the paper's video controller, which reads one pixel a clock through
        ``rd_x``, ``rd_y``; the block as the hardware flow takes it has no such port): every
        processor reads sparse addresses ``rd_addr * read_lanes + j``, ``j = 0 .. read_lanes - 1``,
        on its bench read port (``hdl/sparse/benchread.py``: ``read_lanes`` more read ports on each
        local memory) and ``rd_words`` carries all ``p*q*read_lanes`` words one cycle later, word
        ``j`` of processor ``k = b * p + a`` in lane ``k * read_lanes + j`` (``{rd_rgb, rd_tri,
        rd_z}``, ``lane_bits`` wide, lane 0 the lowest): the raster in ``2**(2n) / read_lanes``
        clocks.
    busy : Out(1) — a record in some FIFO or processor.
    cycles : Out(32) — cycles on which ``i.valid`` or ``busy`` was high (the frame, for a source
        that offers from its first cycle with no gaps).
    stall_cycles : Out(32) — cycles on which ``i.valid`` was high and some FIFO full.
    stat_cell, stat_sel : In; stat : Out(32) — counter ``stat_sel`` (``cell_stats(n)``) of cell
        ``stat_cell`` (``b * p + a``).
    """

    def __init__(self, *, n: int, p: int = 2, q: int = 2, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                 fifo_depth: int = 8, in_depth: int = 64, cells: str = "inline", vp: str = "pipeline",
                 colour: bool = False, kp: int = 0, ke: int = 3, wide_read: bool = False, read_lanes: int = 1):
        if cells not in ("inline", "instance"):
            raise ValueError(f"cells must be 'inline' or 'instance', not {cells!r}")
        if not isinstance(wide_read, bool):
            raise ValueError(f"wide_read must be True or False, not {wide_read!r}")
        if wide_read and read_lanes == 0:
            raise ValueError("read_lanes must be at least 1 with wide_read")
        # the cells' bench read port only with wide_read: the block as the hardware flow takes it has none
        self._lanes = read_lanes if wide_read else 0
        self._kw = dict(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, fifo_depth=fifo_depth,
                        in_depth=in_depth, vp=vp, colour=colour, kp=kp, ke=ke, read_lanes=self._lanes)
        # the processor's checks run here (a bad parameter set fails before any instance is made)
        self._cells = [MatrixCell(**self._kw)] if cells == "instance" else [MatrixCell(**self._kw) for _ in range(p * q)]
        if cells == "instance":
            # only its parameters were checked: not an unused design
            self._cells[0]._MustUse__silence = self._cells[0]._vp._MustUse__silence = True
        self._mode = cells
        self._n, self._p, self._q, self._z_bits, self._in_depth = n, p, q, z_bits, in_depth
        self._colour = colour
        lp, lq = p.bit_length() - 1, q.bit_length() - 1
        ports = {"i": In(stream.Signature(layouts(colour)[0])), "limit": In(range(in_depth + 1)),
                 "rd_x": In(n + lp), "rd_y": In(n + lq), "rd_z": Out(z_bits + 1), "rd_tri": Out(TRI_BITS),
                 "busy": Out(1), "cycles": Out(32), "stall_cycles": Out(32),
                 "stat_cell": In(range(max(p * q, 2))), "stat_sel": In(range(len(cell_stats(n)))), "stat": Out(32)}
        if colour:
            ports["rd_rgb"] = Out(24)
        self.lane_bits = lane_bits(z_bits, colour)
        if wide_read:
            ports.update({"rd_addr": In(2 * n - check_lanes(n, read_lanes)),
                          "rd_words": Out(p * q * read_lanes * self.lane_bits)})
        super().__init__(ports)

    def elaborate(self, platform):
        m = Module()
        n, p, q, zb = self._n, self._p, self._q, self._z_bits
        lp, lq = p.bit_length() - 1, q.bit_length() - 1
        P = p * q
        push = Signal()
        addr = Signal(2 * n)
        m.d.comb += addr.eq((self.rd_y[lq:] << n) | self.rd_x[lp:])
        ports = []
        for k in range(P):
            c = {"room": Signal(name=f"room{k}"), "busy": Signal(name=f"busy{k}"),
                 "rd_z": Signal(zb + 1, name=f"rd_z{k}"), "rd_tri": Signal(TRI_BITS, name=f"rd_tri{k}"),
                 "stat": Signal(32, name=f"stat{k}")}
            if self._colour:
                c["rd_rgb"] = Signal(24, name=f"rd_rgb{k}")
            ins = {"a": k % p, "b": k // p, "limit": self.limit, "push": push, "rec": self.i.payload.as_value(),
                   "rd_addr": addr, "stat_sel": self.stat_sel}
            if self._lanes:
                c["rdw_data"] = Signal(self._lanes * self.lane_bits, name=f"rdw_data{k}")
                ins["rdw_addr"] = self.rd_addr
            if self._mode == "inline":
                cell = self._cells[k]
                m.submodules[f"cell{k}"] = cell
                m.d.comb += [getattr(cell, name).eq(v) for name, v in ins.items()]
                m.d.comb += [v.eq(getattr(cell, name)) for name, v in c.items()]
            else:
                m.submodules[f"cell{k}"] = Instance(
                    CELL_MODULE, i_clk=ClockSignal(), i_rst=ResetSignal(allow_reset_less=True),
                    **{f"i_{name}": v for name, v in ins.items()}, **{f"o_{name}": v for name, v in c.items()})
            ports.append(c)
        room = ports[0]["room"]
        busy = ports[0]["busy"]
        for c in ports[1:]:
            room = room & c["room"]
            busy = busy | c["busy"]
        m.d.comb += [self.i.ready.eq(room), push.eq(self.i.valid & room), self.busy.eq(busy)]
        with m.If(self.i.valid | busy):
            m.d.sync += self.cycles.eq(self.cycles + 1)
        with m.If(self.i.valid & ~room):
            m.d.sync += self.stall_cycles.eq(self.stall_cycles + 1)
        # read-out: processor (x mod p, y mod q), registered to meet the read port's latency
        sel = Signal(range(P))
        m.d.sync += sel.eq((self.rd_y[:lq] << lp | self.rd_x[:lp]) if P > 1 else 0)
        with m.Switch(sel):
            for k, c in enumerate(ports):
                with m.Case(k):
                    m.d.comb += [self.rd_z.eq(c["rd_z"]), self.rd_tri.eq(c["rd_tri"])]
                    if self._colour:
                        m.d.comb += self.rd_rgb.eq(c["rd_rgb"])
        if self._lanes:   # the bench's parallel read-out: every processor's words of the group, side by side
            m.d.comb += self.rd_words.eq(Cat(*(c["rdw_data"] for c in ports)))
        with m.Switch(self.stat_cell):
            for k, c in enumerate(ports):
                with m.Case(k):
                    m.d.comb += self.stat.eq(c["stat"])
        return m


def make_matrix(*, n: int = 4, p: int = 2, q: int = 2, alpha: int = 2, beta: int = 2, z_bits: int = 24,
                fifo_depth: int = 8, in_depth: int = 64, vp: str = "pipeline", colour: bool = False, kp: int = 0,
                ke: int = 3) -> Matrix:
    """Factory for ``rasterhw verilog sparse-matrix`` (default: 2x2 processors on a 32x32 raster,
    every cell elaborated, depth only, parameter additions unpriced)."""
    return Matrix(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth,
                  vp=vp, colour=colour, kp=kp, ke=ke)
