"""The sparse video processor's generated Verilog on plain Verilator (no cocotb, no ``--timing``).

One build serves every processor of the matrix (its index ``(a, b)`` is an input): the bench
``sim/sparse/verilator/tb_sparse_vp.v`` plays the broadcast records from a hex file with no gaps,
waits until the processor is idle and dumps its local memory and per-level counters; the C++
main (``cocotb_tests/plain_main.cpp``) toggles the clock and times that loop. Builds go to
``build/sparse-vp-<hash>/`` (hash of the Verilog, parameters and bench sources), so the second
call with the same parameters only runs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse.formats import TRI_BITS
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.engines.runner import build_plain_verilator, run_plain_verilator
from rasterhw.sim.workdirs import release, temp_run_folder

__all__ = ["build", "pack_records", "run_processor_verilator"]

BENCH_DIR = Path(__file__).resolve().parent / "verilator"
#: what ``tb_sparse_vp.v`` and ``tb_sparse_matrix.v`` share (handed to both builds: their bytes key them)
SHARED_VH = ("tb_sparse_load.vh", "tb_sparse_readout.vh")
TOP = "tb_sparse_vp"
MAXT = 16384


_BUILT: dict = {}


def build(*, n: int, p: int, q: int, z_bits: int = 24) -> tuple[Path, float]:
    """Build once per parameter set; returns ``(binary, build seconds or 0 if reused)``."""
    key = (n, p, q, z_bits)
    if key in _BUILT and _BUILT[key].exists():
        return _BUILT[key], 0.0
    exe, secs = _build(n=n, p=p, q=q, z_bits=z_bits)
    _BUILT[key] = exe
    return exe, secs


def _build(*, n: int, p: int, q: int, z_bits: int) -> tuple[Path, float]:
    from rasterhw.hdl.sparse.layouts import BROADCAST
    from rasterhw.hdl.sparse.vp import make_vp
    from rasterhw.sim.engines.verilog_cache import convert_cached

    src = convert_cached("sparse-vp", lambda: make_vp(n=n, p=p, q=q, z_bits=z_bits),
                         params={"n": n, "p": p, "q": q, "z_bits": z_bits}, module="sparse_vp")
    params = {"N": n, "BW": BROADCAST.size, "MAXT": MAXT, "ZW": z_bits + 1, "TW": TRI_BITS}
    ports = "".join(f"  , .tests_{i + 1}(tests_v[{32 * i + 31}:{32 * i}]), .stalls_{i + 1}(stalls_v[{32 * i + 31}:{32 * i}])\n"
                    for i in range(n))
    return build_plain_verilator("sparse-vp", TOP, [BENCH_DIR / "tb_sparse_vp.v"], params=params,
                                 defines={"RASTERHW_CYCLES": 1},
                                 generated={"sparse_vp.v": src, "tb_sparse_vp_ports.vh": ports,
                                            **{f: (BENCH_DIR / f).read_text() for f in SHARED_VH}})


def _read_hex(path: Path) -> np.ndarray:
    words = [w for w in path.read_text().split() if not w.startswith("//")]
    return np.array([int(w, 16) for w in words], dtype=object)


def pack_records(recs: list[dict], *, colour: bool = False) -> bytes:
    """The bench's stimulus file: one big-endian word of the BROADCAST layout (``BROADCAST_RGB``
    with ``colour``) per triangle (``ceil(size / 8)`` bytes, read with ``$fread``)."""
    from rasterhw.hdl.pack import pack
    from rasterhw.hdl.sparse.layouts import layouts

    lay = layouts(colour)[0]
    nbytes = -(-lay.size // 8)
    return b"".join(pack(lay, r).to_bytes(nbytes, "big") for r in recs)


def run_processor_verilator(recs: list[dict], *, n: int, p: int, q: int, a: int, b: int, z_bits: int = 24,
                            packed: bytes | None = None, idle: int = 0, seed: int = 1) -> dict:
    """One processor on Verilator: the same keys as :func:`rasterhw.sim.sparse.hdl_run.run_processor`
    plus ``run_s`` (the C++ clock loop) and ``build_s``. ``packed``: :func:`pack_records` of ``recs``
    when the caller runs several processors on the same records. ``idle`` (0..255): random idle
    clocks on the input (a record is offered when a seeded 8-bit random number is >= ``idle``);
    the frame and the per-level tests do not depend on it, the cycle count does."""
    if not (isinstance(idle, int) and 0 <= idle <= 255):
        raise RasterhwError(f"sparse verilator bench: idle must be an integer in 0..255, not {idle!r}")
    if len(recs) > MAXT:
        raise RasterhwError(f"sparse verilator bench holds at most {MAXT} triangles, not {len(recs)}")
    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse HDL: processor ({a}, {b}) is outside a {p}x{q} matrix")
    exe, build_s = build(n=n, p=p, q=q, z_bits=z_bits)
    run_dir = temp_run_folder(exe.parent.parent)
    (run_dir / "in.bin").write_bytes(pack_records(recs) if packed is None else packed)
    N = 1 << n
    maxcyc = (200 * (len(recs) + 10) * (1 + n) + 64 * N * N + 10_000_000) * (1 + idle // 16)
    meta = run_plain_verilator(exe, [f"+in={run_dir / 'in.bin'}", f"+out={run_dir / 'out.hex'}",
                                     f"+stats={run_dir / 'stats.hex'}", f"+ntri={len(recs)}", f"+a={a}", f"+b={b}",
                                     f"+idle={idle}", f"+seed={seed}"],
                               run_dir=run_dir, maxcyc=maxcyc)
    b_out = read_memh(run_dir / "out.hex", N * N)
    st = [int(v) for v in _read_hex(run_dir / "stats.hex")]
    release(run_dir)
    if b_out.shape[1] > 8:
        raise RasterhwError(f"sparse bench: {b_out.shape[1]}-byte memory words, expected at most 8")
    words = memh_uint64(b_out, 0, b_out.shape[1]).astype(np.int64)
    tri = words >> (z_bits + 1)
    zq = words & ((1 << (z_bits + 1)) - 1)
    empty = tri == (1 << TRI_BITS) - 1
    tri[empty], zq[empty] = -1, -1
    return {"tri": tri.reshape(N, N), "zq": zq.reshape(N, N), "tests": st[:n], "stalls": st[n:2 * n],
            "cycles": st[2 * n], "writes": st[2 * n + 1], "sim_cycles": meta["sim_cycles"], "run_s": meta["run_s"],
            "build_s": build_s}
