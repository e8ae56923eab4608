"""Timing model of the paper's three machines -- the scalar unit, the FACOM VP100 (compiler
V10L10) and the VP200 (V10L20) -- pricing a :class:`~.trace.Trace` operation by operation, by
the operation's kind and its element width.

Every parameter is in :data:`PARAMS` with its source and its bounds (:func:`bounds`: from a
published fact where one was found, else chosen and marked); ``chosen=True`` marks the values no
published fact fixes (each gets a sensitivity row in the report: the conclusions at half and at
double the value). Nothing here is read from the paper's tables 2-7 (a test imports this module
with ``rasterhw.golden_model.vzbuf.paper`` blocked).

Scalar unit (the scalar column, and the scalar part of both VPs): every operation runs one at a
time, its time the functional-unit time of an X-MP-class scalar unit in clock periods
(:func:`scalar_cp`) times ``scalar_clock_ns``. Lubeck, Moore and Mendez (Los Alamos benchmark
of the VP-200, S810/20 and X-MP/24) found the VP-200's scalar timings within 30 % of the
X-MP/24's, so the VP's scalar clock is bounded by the X-MP's +-30 % (:func:`bounds`):

* integer (4-byte) add 2, multiply 6 clock periods (Cray-1 hardware reference manual 2240004,
  p. 3-11, address add and multiply units); floating (8-byte) divide 29 (p. 3-30: "A scalar
  quotient is computed in 29 clock periods"); floating add ``cp_fadd``, multiply ``cp_fmul``,
  a memory access ``cp_mem``, a taken branch ``cp_branch``: chosen;
* a load or store of ``w`` bytes moves ``ceil(w / 8)`` words; a list access adds the index
  load; a compare is a subtract and a branch; a collect is a branch, a store and an increment;
  a scalar DO loop pays an increment, a compare and a branch per iteration.

Vector units (one vector instruction per operation of a loop body per strip; no chaining or
overlap between pipelines): a loop of ``n`` iterations is strip-mined at ``VL`` = vector-register
bytes / (8 bytes x registers in use), each strip costing ``strip_cp`` scalar clock periods; an
instruction over ``k`` elements takes ``startup + k * t``, where, with ``t_unit`` = one
pipeline unit's element time (``fp_pipes`` / peak x multiplicity) and ``m`` the multiplicity
(VP100 1, VP200 2: "ハードウェア量が2倍"):

* ``add``, ``mul``: ``t_unit / m``; ``div``: ``vdiv_factor`` x that;
* ``load``/``store``/``masked_store``: ``t_unit / m`` per 8-byte word, ``i4_access_factor`` x
  that for a 4-byte element (the paper: "4バイトデータに対する配慮は余りなされていない");
  ``gather``/``scatter``/``masked_scatter``: that / ``list_rate``;
* ``compare``, ``compress``, ``reduce``: the one mask pipeline, ``t_unit`` on both machines;
* V10L10 does not vectorise the gather/scatter procedures ("収集・拡散手続き"): on the VP100 a
  loop's ``compress`` runs on the scalar unit (the loop is split), at the scalar price.

Every price is linear in ``scalar_clock_ns`` (scalar), ``startup_ns`` (start-ups) and
``fp_pipes`` (element times): :func:`components` splits a priced trace so (the calibration of
``sim/vzbuf/calibrate.py`` uses it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rasterhw.golden_model.vzbuf.trace import BODIES, SCALAR_BODIES, Trace

__all__ = ["MACHINES", "PARAMS", "Param", "bounds", "components", "length10_ratio", "out_of_bounds", "price",
           "scalar_cp", "vector_element_ns"]


@dataclass(frozen=True)
class Param:
    value: float
    unit: str
    source: str
    chosen: bool = False


LUBECK = ("Lubeck, Moore, Mendez, 'A performance evaluation of three supercomputers: Fujitsu VP-200, "
          "Hitachi S810/20 and Cray X-MP/24', Applied Mathematics and Computation (Los Alamos benchmark), "
          "abstract: 'Scalar timings differed by, at most, 30 percent'; 'The VP-200 and CRAY X-MP performed "
          "equally on short vectors (vector length 10)'")
CRAY1_HRM = "Cray-1 hardware reference manual 2240004"

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
    "fp_pipes": Param(2.0, "pipelines", "chosen: peak = an add and a multiply pipeline at once (the VP series' "
                      "separate add/logical and multiply pipelines); sets t_unit = fp_pipes / peak", chosen=True),
    "vr_bytes": Param(65536.0, "bytes", "chosen within the published range: vector registers 32-128 KB across "
                      "the VP series, reconfigurable in length (netlib top500 report 1994, VP2000 entry: "
                      "'Just as in the former Fujitsu VP series (VPx00) the vector registers are not fixed "
                      "in length'); 64 KB for the VP-100/200", chosen=True),
    "vregs": Param(8.0, "registers", "chosen: registers a loop body keeps live (sets VL = vr_bytes / 8 / vregs)",
                   chosen=True),
    "startup_ns": Param(150.0, "ns", "chosen inside the bound the published length-10 equality of the VP-200 and "
                        "the X-MP gives (bounds(); " + LUBECK + "); no per-instruction start-up of the VP was "
                        "found", chosen=True),
    "vp200_startup_factor": Param(1.0, "x VP100", "chosen: no published difference; the paper's conjecture "
                                  "('VP200の方がベクトル処理の準備時間が長く…と思われる', 4.1 1)(ii)) is what "
                                  "the model tests, so it is not built in", chosen=True),
    "list_rate": Param(0.5, "x contiguous", "chosen: list-vector (indirect) access at half the contiguous "
                       "rate; the paper asks for '強力なリストベクトル処理機能' (4.1 2)(iii)), no figure "
                       "published", chosen=True),
    "vdiv_factor": Param(3.0, "x an add", "chosen: a vector divide takes three element times, the Cray-1's "
                         f"({CRAY1_HRM}, p. 3-30: 'A vector quotient requires effectively three vector "
                         "times'); no VP figure found", chosen=True),
    "i4_access_factor": Param(1.0, "x an 8-byte element", "chosen: a 4-byte element takes an 8-byte element's "
                              "memory slot (paper 2.3.1 2): 'ベクトル計算機は倍精度の浮動小数点数の演算を高速に"
                              "実行することを目的に設計されているため、4バイトデータに対する配慮は余りなされて"
                              "いない'); no VP figure found", chosen=True),
    "scalar_clock_ns": Param(9.5, "ns / clock period", "chosen: the VP's scalar unit priced in X-MP clock "
                             "periods at the X-MP's 9.5 ns (the X-MP's clock was not found in the library; the "
                             "Cray-1's 12.5 ns was: 'The Cray-1 Computer System' (1977), 'a 12.5 nanosecond "
                             "clock period'); bounded by " + LUBECK.split(", abstract")[0] + ": 'Scalar timings "
                             "differed by, at most, 30 percent'", chosen=True),
    "cp_iadd": Param(2.0, "clock periods", f"{CRAY1_HRM}, p. 3-11: address add unit, 'The functional unit time "
                     "is two clock periods'"),
    "cp_imul": Param(6.0, "clock periods", f"{CRAY1_HRM}, p. 3-11: address multiply unit, 'six clock periods'"),
    "cp_fdiv": Param(29.0, "clock periods", f"{CRAY1_HRM}, p. 3-30: 'A scalar quotient is computed in 29 clock "
                     "periods'"),
    "cp_fadd": Param(6.0, "clock periods", "chosen: a floating add of a Cray-class scalar unit (the Cray-1's "
                     "floating add unit time was not found in the library)", chosen=True),
    "cp_fmul": Param(7.0, "clock periods", "chosen: a floating multiply of a Cray-class scalar unit (not found "
                     "in the library)", chosen=True),
    "cp_mem": Param(11.0, "clock periods", "chosen: one scalar memory access (load or store) of the period, "
                    "run serially; no figure found", chosen=True),
    "cp_branch": Param(5.0, "clock periods", "chosen: a taken conditional branch; no figure found", chosen=True),
    "strip_cp": Param(20.0, "clock periods / strip", "chosen: strip-mining loop control and VL set-up on the "
                      "scalar unit", chosen=True),
}

#: the X-MP reference the published facts compare with: its clock (chosen, see scalar_clock_ns)
#: and its vector instruction, (functional-unit time + n) clock periods (one result per clock
#: once started; Cray-1 HRM: 'each can start an operation on a new pair of input operands in each
#: successive clock period', cited via homepages.inf.ed.ac.uk/rni/comp-arch/Vect/cray1-units.html)
XMP_CLOCK_NS = 9.5
#: the reference loop of the length-10 comparison: an elementary vector operation of the Los
#: Alamos set, V = S x V + V (two loads, a multiply, an add, a store)
LENGTH10_BODY = (("load", 8, 2), ("mul", 8, 1), ("add", 8, 1), ("store", 8, 1))
#: "equal" read as within the 30 % the same abstract uses for scalar timings (chosen)
TOLERANCE = 1.3

MASK_KINDS = ("compare", "compress", "reduce")
LIST_KINDS = ("gather", "scatter", "masked_scatter")
MEM_KINDS = ("load", "store", "masked_store", *LIST_KINDS)


@dataclass(frozen=True)
class Timing:
    """One machine: its name, whether it has a vector unit, and which parameters it reads."""

    name: str
    vector: bool
    peak: str = ""
    multiplicity: str = ""
    l20: bool = True


MACHINES = {
    "scalar": Timing("scalar", vector=False),
    "vp100": Timing("vp100", vector=True, peak="peak_vp100", multiplicity="multiplicity_vp100", l20=False),
    "vp200": Timing("vp200", vector=True, peak="peak_vp200", multiplicity="multiplicity_vp200"),
}


def _params(params: dict | None) -> dict[str, float]:
    P = {k: p.value for k, p in PARAMS.items()}
    if params:
        unknown = set(params) - set(P)
        if unknown:
            raise KeyError(f"facom: no parameter {sorted(unknown)[0]!r}")
        P.update({k: float(v.value if isinstance(v, Param) else v) for k, v in params.items()})
    return P


def _words(w: int) -> int:
    return max(1, math.ceil(w / 8))


def scalar_cp(kind: str, width: int, params: dict | None = None) -> float:
    """Clock periods of one operation of ``kind`` on ``width``-byte elements on the scalar unit
    (see the module docstring)."""
    P = _params(params)
    mem = P["cp_mem"] * _words(width)
    idx = P["cp_mem"]                                  # the 4-byte index of a list access
    if kind in ("add", "mul", "div"):
        table = ({"add": P["cp_iadd"], "mul": P["cp_imul"], "div": P["cp_fdiv"]} if width <= 4 else
                 {"add": P["cp_fadd"], "mul": P["cp_fmul"], "div": P["cp_fdiv"]})
        return table[kind] * _words(width)
    cost = {"load": mem, "store": mem, "gather": idx + mem, "scatter": idx + mem,
            "masked_store": P["cp_branch"] + mem, "masked_scatter": P["cp_branch"] + idx + mem,
            "compare": scalar_cp("add", width, P) + P["cp_branch"],
            "compress": P["cp_branch"] + P["cp_mem"] + P["cp_iadd"],
            "reduce": scalar_cp("add", width, P) + P["cp_branch"]}
    if kind not in cost:
        raise KeyError(f"facom: no operation kind {kind!r}")
    return cost[kind]


def _loop_cp(P) -> float:
    """A scalar DO loop's own work per iteration: increment, compare, branch (counted)."""
    return 2 * P["cp_iadd"] + P["cp_branch"]


def vector_element_ns(kind: str, width: int, machine: str, params: dict | None = None) -> float:
    """ns per element of one vector instruction of ``kind`` on ``width``-byte elements (start-up
    not included)."""
    P = _params(params)
    m = MACHINES[machine]
    if not m.vector:
        raise ValueError(f"facom: {machine} has no vector unit")
    mult = P[m.multiplicity]
    t_unit = P["fp_pipes"] * mult / (P[m.peak] * 1e6) * 1e9
    per = t_unit / mult
    if kind in MASK_KINDS:
        return t_unit / P["mask_pipes"]
    if kind in ("add", "mul"):
        return per
    if kind == "div":
        return per * P["vdiv_factor"]
    if kind in MEM_KINDS:
        t = per * (P["i4_access_factor"] if width < 8 else width / 8)
        return t / P["list_rate"] if kind in LIST_KINDS else t
    raise KeyError(f"facom: no operation kind {kind!r}")


def _startup_ns(P, machine: str) -> float:
    return P["startup_ns"] * (P["vp200_startup_factor"] if machine == "vp200" else 1.0)


def price(trace: Trace, machine: str, *, params: dict | None = None, by: str = "phase") -> dict:
    """Seconds per trace phase on ``machine`` (``scalar``, ``vp100``, ``vp200``), with the
    vector-unit time and the scalar time of the vectorised part (for the paper's rate ④).

    Returns ``{"phases": {phase: s}, "vector": {phase: s}, "vectorised_scalar": {phase: s}}``;
    ``params`` overrides :data:`PARAMS` entries by name (sensitivity rows, calibration);
    ``by="body"`` keys the result by loop body (and scalar body) instead of phase.
    """
    if by not in ("phase", "body"):
        raise ValueError(f"facom: by must be phase or body, not {by!r}")
    if machine not in MACHINES:
        raise KeyError(f"facom: machine must be one of {', '.join(MACHINES)}, not {machine!r}")
    P = _params(params)
    m = MACHINES[machine]
    ts = P["scalar_clock_ns"] * 1e-9
    lo = _loop_cp(P)
    sc_cp = {}
    phases: dict[str, float] = {}
    vec: dict[str, float] = {}
    vsc: dict[str, float] = {}
    if m.vector:
        vl = max(1, int(P["vr_bytes"] // (8 * P["vregs"])))
        t0 = _startup_ns(P, machine) * 1e-9
        strip_s = P["strip_cp"] * ts
        el = {}
    for (ph0, body, n), times in trace.loops.items():
        ph = ph0 if by == "phase" else body
        ops = BODIES[body]
        if body not in sc_cp:
            sc_cp[body] = [scalar_cp(k, w, P) for k, w, _c in ops]
        cps = sc_cp[body]
        if not m.vector:
            per_iter = lo + sum(c * cp for (_k, _w, c), cp in zip(ops, cps, strict=True))
            phases[ph] = phases.get(ph, 0.0) + times * n * per_iter * ts
            continue
        strips = -(-n // vl)
        t_v = 0.0
        t_s = strips * strip_s
        vectorised_sc = n * lo * ts
        for (k, w, c), cp in zip(ops, cps, strict=True):
            if k == "compress" and not m.l20:
                t_s += n * c * cp * ts          # split off, run on the scalar unit
                continue
            vectorised_sc += n * c * cp * ts
            if (k, w) not in el:
                el[(k, w)] = vector_element_ns(k, w, machine, P) * 1e-9
            t_v += c * (strips * t0 + n * el[(k, w)])
        phases[ph] = phases.get(ph, 0.0) + times * (t_v + t_s)
        vec[ph] = vec.get(ph, 0.0) + times * t_v
        vsc[ph] = vsc.get(ph, 0.0) + times * vectorised_sc
    for (ph0, what), units in trace.scalars.items():
        ph = ph0 if by == "phase" else what
        cp = sum(c * scalar_cp(k, w, P) for k, w, c in SCALAR_BODIES[what])
        phases[ph] = phases.get(ph, 0.0) + units * cp * ts
    return {"phases": phases, "vector": vec, "vectorised_scalar": vsc}


#: the three parameters every price is linear in (see :func:`components`)
LINEAR = ("scalar_clock_ns", "startup_ns", "fp_pipes")


def components(trace: Trace, machine: str, params: dict | None = None) -> dict[str, dict[str, float]]:
    """``price(...)["phases"]`` split into the parts proportional to each of :data:`LINEAR`
    at value 1 (the others at 0): ``price`` = sum of ``value x component`` exactly."""
    base = dict(params or {})
    out = {}
    for name in LINEAR:
        p = {**base, **{k: (1.0 if k == name else 0.0) for k in LINEAR}}
        out[name] = price(trace, machine, params=p)["phases"]
    return out


def _xmp_ns(body, n: int, P) -> float:
    return sum(c * (scalar_cp(k, w, P) + n) * XMP_CLOCK_NS for k, w, c in body)


def length10_ratio(params: dict | None = None, machine: str = "vp200", n: int = 10) -> float:
    """VP time / X-MP time of :data:`LENGTH10_BODY` at vector length ``n`` (one strip; no chaining
    on either machine)."""
    P = _params(params)
    vp = sum(c * (_startup_ns(P, machine) + n * vector_element_ns(k, w, machine, P)) for k, w, c in LENGTH10_BODY)
    return vp / _xmp_ns(LENGTH10_BODY, n, P)


#: bounds no published fact sets: (low, high)
CHOSEN_BOUNDS = {"vp200_startup_factor": (0.5, 2.0), "fp_pipes": (1.0, 4.0), "vregs": (4.0, 16.0),
                 "list_rate": (0.25, 1.0), "cp_fadd": (3.0, 14.0), "cp_fmul": (3.0, 14.0), "cp_mem": (2.0, 20.0),
                 "cp_branch": (1.0, 14.0), "strip_cp": (5.0, 60.0)}


def bounds(params: dict | None = None) -> dict[str, tuple[float, float, str]]:
    """Each bounded parameter -> ``(low, high, where the bound comes from)``; ``published`` in
    the text when a published fact sets it, ``chosen`` otherwise. A test fails when a parameter
    leaves its bounds."""
    P = _params(params)
    # the VP-200 start-up at which the length-10 loop takes 1/1.3 and 1.3 x the X-MP's
    xmp = _xmp_ns(LENGTH10_BODY, 10, P)
    ops = sum(c for _k, _w, c in LENGTH10_BODY)
    work = sum(c * 10 * vector_element_ns(k, w, "vp200", P) for k, w, c in LENGTH10_BODY)
    f = P["vp200_startup_factor"]
    s_lo, s_hi = (max(0.0, (xmp / TOLERANCE - work) / ops) / f, (xmp * TOLERANCE - work) / ops / f)
    return {
        "scalar_clock_ns": (XMP_CLOCK_NS / TOLERANCE, 12.5 * TOLERANCE,
                            "published (30 %: Lubeck et al.) around a chosen X-MP clock of 9.5 ns up to the "
                            "Cray-1's published 12.5 ns"),
        "startup_ns": (s_lo, s_hi, "published: the VP-200 within 30 % of the X-MP on a length-10 vector loop "
                       "(Lubeck et al.), the X-MP priced at (functional-unit time + n) clock periods"),
        "vr_bytes": (32768.0, 131072.0, "published range of the VP series (netlib top500 report 1994)"),
        "vdiv_factor": (1.0, 8.0, "chosen, around the Cray-1's published 3"),
        "i4_access_factor": (0.5, 2.0, "chosen: packed 4-byte access (0.5) to a bank conflict per pair (2)"),
        **{k: (lo, hi, "chosen") for k, (lo, hi) in CHOSEN_BOUNDS.items()},
    }


def out_of_bounds(params: dict | None = None) -> list[str]:
    """The parameters (with ``params`` applied) that leave their :func:`bounds`, as
    ``"name = value outside [low, high] (source)"``; empty when every one is inside."""
    P = _params(params)
    return [f"{k} = {P[k]:g} outside [{lo:g}, {hi:g}] ({why})" for k, (lo, hi, why) in bounds(params).items()
            if not lo <= P[k] <= hi]
