"""cocotb bench of one sparse video processor (``cocotb_tests/sparse/test_vp.py``), Verilator or Icarus.

The scene runs (``rasterhw sim sparse``) use the generic engine's timing-free Verilator bench
(:mod:`rasterhw.sim.sparse.verilator_run`, ``ProcessorBench``); this bench drives the generated
Verilog from Python with idle clocks, a stream checker and an in-order scoreboard on the input,
and reads the local memory back through the video-controller port.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.formats import TRI_BITS, parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.sim.engines.runner import build_dir_for, get_sim, run_cocotb
from rasterhw.sim.outfile import write_if_changed
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["run_cocotb_bench"]


def run_cocotb_bench(tris, matrix="4x4", *, a: int = 0, b: int = 0, sim: str | None = None, idle: float = 0.0,
                     seed: int = 1, expect: dict | None = None) -> dict:
    """Processor ``(a, b)`` of ``matrix`` on screen triangles ``tris`` under cocotb, against the
    bit-accurate golden model (``expect`` overrides the golden local memory: a test of the bench).
    Raises :class:`~rasterhw.golden_model.errors.RasterhwError` if any check fails."""
    from rasterhw.hdl.pack import pack
    from rasterhw.hdl.sparse.layouts import BROADCAST
    from rasterhw.hdl.sparse.vp import make_vp
    from rasterhw.sim.engines.verilog_cache import convert_cached

    sim = get_sim(sim)
    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    z_bits = tris.z_bits
    recs = broadcast_records(tris)
    g = sparse_render(tris, (p, q), depth="fixed")
    gz = np.where(g.tri_id >= 0, np.rint(g.depth * (1 << z_bits)), -1).astype(np.int64)
    local_t, local_z = g.tri_id[b::q, a::p], gz[b::q, a::p]
    want = {"tri": local_t, "zq": local_z, "tests": g.tests_per_proc[b * p + a, 1:]}
    want.update(expect or {})
    params = {"n": n, "p": p, "q": q, "z_bits": z_bits}
    text = convert_cached("sparse-vp", lambda: make_vp(**params), params=params, module="sparse_vp")
    bdir = build_dir_for("sparse-vp-cocotb", sim, **params)
    bdir.mkdir(parents=True, exist_ok=True)
    vpath = bdir / "sparse_vp.v"
    write_if_changed(vpath, text)
    run_dir = temp_run_folder(bdir)
    exp = run_dir / "expect.npz"
    np.savez(exp, words=np.array([f"{pack(BROADCAST, r):x}" for r in recs], dtype=str), n=n, a=a, b=b,
             tri=want["tri"], zq=want["zq"], tests=np.asarray(want["tests"]), tri_bits=TRI_BITS)
    timings: dict = {}
    # a failed run keeps its folder (the error names its sim.log); a passed one is removed
    run_cocotb(sources=[vpath], toplevel="sparse_vp", test_module="cocotb_tests.sparse.test_vp", build_dir=bdir,
               test_dir=run_dir, sim=sim, timings=timings,
               extra_env={"VP_EXPECT": str(exp), "VP_IDLE": str(idle), "VP_SEED": str(seed)})
    release(run_dir)
    return {"records": len(recs), "words_read": int(local_t.size), "n": n, **timings}
