"""cocotb bench of one EXPERTS PXP (``cocotb_tests/experts/test_pxp.py``) on Verilator or Icarus.

The scene runs (``rasterhw sim pxp``, :mod:`rasterhw.sim.experts.pxp_sim`) run the PXP's testbench on
the generic engines (pysim, plain Verilator). This bench is the other half: cocotb drives the
generated Verilog with idle clocks on the segment stream and back-pressure on the pixel stream,
stream checkers on both ports, and in-order scoreboards in Python.
"""

from __future__ import annotations

import numpy as np
from rasterhw.sim.engines.runner import build_dir_for, get_sim, run_cocotb
from rasterhw.sim.outfile import write_if_changed
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["run_cocotb_bench"]


def run_cocotb_bench(jb: dict, *, width: int = 512, sim: str | None = None, idle: float = 0.0,
                     stall: float = 0.0, seed: int = 1) -> dict:
    """Run the jobs ``jb`` (:func:`rasterhw.sim.experts.pxp_jobs.job_list`) under cocotb.

    Raises :class:`~rasterhw.golden_model.errors.RasterhwError` if the bench's checks fail
    (a pixel, a line's cycles, the stream rules, the order of transfers)."""
    from rasterhw.sim.engines.verilog_cache import generate_cached

    sim = get_sim(sim)
    text = generate_cached("experts-pxp", width=width, aj=jb["aj"])
    bdir = build_dir_for("experts-pxp-cocotb", sim, width=width, aj=jb["aj"])
    bdir.mkdir(parents=True, exist_ok=True)
    vpath = bdir / "experts_pxp.v"
    write_if_changed(vpath, text)
    run_dir = temp_run_folder(bdir)
    exp = run_dir / "expect.npz"
    np.savez(exp, words=np.array([f"{w:x}" for w in jb["words"]], dtype=str), pixels=jb["pixels"],
             cycles=jb["cycles"], lo0=jb["lo0"], hi0=jb["hi0"])
    timings: dict = {}
    # a failed run keeps its folder (the error names its sim.log); a passed one is removed
    run_cocotb(sources=[vpath], toplevel="experts_pxp", test_module="cocotb_tests.experts.test_pxp",
               build_dir=bdir, test_dir=run_dir, sim=sim, timings=timings,
               extra_env={"PXP_EXPECT": str(exp), "PXP_IDLE": str(idle), "PXP_STALL": str(stall),
                          "PXP_SEED": str(seed)})
    release(run_dir)
    return {"words": len(jb["words"]), "pixels": int(jb["pixels"].size), "lines": jb["lines"], **timings}
