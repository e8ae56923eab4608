"""``rasterhw sim sparse``'s scene level (``sim/engines/scene.py``): every video processor of the matrix in
HDL on the scene, its memories compared with the bit-accurate golden model pixel by pixel (triangle
index and quantised depth), on the generic engines (pysim, Verilator).

Two runs, by ``coupled``:

* the whole matrix in one simulation (``hdl/sparse/matrix.py``; the testbench
  :class:`~rasterhw.sim.sparse.testbench.MatrixFrameBench`: broadcast, every processor's input
  FIFO, back-pressure from the fullest, the raster read out in parallel, then the frame and stall
  counters and every cell's counters), the counters against the golden coupled cycle model
  (``golden_model/sparse/vpcycles.py``: ``coupled_matrix_vp``; the stack processors'
  ``stack.coupled_stack_matrix``): :func:`matrix_job`;
* ``--no-coupled``: every processor alone on the full stream, one simulation each (the testbench
  :class:`~rasterhw.sim.sparse.testbench.ProcessorBench`: its place ``(a, b)`` in a config word, so
  one build serves every processor; its local memory, per-level tests, stalls, writes and cycles
  out), the memories interleaved in software: :func:`processor_job`.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.sparse.cycles import KE_EDGES
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import interleave, sparse_render
from rasterhw.golden_model.sparse.vpcycles import HDL_FIFO_DEPTH
from rasterhw.sim.engines.scene import Done, Job, SceneRun, run_job
from rasterhw.sim.testbench import Expected

__all__ = ["HIER_FROM_CELLS", "IN_DEPTH", "MAXT", "SparseScene", "check_processor", "depth_image", "matrix_job",
           "processor_job", "run_matrix", "run_processor", "simulate", "simulate_coupled", "simulate_tris"]

#: ``hierarchical=None``: Verilator's hierarchical build from this many processors up (measured at
#: 1024² c300 4x4, docs/sparse.md: flat 1,173-2,229 s to build; hierarchical ~20 s, the clock loop slower)
HIER_FROM_CELLS = 16
#: the input FIFOs as built: the deepest run-time limit a run can ask for (one build for every depth)
IN_DEPTH = 64
#: the most records a frame may have (the benches' input memory: one build for every frame)
MAXT = 16384


# ====================================================================== one processor alone
def processor_job(tris, *, n: int, p: int, q: int, a: int, b: int, z_bits: int = 24, idle: int = 0, seed: int = 1,
                  engine: str = "verilator", g=None) -> Job:
    """Processor ``(a, b)`` on ``tris`` (``ProcessorBench``): ``idle`` (0..255): each clock before a
    record is idle with probability ``idle / 256`` (seeded by ``seed``; the frame and the per-level
    tests do not depend on it, the cycle count does, so it is then checked as a lower bound);
    ``g``: the frame's golden search, shared by the processors of a scene."""
    from rasterhw.sim.sparse.testbench import ProcessorBench

    if isinstance(idle, bool) or not (isinstance(idle, int) and 0 <= idle <= 255):
        raise RasterhwError(f"sparse processor bench: idle must be an integer in 0..255, not {idle!r}")
    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse HDL: processor ({a}, {b}) is outside a {p}x{q} matrix")
    tb = ProcessorBench()
    params = tb.params(n=n, p=p, q=q, z_bits=z_bits)
    stim = tb.frame(tris, params, a, b)
    ntri = len(stim.words["i"]) - 2
    if ntri > MAXT:
        raise RasterhwError(f"sparse processor bench holds at most {MAXT} triangles, not {ntri}")
    N = 1 << n
    maxcyc = (200 * (ntri + 10) * (1 + n) + 64 * N * N + 10_000_000) * (1 + idle // 16)
    run = {"idle": idle / 256, "seed": seed, "max_cycles": maxcyc,
           "build": {"depth": MAXT + 2} if engine != "pysim" else None}   # one build per design
    return Job(tb, params, stim, tb.expect(params, stim, g), run, cycle_exact=not idle, name=f"processor ({a}, {b})")


def _decode(d: Done) -> dict:
    return d.job.tb.decode(d.job.params, d.got.words["o"])


def run_processor(tris, *, engine: str = "verilator", **kw) -> dict:
    """:func:`processor_job` (its keywords) on ``engine`` (pysim, Verilator, the cocotb engines):
    ``tri``, ``zq`` (N x N, -1 where empty), ``tests`` and ``stalls`` per level, ``writes``, ``cycles``
    (the processor's own count) plus ``run_s``, ``build_s``, ``records`` and ``sim_cycles`` (the
    bench's clocks, read-out included); a run that broke the stream rules is an error."""
    d = run_job(processor_job(tris, engine=engine, **kw), engine)
    if d.got.protocol_errors:
        raise RasterhwError(f"sparse {d.job.name} on {engine}: {d.got.protocol_errors} clocks broke the stream rules")
    return {**_decode(d), "sim_cycles": d.got.cycles, "run_s": d.got.run_s, "build_s": d.got.build_s,
            "records": len(d.job.stim.words["i"]) - 2}


def check_processor(tris, matrix: str = "4x4", *, a: int = 0, b: int = 0, engine: str = "cocotb-verilator",
                    idle: int = 0, seed: int = 1, expect: dict | None = None) -> dict:
    """Processor ``(a, b)`` of ``matrix`` on screen triangles ``tris`` against the bit-accurate golden
    model: ``mismatches`` counts the local-memory words (triangle and depth) and per-level test
    counts that differ (``expect`` overrides the golden ``tri`` / ``zq`` / ``tests``: a test of the
    check). Also ``records``, ``words_read`` (the local memory's words), ``n``."""
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    g = sparse_render(tris, (p, q), depth="fixed")
    gz = g.depth_words(tris.z_bits)
    want = {"tri": g.tri_id[b::q, a::p], "zq": gz[b::q, a::p], "tests": g.tests_per_proc[b * p + a, 1:]}
    want.update(expect or {})
    r = run_processor(tris, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, idle=idle, seed=seed, engine=engine)
    bad = int(np.count_nonzero((r["tri"] != want["tri"]) | (r["zq"] != want["zq"])))
    bad += int(np.count_nonzero(np.asarray(r["tests"]) != np.asarray(want["tests"])))
    return {"records": r["records"], "words_read": int(r["tri"].size), "n": n, "mismatches": bad}


# ====================================================================== the whole matrix
def matrix_job(tris, *, n: int, p: int, q: int, limit: int, z_bits: int = 24, fifo_depth: int = HDL_FIFO_DEPTH,
               in_depth: int = IN_DEPTH, vp: str = "pipeline", colour: bool = False, kp: int = 0, ke: int = KE_EDGES,
               engine: str = "verilator", hierarchical: bool = False) -> Job:
    """The matrix on one frame of ``tris`` (``MatrixFrameBench``: the records offered back to back,
    the input FIFOs' run-time ``limit`` in a config word, the raster and every counter streamed
    out), against the golden search and coupled cycle model, made once (``Job.expect.golden``:
    ``MatrixFrameBench.golden_counters``). ``engine="verilator"`` instantiates one cell module by
    name; ``"pysim"`` elaborates every cell. ``hierarchical`` (Verilator): the cell verilated and
    compiled once (``build={"hier": True}``): the same model, a much shorter build, a slower clock
    loop (``docs/sparse.md``)."""
    from rasterhw.sim.sparse.testbench import MatrixFrameBench

    if hierarchical and engine != "verilator":
        raise RasterhwError("sparse sim: --hierarchical is a flag of the Verilator build")
    tb = MatrixFrameBench("instance" if engine == "verilator" else "inline")
    params = tb.params(n=n, p=p, q=q, z_bits=z_bits, fifo_depth=fifo_depth, in_depth=in_depth, vp=vp, colour=colour,
                       kp=kp, ke=ke)
    try:
        stim = tb.frame(tris, params, limit)
    except ValueError as e:
        raise RasterhwError(str(e)) from None
    ntri = len(stim.words["i"]) - 2
    if ntri > MAXT:
        raise RasterhwError(f"sparse matrix bench holds at most {MAXT} triangles, not {ntri}")
    gc = tb.golden_counters(params, stim)
    exp = tb.expect(params, stim, gc)
    maxcyc = 400 * (ntri + 10) * (1 + n) * (1 + 64 // limit) + 4 * (p << n) * (q << n) + 10_000_000
    # the input memory sized for MAXT records whatever the frame: one build per design
    build = {"depth": MAXT + 2, **({"hier": True} if hierarchical else {})} if engine == "verilator" else None
    return Job(tb, params, stim, Expected(exp.words, golden=gc), {"max_cycles": maxcyc, "build": build})


def run_matrix(tris, *, engine: str = "verilator", **kw) -> dict:
    """:func:`matrix_job` (its keywords) on ``engine``: ``tri`` / ``zq`` (full raster, -1 where
    empty), ``rgb`` (``(H, W, 3)`` with ``colour``, else None), ``cycles`` (the matrix's frame
    counter), ``stall_cycles``, ``stats`` (counter name -> (p*q,) array), ``run_s``, ``build_s``,
    ``sim_cycles`` (the bench's clocks, read-out included), ``protocol_errors``."""
    d = run_job(matrix_job(tris, engine=engine, **kw), engine)
    return {**_decode(d), "run_s": d.got.run_s, "sim_cycles": d.got.cycles, "build_s": d.got.build_s,
            "protocol_errors": d.got.protocol_errors}


def depth_image(zq: np.ndarray, z_bits: int) -> np.ndarray:
    """(H, W, 3) uint8 grey image of a read-out depth buffer (-1 empty -> black; near -> bright)."""
    z = zq.astype(np.float64)
    grey = np.where(zq >= 0, 255.0 - 200.0 * z / float((1 << z_bits) - 1), 0.0)
    g = np.clip(np.rint(grey), 0, 255).astype(np.uint8)
    return np.repeat(g[..., None], 3, axis=2)


# ====================================================================== the scene level
class SparseScene(SceneRun):
    """``rasterhw sim sparse`` (module docstring). ``coupled``: the whole matrix in one simulation;
    otherwise every processor alone (``"coupled": false``; its processors built with eight-entry
    inner FIFOs, ours). ``fifo_depth``: the input FIFOs' run-time limit (built :data:`IN_DEPTH`
    deep); ``vp_fifo_depth``: the FIFOs between the processor's levels (a build parameter): ``None``
    is :data:`HDL_FIFO_DEPTH` (8: a queue of windows inside the processor) or down to 2 (the paper
    gives no size; both ours; ``"vp_buffers"`` says which). ``vp="stack"``: every processor the
    stack-based one (``hdl/sparse/stack_vp.py``); ``busy`` is then the processor's own count of the
    cycles it holds a record. ``colour``: the vertex colours broadcast as three more linear
    functions and written with the Z test, the HDL's colour memories against ``fixed.colour_rgb8``
    (``colour_mismatches``; the frame image is then the HDL's colour); ``kp``: formula (5)'s cost of
    ``kp`` parameter additions per surviving window on ``k_e`` = 3 edge adders. ``hierarchical``
    (Verilator): the cell verilated and compiled once; ``None``: from :data:`HIER_FROM_CELLS`
    processors up. ``mismatches``: pixels whose triangle or depth differs; ``cycle_mismatches``:
    counters that differ from the golden cycle models. Screen triangles may stand for the scene
    (the report's and the soak's frames); ``idle``, ``seed`` (``--no-coupled``): random idle clocks
    on every processor's input (processor ``(a, b)`` seeded ``seed + 64 b + a``)."""

    block = "sparse"
    engines = ("pysim", "verilator")
    workers = 2

    def check(self, engine: str, matrix="4x4", coupled: bool = True, fifo_depth: int = 64,
              vp_fifo_depth: int | None = None, vp: str = "pipeline", colour: bool = False, kp: int = 0,
              hierarchical: bool | None = None, idle: int = 0, seed: int = 1) -> None:
        parse_matrix(matrix)
        if not coupled:
            if fifo_depth != 64 or vp_fifo_depth is not None or vp != "pipeline" or colour or kp or hierarchical:
                raise RasterhwError("sparse sim: --fifo-depth, --vp-fifo-depth, --vp, --colour, --kp and "
                                    "--hierarchical are options of the coupled matrix (drop --no-coupled)")
            return
        if vp == "stack" and vp_fifo_depth is not None:
            raise RasterhwError("sparse sim: --vp-fifo-depth is the pipeline processor's; the stack processor has "
                                "no inner FIFOs")
        vpd = HDL_FIFO_DEPTH if vp_fifo_depth is None else vp_fifo_depth
        if isinstance(vpd, bool) or not isinstance(vpd, int) or not 2 <= vpd <= 64:
            raise RasterhwError(f"sparse sim: --vp-fifo-depth must be an integer in 2..64, not {vpd!r}")
        if vp not in ("pipeline", "stack"):
            raise RasterhwError(f"sparse sim: --vp must be 'pipeline' or 'stack', not {vp!r}")
        if not isinstance(colour, bool):
            raise RasterhwError(f"sparse sim: --colour is a flag, not {colour!r}")
        if isinstance(kp, bool) or not isinstance(kp, int) or not 0 <= kp <= 15:
            raise RasterhwError(f"sparse sim: --kp must be an integer in 0..15, not {kp!r}")
        if hierarchical is not None and (not isinstance(hierarchical, bool) or (hierarchical and engine != "verilator")):
            raise RasterhwError("sparse sim: --hierarchical is a flag of the Verilator build")

    def golden(self, scene, width: int, height: int, *, engine: str, matrix="4x4", coupled: bool = True,
               **_) -> dict:
        p, q = parse_matrix(matrix)
        n = sparse_geometry(width, height, p, q)
        tris = scene if isinstance(scene, ScreenTriangles) else run_geometry(scene, width, height)
        # the golden search of the whole frame (its matrix's jobs make theirs with the cycle model)
        return {"tris": tris, "p": p, "q": q, "n": n,
                "search": None if coupled else sparse_render(tris, (p, q), depth="fixed", trace=True)}

    def jobs(self, gold: dict, *, engine: str, coupled: bool = True, fifo_depth: int = 64,
             vp_fifo_depth: int | None = None, vp: str = "pipeline", colour: bool = False, kp: int = 0,
             hierarchical: bool | None = None, idle: int = 0, seed: int = 1, **_) -> list[Job]:
        tris, p, q, n = gold["tris"], gold["p"], gold["q"], gold["n"]
        if not coupled:
            return [processor_job(tris, n=n, p=p, q=q, a=a, b=b, z_bits=tris.z_bits, idle=idle, seed=seed + 64 * b + a,
                                  engine=engine, g=gold["search"]) for b in range(q) for a in range(p)]
        if hierarchical is None:
            hierarchical = engine == "verilator" and p * q >= HIER_FROM_CELLS
        return [matrix_job(tris, n=n, p=p, q=q, limit=fifo_depth, z_bits=tris.z_bits,
                           fifo_depth=HDL_FIFO_DEPTH if vp_fifo_depth is None else vp_fifo_depth, vp=vp,
                           colour=colour, kp=kp, engine=engine, hierarchical=hierarchical)]

    def result(self, gold: dict, done: list[Done], *, engine: str, coupled: bool = True, **_) -> dict:
        tris, p, q, n = gold["tris"], gold["p"], gold["q"], gold["n"]
        base = {"matrix": f"{p}x{q}", "n": n, "triangles": int(np.asarray(tris.xy).shape[0])}
        if not coupled:
            return {**base, "coupled": False, **self._processors(gold, done)}
        (d,) = done
        h, gc, prm = _decode(d), d.job.expect.golden, d.job.params
        g = gc["frame"]
        gz = g.depth_words(tris.z_bits)
        st = h["stats"]
        tests = np.stack([st[f"tests_{i}"] for i in range(1, n + 1)], axis=1)
        pairs = [(h["cycles"], gc["frame_cycles"]), (h["stall_cycles"], gc["stall_cycles"])]
        pairs += list(zip(st["fifo_peak"].tolist(), gc["fifo_peak"], strict=True))
        pairs += list(zip(st["busy_cycles"].tolist(), gc["busy"], strict=True))
        pairs += list(zip(tests.ravel().tolist(), np.asarray(gc["tests"]).ravel().tolist(), strict=True))
        frame, busy, vp, colour = h["cycles"], st["busy_cycles"], prm["vp"], prm["colour"]
        out = {**base, "coupled": True, "vp": vp, "cycles": frame,
               "pixels_compared": int(h["tri"].size),
               "mismatches": int(np.count_nonzero((h["tri"] != g.tri_id) | (h["zq"] != gz))),
               "cycle_mismatches": sum(int(a != b) for a, b in pairs), "colour": colour}
        if colour:
            from rasterhw.golden_model.sparse.fixed import colour_rgb8

            grgb = colour_rgb8(tris, g.tri_id, p, q)
            out.update(colour_mismatches=int(np.count_nonzero((h["rgb"] != grgb).any(axis=-1))),
                       colour_pixels_compared=int(h["tri"].size))
        vpd = prm["fifo_depth"]
        out.update({
            "kp": prm["kp"], "ke": prm["ke"], "cycles_compared": len(pairs), "fifo_depth": d.job.stim.source["limit"],
            "fifo_depth_built": prm["in_depth"], "vp_fifo_depth": vpd,
            "vp_buffers": "none (stack processor)" if vp == "stack" else f"ours ({vpd}-entry FIFOs between the levels)",
            "hierarchical": bool((d.job.run.get("build") or {}).get("hier")), "gp_issue_interval": 1,
            "frame_cycles": frame, "frame_cycles_golden": gc["frame_cycles"],
            "stall_cycles": h["stall_cycles"], "stall_cycles_golden": gc["stall_cycles"],
            "fifo_peak": st["fifo_peak"].tolist(), "fifo_peak_golden": gc["fifo_peak"],
            "fifo_peak_max": int(st["fifo_peak"].max()), "fifo_peak_max_golden": gc["fifo_peak_max"],
            "busy": busy.tolist(), "busy_golden": gc["busy"],
            "idle": (frame - busy).tolist(), "idle_golden": gc["idle"],
            "tests_per_level_hdl": tests.sum(axis=0).tolist(),
            "tests_match_golden": bool(np.array_equal(tests, g.tests_per_proc[:, 1:])),
            "writes": int(st["writes"].sum()), "pixels_written_golden": int(g.pixels_written),
            # the paper's video controller at one pixel a clock (ours: the paper gives no rate) and the
            # bench's clocks for the raster through its wide read-out, readout_lanes sparse addresses a clock
            "readout_cycles": int(h["tri"].size), "readout_lanes": d.job.tb.lanes,
            "bench_readout_clocks": d.job.tb.pixel_words(prm)})
        if colour:
            out.update(frame_rgb=h["rgb"].astype(np.uint8),
                       frame_note="the HDL's colour memories (R, G, B as linear functions), read out interleaved")
        else:
            out.update(frame_rgb=depth_image(h["zq"], tris.z_bits),
                       frame_note="the HDL's video memory holds depth only: the image is its depth buffer (near = bright)")
        return out

    @staticmethod
    def _processors(gold: dict, done: list[Done]) -> dict:
        """``--no-coupled``: the processors' memories interleaved against the golden frame; each
        processor's tests, stalls, writes and cycles (its tail words) against its cycle model."""
        tris, p, q, n, g = gold["tris"], gold["p"], gold["q"], gold["n"], gold["search"]
        N = 1 << n
        loc_t = np.full((q, p, N, N), -1, dtype=np.int64)
        loc_z = np.full((q, p, N, N), -1, dtype=np.int64)
        per = [_decode(d) for d in done]
        for d, r in zip(done, per, strict=True):
            a, b = d.job.stim.source["a"], d.job.stim.source["b"]
            loc_t[b, a], loc_z[b, a] = r["tri"], r["zq"]
        ht, hz = interleave(loc_t), interleave(loc_z)
        tail = N * N
        tests = np.array([r["tests"] for r in per])  # (P, n)
        return {"cycles": int(max(r["cycles"] for r in per)), "pixels_compared": int(ht.size),
                "mismatches": int(np.count_nonzero((ht != g.tri_id) | (hz != g.depth_words(tris.z_bits)))),
                "cycle_mismatches": sum(int(a != b) for d in done for a, b in
                                        zip(d.got.words["o"][tail:], d.job.expect.words["o"][tail:], strict=True)
                                        if d.job.cycle_exact),
                "tests_per_level_hdl": tests.sum(axis=0).tolist(),
                "tests_match_golden": bool(np.array_equal(tests, g.tests_per_proc[:, 1:])),
                "max_stage_tests_per_processor": int(tests.max()), "writes": int(sum(r["writes"] for r in per)),
                "pixels_written_golden": int(g.pixels_written)}


simulate = SparseScene().simulate


def simulate_coupled(tris, matrix="4x4", **kw) -> dict:
    """The whole matrix on screen triangles ``tris`` (:class:`SparseScene`'s keys and options)."""
    return simulate(tris, tris.width, tris.height, matrix=matrix, coupled=True, **kw)


def simulate_tris(tris, matrix="4x4", **kw) -> dict:
    """Every processor alone on screen triangles ``tris`` (``--no-coupled``; :class:`SparseScene`'s
    keys and options, ``idle``, ``seed``, ``workers``)."""
    return simulate(tris, tris.width, tris.height, matrix=matrix, coupled=False, **kw)
