# amaranth: UnusedElaboratable=no
"""Testbenches of the sparse-raster blocks (``sim/testbench.py``): a video processor and the whole
matrix, fed with the broadcast records of a random frame; the local memory (the matrix's full
raster) streamed out after the input ends, against the golden search."""

from __future__ import annotations

import numpy as np
from amaranth import Cat
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.sim import registry
from rasterhw.sim.engines.readout import ReadOut
from rasterhw.sim.testbench import Expected, Stimulus, Testbench

__all__ = ["READ_LANES", "MatrixFrameBench", "MatrixBench", "ProcessorBench", "StackVPBench", "VPBench"]


def _word(rgb: bool):
    """The read-out word of a sparse memory: ``{rd_z, rd_tri}`` (and ``rd_rgb`` with colour)."""
    return (lambda b: Cat(b.rd_z, b.rd_tri, b.rd_rgb)) if rgb else (lambda b: Cat(b.rd_z, b.rd_tri))


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
        zq = g.depth_words(tris.z_bits)
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
        return ReadOut(vp, words=1 << (2 * n), address=address, data=_word(col),
                       fixed={"a": params["p"] - 1, "b": params["q"] - 1}, tail=self.tail(params),
                       record_bits=layouts(col)[0].size)

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

        return ReadOut(mx, words=w * h, address=address, data=_word(False), fixed={"limit": params["in_depth"]})

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        g, zq = self._golden(params, stim)
        return Expected({"o": _words(g.tri_id, zq, params["z_bits"])})


class ProcessorBench(VPBench):
    """One pipeline video processor of the matrix on one frame, as ``rasterhw sim sparse
    --no-coupled`` runs every processor (not registered: the ``sparse-vp`` block on the generic
    engines, :func:`rasterhw.sim.sparse.scene.run_processor`).

    In (``i``): a config word setting the processor's place ``(a, b)`` (run-time inputs: one build
    serves every processor), the broadcast records, the end word. Out (``o``): its local memory
    (``{tri, z}`` per sparse address), then its per-level tests and stalls, its pixel writes and its
    cycles (from the first record offered until idle, the clock that sees it idle included),
    against the golden search and the processor's cycle model (``vpcycles.vp_standalone``; the
    cycles hold for records offered back to back)."""

    def __init__(self):
        #: the Verilator engine's C++ level: a frame is one run of up to millions of clocks
        self.verilator_opt = "-O2"

    def tail(self, params: dict) -> tuple[str, ...]:
        n = params["n"]
        return tuple(f"tests_{i}" for i in range(1, n + 1)) + tuple(f"stalls_{i}" for i in range(1, n + 1)) + ("writes",)

    def dut(self, params: dict):

        vp = registry.load(registry.blocks()[self.block])(**params)
        n = params["n"]

        def address(m, b, addr):
            m.d.comb += b.rd_addr.eq(addr[:2 * n])

        return ReadOut(vp, words=1 << (2 * n), address=address, data=_word(False),
                       config={"a": params["p"] - 1, "b": params["q"] - 1},
                       tail=self.tail(params), count=True, record_bits=self._lay(params).size)

    @staticmethod
    def _lay(params: dict):
        from rasterhw.hdl.sparse.layouts import layouts

        return layouts(bool(params.get("colour")))[0]

    def frame(self, tris, params: dict, a: int, b: int, what: str = "") -> Stimulus:
        """The words of processor ``(a, b)``'s run: its place, the records of ``tris``, the end word."""
        from rasterhw.golden_model.sparse.formats import MATRIX_LOG2_MAX
        from rasterhw.hdl.pack import pack

        if params.get("colour"):
            raise ValueError("the processor bench runs the depth-only processor")
        lay = self._lay(params)
        cfg = ReadOut.config_word(lay.size, {"a": MATRIX_LOG2_MAX, "b": MATRIX_LOG2_MAX}, {"a": a, "b": b})
        words = [cfg] + [pack(lay, r) for r in broadcast_records(tris)] + [1 << lay.size]
        return Stimulus({"i": words}, what=what, source={"tris": tris, "a": a, "b": b})

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        st = _SparseBench.stimulus(self, params, seed)
        rng = np.random.default_rng(seed)
        a, b = int(rng.integers(0, params["p"])), int(rng.integers(0, params["q"]))
        return self.frame(st.source, params, a, b, what=f"{st.what}, processor ({a}, {b})")

    def expect(self, params: dict, stim: Stimulus, g=None) -> Expected:
        """``g``: the frame's golden search (``sparse_render(..., trace=True)``), made here if not given
        (a scene's processors share one)."""
        from rasterhw.golden_model.sparse.vpcycles import vp_standalone, vp_streams

        tris, a, b = stim.source["tris"], stim.source["a"], stim.source["b"]
        p, q = params["p"], params["q"]
        g = sparse_render(tris, (p, q), depth="fixed", trace=True) if g is None else g
        zq = g.depth_words(tris.z_bits)
        k = b * p + a
        m = vp_standalone(*vp_streams(g, k), g.triangles, fifo_depth=params["fifo_depth"], kp=params["kp"],
                          ke=params["ke"])
        tail = [*m["tests"], *m["stalls"], int(g.stats["writes_per_proc"][k]), m["cycles"]]
        return Expected({"o": _words(g.tri_id[b::q, a::p], zq[b::q, a::p], params["z_bits"]) + [int(v) for v in tail]})

    def decode(self, params: dict, words: list[int]) -> dict:
        """The engine's ``o`` words as ``tri``, ``zq`` (N x N, -1
        where empty), ``tests``, ``stalls``, ``writes``, ``cycles``."""
        n, zb = params["n"], params["z_bits"]
        N = 1 << n
        if len(words) != N * N + 2 * n + 2:
            raise ValueError(f"sparse processor bench: {len(words)} words, expected {N * N + 2 * n + 2}")
        low = np.array(words[:N * N], dtype=np.int64)
        tri = low >> (zb + 1)
        zq = low & ((1 << (zb + 1)) - 1)
        empty = tri == (1 << TRI_BITS) - 1
        tri[empty], zq[empty] = -1, -1
        t = [int(v) for v in words[N * N:]]
        return {"tri": tri.reshape(N, N), "zq": zq.reshape(N, N), "tests": t[:n], "stalls": t[n:2 * n],
                "writes": t[2 * n], "cycles": t[2 * n + 1]}


#: sparse addresses the frame bench reads a clock through the matrix's wide read-out (ours; docs/sparse.md)
READ_LANES = 4
#: cell parameters left out of the cell Verilog's cache key at these values
_CELL_DEFAULTS = {"alpha": 2, "beta": 2, "vp": "pipeline", "colour": False, "kp": 0, "ke": 3}


class MatrixFrameBench(MatrixBench):
    """The whole matrix on one frame as ``rasterhw sim sparse`` runs it (not registered: the
    ``sparse-matrix`` block on the generic engines, :func:`rasterhw.sim.sparse.scene.run_matrix`).

    In (``i``): a config word setting the input FIFOs' run-time ``limit`` (1 .. ``in_depth``: one
    build serves every depth), the broadcast records, the end word. Out (``o``): the full raster
    (``{tri, z}`` per pixel, row-major; ``{rgb, tri, z}`` with ``colour``), then the matrix's frame
    and broadcast-stall cycles, then every cell's counters (:func:`~rasterhw.hdl.sparse.cell.cell_stats`,
    cell ``b * p + a``), against the golden search and the golden coupled cycle model (the
    pipeline's ``vpcycles.coupled_matrix_vp``, the stack's ``stack.coupled_stack_matrix``); the
    counters hold for input offered back to back (the frame counts the cycles with a record
    offered or held). ``cells="instance"`` (Verilator only): the matrix instantiates one cell
    module by name, generated once (a 1024 x 1024 frame's cell is 4.6 MB of Verilog, mostly its
    local memories' initial values); ``"inline"`` elaborates every cell (pysim too).

    ``readout="wide"`` (default): the raster leaves through the matrix's parallel read-out (ours,
    the bench's; ``Matrix(wide_read=True)``), ``lanes`` sparse addresses a clock with every
    processor's words side by side (``rd_words``: ``2**(2n) / lanes`` words of ``p*q*lanes``
    lanes, lane ``k * lanes + j`` processor ``k``'s word of sparse address ``g * lanes + j``,
    ``{tri, z}`` or ``{rgb, tri, z}``), so the read-out costs ``1 / (p*q*lanes)`` of the raster's
    pixels in clocks; ``"port"``: through the paper's interleaved read port, one pixel a clock,
    row-major (the counters follow either way, one a word). :meth:`decode` gives the same full
    raster from either."""

    def __init__(self, cells: str = "instance", readout: str = "wide", lanes: int = READ_LANES):
        if readout not in ("wide", "port"):
            raise ValueError(f"sparse frame bench: readout must be 'wide' or 'port', not {readout!r}")
        if isinstance(lanes, bool) or not isinstance(lanes, int) or lanes < 1 or lanes & (lanes - 1):
            raise ValueError(f"sparse frame bench: lanes must be a power of two, not {lanes!r}")
        self.cells, self.readout, self.lanes = cells, readout, lanes
        #: the Verilator engine's C++ level: a frame is one run of up to millions of clocks
        self.verilator_opt = "-O2"

    def hier_blocks(self, params: dict) -> tuple[str, ...]:
        """The cell module (``cells="instance"``): one verilation for the p*q cells
        (``build={"hier": True}``, ``rasterhw sim sparse --hierarchical``)."""
        from rasterhw.hdl.sparse.matrix import CELL_MODULE

        return (CELL_MODULE,) if self.cells == "instance" else ()

    @staticmethod
    def names(params: dict) -> list[str]:
        """The counter words after the raster, in order."""
        from rasterhw.hdl.sparse.cell import cell_stats

        P = params["p"] * params["q"]
        return ["cycles", "stall_cycles"] + [f"{c}/{k}" for k in range(P) for c in cell_stats(params["n"])]

    def dut(self, params: dict):
        from rasterhw.hdl.sparse.cell import MatrixCell, cell_stats
        from rasterhw.hdl.sparse.layouts import layouts
        from rasterhw.hdl.sparse.matrix import CELL_MODULE, Matrix
        from rasterhw.sim.engines.verilog_cache import convert_cached

        kw = dict(params)
        wide = self.readout == "wide"
        lanes = self._check_lanes(params) if wide else 0
        mx = Matrix(**kw, cells=self.cells, wide_read=wide, read_lanes=max(lanes, 1))
        extra = ""
        if self.cells == "instance":
            # the cell's cache key as the plain bench had it: parameters at their defaults left out
            key = {k: kw[k] for k in ("n", "p", "q", "z_bits", "fifo_depth", "in_depth")}
            key.update({k: kw[k] for k, v in _CELL_DEFAULTS.items() if kw[k] != v})
            if lanes:
                key["read_lanes"] = lanes
            extra = convert_cached("sparse-matrix", lambda: MatrixCell(**kw, read_lanes=lanes), params=key,
                                   module=CELL_MODULE)
        if wide:
            nb = len(mx.rd_addr)

            def address(m, b, addr):
                m.d.comb += b.rd_addr.eq(addr[:nb])

            words, data = self.pixel_words(params), (lambda b: b.rd_words)
        else:
            w, h = self.raster(params)
            xb = (w - 1).bit_length()

            def address(m, b, addr):
                m.d.comb += [b.rd_x.eq(addr[:xb]), b.rd_y.eq(addr[xb:])]

            words, data = w * h, _word(params["colour"])
        return ReadOut(mx, words=words, address=address, data=data,
                       config={"limit": params["in_depth"]}, tail=("cycles", "stall_cycles"),
                       stats=(params["p"] * params["q"], len(cell_stats(params["n"]))),
                       record_bits=layouts(params["colour"])[0].size, extra=extra)

    def _check_lanes(self, params: dict) -> int:
        """``lanes``, checked against the matrix's sparse addresses (``benchread.check_lanes``)."""
        from rasterhw.hdl.sparse.benchread import check_lanes

        check_lanes(params["n"], self.lanes)
        return self.lanes

    def pixel_words(self, params: dict) -> int:
        """The raster's words on ``o`` (before the counters): ``2**(2n) / lanes`` through the wide
        read-out, ``W * H`` through the port."""
        w, h = self.raster(params)
        return (1 << (2 * params["n"])) // self._check_lanes(params) if self.readout == "wide" else w * h

    @staticmethod
    def _lane_bits(params: dict) -> int:
        from rasterhw.hdl.sparse.benchread import lane_bits

        return lane_bits(params["z_bits"], params["colour"])

    def _lanes(self, params: dict, words: list[int]) -> list[int]:
        """Row-major full-raster words -> the parallel read-out's words: word ``g`` carries sparse
        address ``s = g * lanes + j`` (``s = v * 2**n + u``: pixel ``(u p + a, v q + b)``) of every
        processor ``k = b p + a`` in lane ``k * lanes + j``."""
        p, q, lb, L = params["p"], params["q"], self._lane_bits(params), self._check_lanes(params)
        w, h = self.raster(params)
        rows = [words[y * w:(y + 1) * w] for y in range(h)]
        out = [0] * self.pixel_words(params)
        for k in range(p * q):
            a, b = k % p, k // p
            lane = [v for row in rows[b::q] for v in row[a::p]]
            for j in range(L):
                out = [o | v << ((k * L + j) * lb) for o, v in zip(out, lane[j::L], strict=True)]
        return out

    def _unlanes(self, params: dict, wide: list[int]) -> list[int]:
        """The inverse of :meth:`_lanes`: the row-major full-raster words."""
        p, q, lb, n, L = params["p"], params["q"], self._lane_bits(params), params["n"], self._check_lanes(params)
        w, h = self.raster(params)
        N, mask = 1 << n, (1 << lb) - 1
        out = [0] * (w * h)
        for k in range(p * q):
            a, b = k % p, k // p
            for j in range(L):
                sh = (k * L + j) * lb
                for g, v in enumerate(wide):
                    s = g * L + j
                    out[((s >> n) * q + b) * w + (s & (N - 1)) * p + a] = (v >> sh) & mask
        return out

    def frame(self, tris, params: dict, limit: int, what: str = "") -> Stimulus:
        """The words of one frame: the limit, the records of ``tris``, the end word."""
        from rasterhw.golden_model.sparse.stack import broadcast_records_rgb
        from rasterhw.hdl.pack import pack
        from rasterhw.hdl.sparse.layouts import layouts

        if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= params["in_depth"]:
            raise ValueError(f"sparse matrix: FIFO depth must be an integer in 1..{params['in_depth']}, not {limit!r}")
        lay = layouts(params["colour"])[0]
        recs = broadcast_records_rgb(tris) if params["colour"] else broadcast_records(tris)
        cfg = ReadOut.config_word(lay.size, {"limit": params["in_depth"].bit_length()}, {"limit": limit})
        words = [cfg] + [pack(lay, r) for r in recs] + [1 << lay.size]
        return Stimulus({"i": words}, what=what, source={"tris": tris, "limit": limit})

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        st = super().stimulus(params, seed)
        limit = int(np.random.default_rng(seed).integers(1, params["in_depth"] + 1))
        return self.frame(st.source, params, limit, what=f"{st.what}, input FIFO limit {limit}")

    def golden_counters(self, params: dict, stim: Stimulus) -> dict:
        """The golden coupled cycle model of the frame: ``coupled_matrix_vp``'s keys (``stalls``
        per processor and level) and ``writes`` per processor."""
        from rasterhw.golden_model.sparse.cycles import KE_EDGES
        from rasterhw.golden_model.sparse.stack import coupled_stack_matrix
        from rasterhw.golden_model.sparse.vpcycles import coupled_matrix_vp

        tris, limit = stim.source["tris"], stim.source["limit"]
        p, q = params["p"], params["q"]
        g = sparse_render(tris, (p, q), depth="fixed", trace=True)
        if params["vp"] == "stack":
            gc = coupled_stack_matrix(tris, p, q, limit, kp=params["kp"], ke=params["ke"])
        else:
            gc = coupled_matrix_vp(g, limit, fifo_depth=params["fifo_depth"], kp=params["kp"],
                                   ke=params.get("ke", KE_EDGES))
        return {**gc, "writes": g.stats["writes_per_proc"].tolist(), "records": g.triangles, "frame": g}

    def expect(self, params: dict, stim: Stimulus, gc: dict | None = None) -> Expected:
        """``gc``: :meth:`golden_counters` of ``stim``, made here if not given."""
        from rasterhw.golden_model.sparse.fixed import colour_rgb8

        tris = stim.source["tris"]
        gc = self.golden_counters(params, stim) if gc is None else gc
        g = gc["frame"]
        zq = g.depth_words(tris.z_bits)
        words = _words(g.tri_id, zq, params["z_bits"])
        if params["colour"]:
            words = VPBench.with_rgb(words, colour_rgb8(tris, g.tri_id, params["p"], params["q"]), params["z_bits"])
        if self.readout == "wide":
            words = self._lanes(params, words)
        cells = []
        for k in range(params["p"] * params["q"]):
            cells += list(gc["tests"][k]) + list(gc["stalls"][k]) + [gc["writes"][k], gc["busy"][k],
                                                                     gc["fifo_peak"][k], gc["records"]]
        return Expected({"o": words + [gc["frame_cycles"], gc["stall_cycles"]] + [int(v) for v in cells]})

    def decode(self, params: dict, words: list[int]) -> dict:
        """The engine's ``o`` words as ``run_matrix_pysim``'s keys: ``tri``, ``zq``, ``rgb`` (or
        None), ``cycles``, ``stall_cycles``, ``stats`` (counter name -> (p*q,) array)."""
        from rasterhw.hdl.sparse.cell import cell_stats

        w, h = self.raster(params)
        zb = params["z_bits"]
        names = cell_stats(params["n"])
        P = params["p"] * params["q"]
        npx = self.pixel_words(params)
        if len(words) != npx + 2 + P * len(names):
            raise ValueError(f"sparse frame bench: {len(words)} words, expected {npx + 2 + P * len(names)}")
        px = self._unlanes(params, words[:npx]) if self.readout == "wide" else words[:npx]
        if params["colour"]:
            sh = TRI_BITS + zb + 1
            rgb_w = np.array([v >> sh for v in px], dtype=np.int64)
            low = np.array([v & ((1 << sh) - 1) for v in px], dtype=np.int64)
            rgb = np.stack([(rgb_w >> (8 * ch)) & 255 for ch in range(3)], axis=-1).reshape(h, w, 3)
        else:
            low, rgb = np.array(px, dtype=np.int64), None
        tri = low >> (zb + 1)
        zq = low & ((1 << (zb + 1)) - 1)
        empty = tri == (1 << TRI_BITS) - 1
        tri[empty], zq[empty] = -1, -1
        st = np.array(words[npx + 2:], dtype=np.int64).reshape(P, len(names))
        return {"tri": tri.reshape(h, w), "zq": zq.reshape(h, w), "rgb": rgb, "cycles": int(words[npx]),
                "stall_cycles": int(words[npx + 1]), "stats": {nm: st[:, j] for j, nm in enumerate(names)}}


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
