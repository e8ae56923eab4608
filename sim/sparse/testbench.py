# amaranth: UnusedElaboratable=no
"""Testbenches of the sparse-raster blocks (``sim/testbench.py``): a video processor and the whole
matrix, fed with the broadcast records of a random frame; the local memory (the matrix's full
raster) streamed out after the input ends, against the golden search."""

from __future__ import annotations

import numpy as np
from amaranth import Cat, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.sim import registry
from rasterhw.sim.testbench import Expected, Stimulus, Testbench

__all__ = ["MatrixBench", "ReadOut", "StackVPBench", "VPBench"]


class ReadOut(wiring.Component):
    """Bench adapter for a memory-backed block: records in, memory words out.

    ``i`` carries ``{end, record}``: records go to the block's ``i``; a word with ``end`` set is
    taken at once and starts the read-out when the block is no longer ``busy``: the read address
    sweeps ``0 .. words - 1`` (``address(m, addr)`` drives the block's read port; one cycle of read
    latency) and ``o`` carries ``{rd_tri, rd_z}`` of each address, two cycles a word, each held
    until taken. ``fixed``: constant inputs of the block (``{name: value}``). ``tail``: the block's
    counters (output names) sent after the memory, one word each (zero-extended), in order."""

    def __init__(self, block, *, words: int, address, fixed: dict, z_bits: int, tail: tuple[str, ...] = (),
                 record_bits: int | None = None, rgb: bool = False):
        from rasterhw.hdl.sparse.layouts import BROADCAST

        self.block, self._words, self._address, self._fixed, self._tail = block, words, address, fixed, tuple(tail)
        self._rec = BROADCAST.size if record_bits is None else record_bits
        self._rgb = rgb
        super().__init__({"i": In(stream.Signature(self._rec + 1)),
                          "o": Out(stream.Signature(TRI_BITS + z_bits + 1 + (24 if rgb else 0)))})

    def elaborate(self, platform):
        m = Module()
        m.submodules.block = b = self.block
        for name, v in self._fixed.items():
            m.d.comb += getattr(b, name).eq(v)
        end = self.i.payload[self._rec]
        addr = Signal(range(self._words + 1))
        primed = Signal()
        self._address(m, b, addr)
        word = Cat(b.rd_z, b.rd_tri, b.rd_rgb) if self._rgb else Cat(b.rd_z, b.rd_tri)
        m.d.comb += [b.i.payload.eq(self.i.payload[:self._rec]), self.o.payload.eq(word)]
        with m.FSM():
            with m.State("FEED"):
                m.d.comb += [b.i.valid.eq(self.i.valid & ~end), self.i.ready.eq(end | b.i.ready)]
                with m.If(self.i.valid & end):
                    m.next = "WAIT"
            with m.State("WAIT"):
                with m.If(~b.busy):
                    m.next = "READ"
            with m.State("READ"):
                m.d.sync += primed.eq(1)
                m.d.comb += self.o.valid.eq(primed)
                with m.If(self.o.valid & self.o.ready):
                    m.d.sync += [addr.eq(addr + 1), primed.eq(0)]
                    with m.If(addr == self._words - 1):
                        m.next = "TAIL" if self._tail else "DONE"
            if self._tail:
                k = Signal(range(len(self._tail)))
                with m.State("TAIL"):
                    m.d.comb += self.o.valid.eq(1)
                    with m.Switch(k):
                        for j, name in enumerate(self._tail):
                            with m.Case(j):
                                m.d.comb += self.o.payload.eq(getattr(b, name))
                    with m.If(self.o.ready):
                        m.d.sync += k.eq(k + 1)
                        with m.If(k == len(self._tail) - 1):
                            m.next = "DONE"
            with m.State("DONE"):
                pass
        return m


def _words(tri: np.ndarray, zq: np.ndarray, z_bits: int) -> list[int]:
    t = np.where(tri >= 0, tri, (1 << TRI_BITS) - 1).astype(np.int64)
    z = np.where(tri >= 0, zq, 1 << z_bits).astype(np.int64)
    return ((t << (z_bits + 1)) | z).ravel().tolist()


class _SparseBench(Testbench):
    def raster(self, params: dict) -> tuple[int, int]:
        return params["p"] << params["n"], params["q"] << params["n"]

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        from rasterhw.hdl.pack import pack
        from rasterhw.hdl.sparse.layouts import BROADCAST

        rng = np.random.default_rng(seed)
        w, h = self.raster(params)
        tris = random_triangles(w, h, int(rng.integers(8, 25)), mean_area=float(rng.uniform(4, w * h / 8)),
                                seed=int(rng.integers(0, 1 << 30)))
        if tris.z_bits != params["z_bits"]:
            raise ValueError(f"{self.block}: the bench's frames carry {tris.z_bits}-bit depth, not {params['z_bits']}")
        recs = broadcast_records(tris)
        words = [pack(BROADCAST, r) for r in recs] + [1 << BROADCAST.size]
        return Stimulus({"i": words}, what=f"{len(recs)} random triangles on {w}x{h}, seed {seed}", source=tris)

    def _golden(self, params: dict, stim: Stimulus):
        tris = stim.source
        g = sparse_render(tris, (params["p"], params["q"]), depth="fixed")
        zq = np.where(g.tri_id >= 0, np.rint(g.depth * (1 << tris.z_bits)), -1).astype(np.int64)
        return g, zq


class VPBench(_SparseBench):
    """``sparse-vp``: processor ``(p - 1, q - 1)`` of the matrix (the last, every offset non-zero):
    broadcast records and an end word in (``i``), its local memory out (``o``, ``{tri, z}`` per
    sparse address ``v * 2**n + u``, empty ``{all ones, 2**z_bits}``), against the golden search's
    pixels of that processor (``(u p + a, v q + b)`` of the full raster). With ``colour`` the
    records carry the colour planes and each memory word its colour (``rgb << (TRI_BITS + z_bits + 1)``,
    against ``fixed.colour_rgb8``)."""

    block = "sparse-vp"

    def tail(self, params: dict) -> tuple[str, ...]:
        """Counters sent after the memory (none for the pipeline processor)."""
        return ()

    def dut(self, params: dict):
        from rasterhw.hdl.sparse.layouts import layouts

        vp = registry.load(registry.blocks()[self.block])(**params)
        n = params["n"]

        def address(m, b, addr):
            m.d.comb += b.rd_addr.eq(addr[:2 * n])

        col = params.get("colour", False)
        return ReadOut(vp, words=1 << (2 * n), address=address, fixed={"a": params["p"] - 1, "b": params["q"] - 1},
                       z_bits=params["z_bits"], tail=self.tail(params), record_bits=layouts(col)[0].size, rgb=col)

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        st = super().stimulus(params, seed)
        return self.records(st.source, params, what=st.what) if params.get("colour") else st

    @staticmethod
    def records(tris, params: dict, what: str = "") -> Stimulus:
        """The broadcast records of ``tris`` for this block (with the colour planes when ``colour``)
        and the end word."""
        from rasterhw.golden_model.sparse.stack import broadcast_records_rgb
        from rasterhw.hdl.pack import pack
        from rasterhw.hdl.sparse.layouts import layouts

        lay = layouts(bool(params.get("colour")))[0]
        recs = broadcast_records_rgb(tris) if params.get("colour") else broadcast_records(tris)
        return Stimulus({"i": [pack(lay, r) for r in recs] + [1 << lay.size]}, what=what, source=tris)

    @staticmethod
    def with_rgb(words: list[int], rgb: np.ndarray, z_bits: int) -> list[int]:
        """Memory words with each pixel's colour above them (``rgb``: ``(.., 3)``)."""
        sh = TRI_BITS + z_bits + 1
        return [w | (int(c[0]) | int(c[1]) << 8 | int(c[2]) << 16) << sh
                for w, c in zip(words, rgb.reshape(-1, 3), strict=True)]

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        from rasterhw.golden_model.sparse.fixed import colour_rgb8

        g, zq = self._golden(params, stim)
        p, q = params["p"], params["q"]
        a, b = p - 1, q - 1
        words = _words(g.tri_id[b::q, a::p], zq[b::q, a::p], params["z_bits"])
        if params.get("colour"):
            words = self.with_rgb(words, colour_rgb8(stim.source, g.tri_id, p, q)[b::q, a::p], params["z_bits"])
        return Expected({"o": words})


class MatrixBench(_SparseBench):
    """``sparse-matrix``: broadcast records and an end word in (``i``), the full raster out through
    the matrix's interleaved read port (``o``, ``{tri, z}`` per pixel, row-major), against the golden
    search; the input FIFOs at their built depth."""

    block = "sparse-matrix"

    def dut(self, params: dict):
        mx = registry.load(registry.blocks()[self.block])(**params)
        w, h = self.raster(params)
        xb = (w - 1).bit_length()

        def address(m, b, addr):
            m.d.comb += [b.rd_x.eq(addr[:xb]), b.rd_y.eq(addr[xb:])]

        return ReadOut(mx, words=w * h, address=address, fixed={"limit": params["in_depth"]}, z_bits=params["z_bits"])

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        g, zq = self._golden(params, stim)
        return Expected({"o": _words(g.tri_id, zq, params["z_bits"])})


class StackVPBench(VPBench):
    """``sparse-stack-vp``: the stack-based processor (``hdl/sparse/stack_vp.py``) in the place of
    ``sparse-vp``: the same records in and the same local memory out, then its counters (busy
    cycles, records, the stack's depth, pixel writes, tests per level), against the golden stack
    processor (``golden_model/sparse/stack.py``): bit and cycle exact (busy cycles = the stack
    cycle model's ``3 + tests`` per record, plus (5)'s parameter cycles with ``kp``, whatever the
    input's gaps). With ``colour`` the records carry the colour planes and each memory word its
    colour (``rgb << (TRI_BITS + z_bits + 1)``)."""

    block = "sparse-stack-vp"

    @staticmethod
    def counters(n: int) -> tuple[str, ...]:
        return ("busy_cycles", "records", "max_stack", "writes") + tuple(f"tests_{i}" for i in range(1, n + 1))

    def tail(self, params: dict) -> tuple[str, ...]:
        return self.counters(params["n"])

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        from rasterhw.golden_model.sparse.stack import stack_processor

        p, q = params["p"], params["q"]
        col = params.get("colour", False)
        g = stack_processor(stim.source, (p, q), p - 1, q - 1, colour=col, kp=params.get("kp", 0),
                            ke=params.get("ke", 3))
        tail = [g["busy"], len(g["cycles"]), g["max_stack"], g["writes"]] + [int(v) for v in g["tests"]]
        words = _words(g["tri"], g["zq"], params["z_bits"])
        if col:
            words = self.with_rgb(words, g["rgb"], params["z_bits"])
        return Expected({"o": words + tail})
