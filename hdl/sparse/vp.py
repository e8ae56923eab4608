"""A video processor of the matrix: set-up, one pipeline stage per level with FIFOs, pixel processor."""

from __future__ import annotations

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import fifo, stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.sparse.formats import MATRIX_LOG2_MAX, TRI_BITS
from rasterhw.hdl.sparse.benchread import bench_read_ports, check_lanes, forward_bench_read
from rasterhw.hdl.sparse.layouts import layouts
from rasterhw.hdl.sparse.pixel import PixelProcessor
from rasterhw.hdl.sparse.stage import LevelStage

__all__ = ["VideoProcessor", "check_params", "make_vp", "rewrite_record"]


def _log2(name: str, v: int) -> int:
    if not isinstance(v, int) or v < 1 or v & (v - 1) or v > 1 << MATRIX_LOG2_MAX:
        raise ValueError(f"{name} must be a power of two in 1..{1 << MATRIX_LOG2_MAX}, not {v!r}")
    return v.bit_length() - 1


def check_params(*, n, p, q, alpha, beta, z_bits, colour, kp, ke) -> tuple[int, int]:
    """The parameter checks both raster processors share (``ValueError``); returns ``log2 p, log2 q``."""
    if not isinstance(n, int) or not 1 <= n <= 12:
        raise ValueError(f"n must be an integer in 1..12, not {n!r}")
    lp, lq = _log2("p", p), _log2("q", q)
    if not (isinstance(alpha, int) and isinstance(beta, int) and 0 <= alpha <= 15 and 0 <= beta <= 15):
        raise ValueError(f"aperture must be integers in 0..15, not {alpha}x{beta}")
    if not isinstance(z_bits, int) or not 1 <= z_bits <= 32:
        raise ValueError(f"z_bits must be an integer in 1..32, not {z_bits!r}")
    if not isinstance(colour, bool):
        raise ValueError(f"colour must be True or False, not {colour!r}")
    for name, v, lo in (("kp", kp, 0), ("ke", ke, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= 15:
            raise ValueError(f"{name} must be an integer in {lo}..{15}, not {v!r}")
    return lp, lq


def rewrite_record(m: Module, bc, hdr, root, *, a, b, lp: int, lq: int, alpha: int, beta: int,
                   colour: bool = False) -> None:
    """The set-up's arithmetic (both raster processors): broadcast record ``bc`` rewritten for
    processor ``(a, b)`` of the ``2**lp x 2**lq`` matrix into header ``hdr`` (``A' = pA``,
    ``B' = qB``, aperture growth ``(|A| alpha + |B| beta) / 2``, ``zu = p zx``, ``zv = q zy``;
    colour: ``cu = p cx``, ``cv = q cy``) and the root window's values ``root.E`` (``C + aA + bB``),
    ``root.z`` (``z00 + a zx + b zy``) and colour ``root.c`` (``c00 + a cx + b cy``). Comb."""
    for k in range(3):
        absA = Mux(bc.A[k] < 0, -bc.A[k], bc.A[k])
        absB = Mux(bc.B[k] < 0, -bc.B[k], bc.B[k])
        m.d.comb += [hdr.Ap[k].eq(bc.A[k] << lp), hdr.Bp[k].eq(bc.B[k] << lq), hdr.thr[k].eq(bc.thr[k]),
                     hdr.ext[k].eq((absA * alpha + absB * beta) >> 1),
                     root.E[k].eq(bc.C[k] + a * bc.A[k] + b * bc.B[k])]
    for k in range(4):
        m.d.comb += hdr.bbox[k].eq(bc.bbox[k])
    m.d.comb += [hdr.zu.eq(bc.zx << lp), hdr.zv.eq(bc.zy << lq), hdr.tri.eq(bc.tri),
                 root.z.eq(bc.z00 + a * bc.zx + b * bc.zy)]
    if colour:
        for ch in range(3):
            m.d.comb += [hdr.cu[ch].eq(bc.cx[ch] << lp), hdr.cv[ch].eq(bc.cy[ch] << lq),
                         root.c[ch].eq(bc.c00[ch] + a * bc.cx[ch] + b * bc.cy[ch])]


class VideoProcessor(wiring.Component):
    """A video processor of a ``p x q`` matrix with ``2**n x 2**n`` sparse rasters; its place
    ``(a, b)`` in the matrix is an input (every processor is the same hardware).

    The set-up rewrites each broadcast triangle for this processor's lattice — ``A' = pA``,
    ``B' = qB``, ``C' = C + aA + bB``, depth ``Z0 = z00 + a*zx + b*zy``, ``zu = p*zx``,
    ``zv = q*zy``, aperture growth ``(|A| alpha + |B| beta) / 2`` — and sends a header and the
    root window into the input FIFOs of level 1. Levels 1..n are :class:`LevelStage` s, each fed
    by a window FIFO and a header FIFO (``fifo_depth`` entries each); the last one feeds the
    :class:`PixelProcessor`.

    Members
    -------
    a, b : In(MATRIX_LOG2_MAX) — the processor's index in the matrix (held constant).
    i : In(stream BROADCAST) — triangles, in submission order.
    rd_addr, rd_z, rd_tri — the local memory's video-controller read port (one cycle latency).
    tests : Out(32) per level (``tests_1 .. tests_n``) — coverage tests (busy cycles) per stage.
    stalls : Out(32) per level.
    writes : Out(32) — pixels written.
    busy : Out(1) — a record is still somewhere in the processor.
    rd_rgb : Out(24) (``colour`` only) — R | G << 8 | B << 16 at ``rd_addr`` (one cycle latency).
    rdw_addr, rdw_data (``read_lanes`` > 0 only) — the pixel processor's bench read port
        (``hdl/sparse/benchread.py``; not the paper's).

    **Surface parameters** (``colour``): the record is ``BROADCAST_RGB``; R, G, B travel as three
    linear functions with the edges (set-up: ``C0 = c00 + a cx + b cy``, ``cu = p cx``,
    ``cv = q cy``), are stepped with every window like depth and written with the Z test into a
    colour memory (``fixed.colour_rgb8``'s rounding). **Their cost** (``kp`` > 0): formula (5)'s
    ``w_i k_p / k_e`` cycles at every level (:class:`LevelStage`); the defaults (``colour=False,
    kp=0``) build the processor as before, depth stepped free of charge.
    """

    def __init__(self, *, n: int, p: int = 4, q: int = 4, alpha: int = 2, beta: int = 2,
                 z_bits: int = 24, fifo_depth: int = 8, test: str = "exact", colour: bool = False,
                 kp: int = 0, ke: int = 3, read_lanes: int = 0):
        try:
            self._lp, self._lq = check_params(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, colour=colour,
                                              kp=kp, ke=ke)
            if test not in ("exact", "edges"):
                raise ValueError(f"test must be 'exact' or 'edges', not {test!r}")
            if not isinstance(fifo_depth, int) or fifo_depth < 2:
                raise ValueError(f"fifo_depth must be an integer >= 2, not {fifo_depth!r}")
            check_lanes(n, read_lanes)
        except ValueError:
            self._MustUse__silence = True  # a rejected parameter set is not an unused design
            raise
        self._n, self._p, self._q = n, p, q
        self._alpha, self._beta, self._z_bits, self._depth, self._test = alpha, beta, z_bits, fifo_depth, test
        self._colour, self._kp, self._ke, self._lanes = colour, kp, ke, read_lanes
        broadcast, _, _ = layouts(colour)
        ports = {"a": In(MATRIX_LOG2_MAX), "b": In(MATRIX_LOG2_MAX), "i": In(stream.Signature(broadcast)), "rd_addr": In(2 * n), "rd_z": Out(z_bits + 1),
                 "rd_tri": Out(TRI_BITS), "writes": Out(32), "busy": Out(1)}
        if colour:
            ports["rd_rgb"] = Out(24)
        for lvl in range(1, n + 1):
            ports[f"tests_{lvl}"] = Out(32)
            ports[f"stalls_{lvl}"] = Out(32)
        ports.update(bench_read_ports(n, z_bits, colour, read_lanes))
        super().__init__(ports)

    @property
    def n(self) -> int:
        return self._n

    def elaborate(self, platform):
        m = Module()
        n = self._n
        broadcast, header, window = layouts(self._colour)
        stages = []
        fifos = []
        for lvl in range(1, n + 1):
            st = LevelStage(level=lvl, n=n, p=self._p, q=self._q, alpha=self._alpha, beta=self._beta,
                            test=self._test, colour=self._colour, kp=self._kp, ke=self._ke)
            m.d.comb += [st.a.eq(self.a), st.b.eq(self.b)]
            m.submodules[f"level{lvl}"] = st
            stages.append(st)
        for k in range(n + 1):
            f = fifo.SyncFIFOBuffered(width=window.size, depth=self._depth)
            h = fifo.SyncFIFOBuffered(width=header.size, depth=self._depth)
            m.submodules[f"fifo{k}"] = f
            m.submodules[f"hfifo{k}"] = h
            fifos.append((f, h))
        m.submodules.pixel = px = PixelProcessor(n=n, z_bits=self._z_bits, colour=self._colour, read_lanes=self._lanes)
        forward_bench_read(m, self, px, self._lanes)

        def push(src, f):
            m.d.comb += [f.w_data.eq(src.payload), f.w_en.eq(src.valid), src.ready.eq(f.w_rdy)]

        def pop(f, dst):
            m.d.comb += [dst.payload.eq(f.r_data), dst.valid.eq(f.r_rdy), f.r_en.eq(dst.ready)]

        # set-up: the header into header FIFO 0, then the root window (new = 1) into FIFO 0
        setup_w = stream.Signature(window).create()
        setup_h = stream.Signature(header).create()
        bc = Signal(broadcast)
        hdr = Signal(header)
        root = Signal(window)
        rewrite_record(m, bc, hdr, root, a=self.a, b=self.b, lp=self._lp, lq=self._lq, alpha=self._alpha,
                       beta=self._beta, colour=self._colour)
        m.d.comb += root.new.eq(1)
        setup_idle = Signal()
        with m.FSM(name="setup"):
            with m.State("IDLE"):
                m.d.comb += [self.i.ready.eq(1), setup_idle.eq(1)]
                with m.If(self.i.valid):
                    m.d.sync += bc.eq(self.i.payload)
                    m.next = "HDR"
            with m.State("HDR"):
                m.d.comb += [setup_h.valid.eq(1), setup_h.payload.eq(hdr)]
                with m.If(setup_h.ready):
                    m.next = "ROOT"
            with m.State("ROOT"):
                m.d.comb += [setup_w.valid.eq(1), setup_w.payload.eq(root)]
                with m.If(setup_w.ready):
                    m.next = "IDLE"
        push(setup_w, fifos[0][0])
        push(setup_h, fifos[0][1])
        for k, st in enumerate(stages):
            pop(fifos[k][0], st.i)
            pop(fifos[k][1], st.i_hdr)
            push(st.o, fifos[k + 1][0])
            push(st.o_hdr, fifos[k + 1][1])
            m.d.comb += [getattr(self, f"tests_{k + 1}").eq(st.tests), getattr(self, f"stalls_{k + 1}").eq(st.stalls)]
        pop(fifos[n][0], px.i)
        pop(fifos[n][1], px.i_hdr)
        m.d.comb += [px.rd_addr.eq(self.rd_addr), self.rd_z.eq(px.rd_z), self.rd_tri.eq(px.rd_tri),
                     self.writes.eq(px.writes)]
        if self._colour:
            m.d.comb += self.rd_rgb.eq(px.rd_rgb)
        idle = setup_idle & px.idle
        for st in stages:
            idle = idle & st.idle
        for f, h in fifos:
            idle = idle & (f.level == 0) & (h.level == 0)
        m.d.comb += self.busy.eq(~idle)
        return m


def make_vp(*, n: int = 7, p: int = 4, q: int = 4, alpha: int = 2, beta: int = 2,
            z_bits: int = 24, fifo_depth: int = 8, colour: bool = False, kp: int = 0, ke: int = 3) -> VideoProcessor:
    """Factory for ``rasterhw verilog sparse-vp``: by default a processor of a 4x4 matrix on the
    512 x 512 raster (n = 7), depth only, parameter additions unpriced; ``colour=True, kp=4``
    carries R, G, B and prices depth + RGB as (5)."""
    return VideoProcessor(n=n, p=p, q=q, alpha=alpha, beta=beta, z_bits=z_bits, fifo_depth=fifo_depth,
                          colour=colour, kp=kp, ke=ke)
