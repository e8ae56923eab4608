"""Timing model of the paper's three machines -- the scalar unit, the FACOM VP100 (compiler
V10L10) and the VP200 (V10L20) -- pricing a :class:`~.trace.Trace`.

Every parameter is in :data:`PARAMS` with its source; ``chosen=True`` marks the ones no
published fact fixes (each gets a sensitivity row in the report: the conclusions at half and at
double the value). Nothing here is read from the paper's tables 2-7 (a test imports this module
with ``rasterhw.sim.vzbuf.paper`` blocked).

Model (one vector instruction per operation of a loop body per strip; no chaining or overlap
between pipelines):

* a loop of ``n`` iterations is strip-mined at the vector length ``VL`` =
  vector-register bytes / (8 bytes x registers in use); each strip costs ``strip_scalar``
  scalar instructions (loop control, VL set-up);
* a vector instruction over ``k`` elements takes ``startup + k * t_elem / m``, where ``t_elem``
  is one pipeline unit's element time (fp pipes at peak x multiplicity / peak rate) and ``m`` the
  multiplicity: the VP200 has twice the hardware of the VP100 (``m`` = 2 against 1) for
  arithmetic and memory access, but one mask pipeline on both (``compare``, ``compress``,
  ``reduce`` at ``m`` = 1); list-vector access (``gather``/``scatter``) runs at
  ``list_rate`` x the contiguous rate;
* V10L10 does not vectorise the gather/scatter procedures ("収集・拡散手続き"): on the VP100 a
  loop's ``compress`` part runs on the scalar unit (the loop is split), at the scalar cost;
* the scalar machine runs every loop one element at a time: per iteration
  ``loop_overhead`` + the body's scalar instruction counts (:data:`SCALAR_COST`), each
  instruction ``scalar_ns``; the parts the paper keeps scalar run at the same cost on all three.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from rasterhw.golden_model.vzbuf.trace import BODIES, Trace

__all__ = ["MACHINES", "PARAMS", "Param", "Timing", "price"]


@dataclass(frozen=True)
class Param:
    value: float
    unit: str
    source: str
    chosen: bool = False


#: every model parameter; docs/vzbuf.md lists the same with the full references
PARAMS: dict[str, Param] = {
    "peak_vp100": Param(250.0, "MFLOPS", "Fujitsu FACOM VP series: VP-100 250 MFLOPS peak (Fujitsu VP series "
                        "overview, grokipedia.com/page/fujitsu_vp, citing Fujitsu's history pages)"),
    "peak_vp200": Param(500.0, "MFLOPS", "same source: VP-200 500 MFLOPS peak"),
    "multiplicity_vp100": Param(1.0, "units", "VP100 = the base configuration (paper 4.1 2)(ii): the VP200 has "
                                "'ハードウェア量が2倍'; 250 vs 500 MFLOPS)"),
    "multiplicity_vp200": Param(2.0, "units", "paper 4.1 1)(ii), 2)(ii): 'ハードウェア量が2倍に増えた'"),
    "mask_pipes": Param(1.0, "pipelines", "paper 4.1 2)(ii): 'マスク・パイプラインが2本以上あれば、更に効率上がる' "
                        "(so one, not doubled on the VP200)"),
    "l10_gather_scatter": Param(0.0, "flag", "paper 3.2: V10L10 does not vectorise the 収集・拡散 procedures, "
                                "V10L20 does; 3.3 2) ②: update 2's VP100/VP200 gap is the vectorised 収集"),
    "element_bytes": Param(8.0, "bytes", "paper 3.1 e): '演算はすべて倍精度'"),
    "fp_pipes": Param(2.0, "pipelines", "chosen: peak = an add and a multiply pipeline at once (the VP series' "
                      "separate add/logical and multiply pipelines); sets t_elem = fp_pipes / peak", chosen=True),
    "vr_bytes": Param(65536.0, "bytes", "chosen within the published range: vector registers 32-128 KB across "
                      "the VP series, reconfigurable in length (netlib top500 report 1994, VP2000 entry: "
                      "'Just as in the former Fujitsu VP series (VPx00) the vector registers are not fixed "
                      "in length'); 64 KB for the VP-100/200", chosen=True),
    "vregs": Param(8.0, "registers", "chosen: registers a loop body keeps live (sets VL = vr_bytes / 8 / vregs)",
                   chosen=True),
    "startup_ns": Param(300.0, "ns", "chosen: no published per-instruction start-up of the VP100/VP200 was "
                        "found; 300 ns is a memory-to-register pipeline start-up of the period (a few tens "
                        "of element times)", chosen=True),
    "vp200_startup_factor": Param(1.0, "x VP100", "chosen: no published difference; the paper's conjecture "
                                  "('VP200の方がベクトル処理の準備時間が長く…と思われる', 4.1 1)(ii)) is what "
                                  "the model tests, so it is not built in", chosen=True),
    "list_rate": Param(0.5, "x contiguous", "chosen: list-vector (indirect) access at half the contiguous "
                       "rate; the paper asks for '強力なリストベクトル処理機能' (4.1 2)(iii)), no figure "
                       "published", chosen=True),
    "scalar_ns": Param(50.0, "ns / instruction", "chosen: an M-380-class scalar unit at ~20 MIPS; no "
                       "published instruction time of the VP's scalar unit was found", chosen=True),
    "strip_scalar": Param(6.0, "instructions / strip", "chosen: strip-mining loop control and VL set-up",
                          chosen=True),
    "loop_overhead": Param(3.0, "instructions / iteration", "counted: increment, compare, branch of a scalar "
                           "DO loop"),
}

#: scalar instructions per element operation on the scalar unit (counted from S/370-style code:
#: a list access is an index load + the access; a compare is compare + branch; a collect is
#: test, branch, store, increment)
SCALAR_COST = {"load": 1, "store": 1, "gather": 2, "scatter": 2, "masked_store": 1, "masked_scatter": 2,
               "arith": 1, "div": 1, "compare": 2, "compress": 4, "reduce": 2}

MASK_KINDS = ("compare", "compress", "reduce")
LIST_KINDS = ("gather", "scatter", "masked_scatter")


@dataclass(frozen=True)
class Timing:
    """One machine: its name and the parameters it reads (overrides for sensitivity runs)."""

    name: str
    vector: bool
    multiplicity: float = 1.0
    l20: bool = True
    startup_factor: float = 1.0


MACHINES = {
    "scalar": Timing("scalar", vector=False),
    "vp100": Timing("vp100", vector=True, multiplicity=PARAMS["multiplicity_vp100"].value,
                    l20=bool(PARAMS["l10_gather_scatter"].value)),
    "vp200": Timing("vp200", vector=True, multiplicity=PARAMS["multiplicity_vp200"].value, l20=True,
                    startup_factor=PARAMS["vp200_startup_factor"].value),
}


def _v(params: dict, name: str) -> float:
    return float(params[name].value if isinstance(params[name], Param) else params[name])


def price(trace: Trace, machine: str, *, params: dict | None = None, by: str = "phase") -> dict:
    """Seconds per trace phase on ``machine`` (``scalar``, ``vp100``, ``vp200``), with the
    vector-unit time and the scalar time of the vectorised part (for the paper's rate ④).

    Returns ``{"phases": {phase: s}, "vector": {phase: s}, "vectorised_scalar": {phase: s}}``;
    ``params`` overrides :data:`PARAMS` entries by name (sensitivity rows); ``by="body"`` keys
    the result by loop body (and scalar part) instead of phase.
    """
    if by not in ("phase", "body"):
        raise ValueError(f"facom: by must be phase or body, not {by!r}")
    if machine not in MACHINES:
        raise KeyError(f"facom: machine must be one of {', '.join(MACHINES)}, not {machine!r}")
    P = dict(PARAMS)
    if params:
        unknown = set(params) - set(P)
        if unknown:
            raise KeyError(f"facom: no parameter {sorted(unknown)[0]!r}")
        P.update(params)
    m = MACHINES[machine]
    if machine == "vp200":
        m = replace(m, startup_factor=_v(P, "vp200_startup_factor"), multiplicity=_v(P, "multiplicity_vp200"))
    elif machine == "vp100":
        m = replace(m, multiplicity=_v(P, "multiplicity_vp100"), l20=bool(_v(P, "l10_gather_scatter")))
    ts = _v(P, "scalar_ns") * 1e-9
    lo = _v(P, "loop_overhead")
    peak = _v(P, "peak_vp200" if machine == "vp200" else "peak_vp100") * 1e6
    mult = m.multiplicity
    t_unit = _v(P, "fp_pipes") * mult / peak          # one pipeline unit's element time
    vl = max(1, int(_v(P, "vr_bytes") // (_v(P, "element_bytes") * _v(P, "vregs"))))
    t0 = _v(P, "startup_ns") * 1e-9 * m.startup_factor
    strip_s = _v(P, "strip_scalar") * ts
    lrate = _v(P, "list_rate")
    mask_m = _v(P, "mask_pipes")
    phases: dict[str, float] = {}
    vec: dict[str, float] = {}
    vsc: dict[str, float] = {}
    for (ph0, body, n), times in trace.loops.items():
        ph = ph0 if by == "phase" else body
        ops = BODIES[body]
        sc_iter = lo + sum(c * SCALAR_COST[k] for k, _w, c in ops)
        if not m.vector:
            phases[ph] = phases.get(ph, 0.0) + times * n * sc_iter * ts
            continue
        strips = -(-n // vl)
        t_v = 0.0
        t_s = strips * strip_s
        vectorised_sc = n * lo * ts
        for k, _w, c in ops:
            if k == "compress" and not m.l20:
                t_s += n * c * SCALAR_COST[k] * ts          # split off, run on the scalar unit
                continue
            vectorised_sc += n * c * SCALAR_COST[k] * ts
            if k in MASK_KINDS:
                per = t_unit / mask_m if mask_m else t_unit
            elif k in LIST_KINDS:
                per = t_unit / lrate / mult
            else:
                per = t_unit / mult
            t_v += c * (strips * t0 + n * per)
        phases[ph] = phases.get(ph, 0.0) + times * (t_v + t_s)
        vec[ph] = vec.get(ph, 0.0) + times * t_v
        vsc[ph] = vsc.get(ph, 0.0) + times * vectorised_sc
    for (ph0, what), k in trace.scalars.items():
        ph = ph0 if by == "phase" else what
        phases[ph] = phases.get(ph, 0.0) + k * ts
    return {"phases": phases, "vector": vec, "vectorised_scalar": vsc}
