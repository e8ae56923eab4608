"""The paper's window-count and timing theory, formulas (1)-(12) of seed 002, as functions.

Formula (1) is damaged in the OCR ("w,(S) < = - "Sipq)-' + Т - "Di{а] + libKS(pq)-' + «, А, d )").
Our reconstruction (see ``docs/sparse.md`` for the arithmetic that checks it)::

    w_i(S) <= 2**(-2(n-i)) * S/(pq) + 2**(-(n-i)) * L * sqrt((alpha_i**2 + beta_i**2) * pi * S/(pq))
              + alpha_i * beta_i                                                            (1)

    alpha_i = 1 + 2**(i-n) * (alpha/p - 1),  beta_i = 1 + 2**(i-n) * (beta/q - 1)          (2)

At ``i = n`` it is (3), ``w_n <= [S + L*sqrt((alpha**2 q/p + beta**2 p/q) pi S) + alpha*beta]/(pq)``,
and ``w_n = 1`` with ``p = q``, ``alpha = beta`` gives (4),
``S_k + alpha*L*sqrt(2*pi*S_k) + alpha**2 = 4**k``. ``L = perimeter / (2*sqrt(pi*S))`` (1 for a
disc, 1.514 for a 5:1 rectangle).

Timing (τ = time of one coverage test, ``kp/ke`` parameters per edge; the root ``w_0 = 1``)::

    t_i = tau * [4 w_(i-1) + w_i kp/ke]                  (5)     T = sum_i t_i              (6)
    Q_a = T_so / (pq T_s)                                (7)     = P_s / (pq P_so)          (8)
    P_p = 1 / (tau * max_i [4 w_(i-1) + w_i kp/ke])      (9)
    R_p = sum_i t_i / (n max_i t_i) = P_p / (n P_s)      (10)
    Q_p = Q_a * R_p                                      (11), (12)
    P_max = 0.2 / tau  (five coverage tests),  p_s = P_s / P_max,  p_p = P_p / P_max

``T_so`` is the monoprocessor (``p = q = 1``) on the full ``p*2**n x q*2**n`` raster, i.e.
``n + log2(p)`` levels; the formulas are the paper's bounds used as values, as the paper does.
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse.paper import (
    PAPER_S_K,  # the crossing areas S_1..S_4, with the quote
)

__all__ = [
    "L_RECT_5_1",
    "PAPER_S_K",
    "alpha_i",
    "efficiency_pipeline",
    "load_pipeline",
    "perf_pipeline",
    "perf_stack",
    "q_algorithm",
    "s_k",
    "s_k_quadratic",
    "shape_coefficient",
    "stage_times",
    "summary",
    "total_time",
    "windows",
]



def shape_coefficient(perimeter: float, area: float) -> float:
    """``L = perimeter / (2 sqrt(pi S))``: 1 for a disc."""
    return perimeter / (2.0 * math.sqrt(math.pi * area))


#: L of a 5:1 rectangle: 12 / (2 sqrt(5 pi)) = 1.5139
L_RECT_5_1 = shape_coefficient(12.0, 5.0)


def _check(n: int, p: int, q: int, alpha: float, beta: float) -> None:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise RasterhwError(f"sparse theory: n must be an integer >= 1, not {n!r}")
    for name, v in (("p", p), ("q", q)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1 or v & (v - 1):
            raise RasterhwError(f"sparse theory: {name} must be a power of two >= 1, not {v!r}")
    if not (alpha > 0 and beta > 0):
        raise RasterhwError(f"sparse theory: the aperture must be positive, not {alpha} x {beta}")


def alpha_i(i, n: int, p: int, alpha: float = 2.0) -> np.ndarray:
    """Relative window size (2): ``1 + 2**(i-n) (alpha/p - 1)``."""
    i = np.asarray(i, dtype=np.float64)
    return 1.0 + 2.0 ** (i - n) * (alpha / p - 1.0)


def windows(S, n: int, p: int, q: int | None = None, *, alpha: float = 2.0, beta: float | None = None,
            L: float = L_RECT_5_1) -> np.ndarray:
    """Formula (1): windows per level, shape ``(n + 1,) + shape(S)``; row 0 is the root ``w_0 = 1``."""
    q = p if q is None else q
    beta = alpha if beta is None else beta
    _check(n, p, q, alpha, beta)
    S = np.asarray(S, dtype=np.float64)
    if np.any(S < 0):
        raise RasterhwError("sparse theory: areas must be >= 0")
    out = np.empty((n + 1,) + S.shape)
    out[0] = 1.0
    for i in range(1, n + 1):
        ai, bi = alpha_i(i, n, p, alpha), alpha_i(i, n, q, beta)
        out[i] = (4.0 ** (i - n) * S / (p * q) + 2.0 ** (i - n) * L * np.sqrt((ai ** 2 + bi ** 2) * math.pi * S / (p * q))
                  + ai * bi)
    return out


def stage_times(w: np.ndarray, *, kp_ke: float = 1.0, tau: float = 1.0) -> np.ndarray:
    """(5): ``t_i = tau [4 w_(i-1) + w_i kp/ke]`` for i = 1..n from windows ``w`` (row 0 = root)."""
    w = np.asarray(w, dtype=np.float64)
    return tau * (4.0 * w[:-1] + w[1:] * kp_ke)


def total_time(w, **kw) -> np.ndarray:
    """(6): ``T = sum_i t_i``."""
    return stage_times(w, **kw).sum(axis=0)


def perf_stack(w, *, tau: float = 1.0, kp_ke: float = 1.0) -> np.ndarray:
    """``p_s = P_s / P_max`` with ``P_s = 1/T`` and ``P_max = 0.2/tau`` (fig. 5a)."""
    return (1.0 / total_time(w, tau=tau, kp_ke=kp_ke)) / (0.2 / tau)


def perf_pipeline(w, *, tau: float = 1.0, kp_ke: float = 1.0) -> np.ndarray:
    """(9) relative: ``p_p = P_p / P_max`` with ``P_p = 1/max_i t_i`` (fig. 6a)."""
    return (1.0 / stage_times(w, tau=tau, kp_ke=kp_ke).max(axis=0)) / (0.2 / tau)


def load_pipeline(w, *, kp_ke: float = 1.0) -> np.ndarray:
    """(10): ``R_p = sum_i t_i / (n max_i t_i)`` (fig. 6b, solid)."""
    t = stage_times(w, kp_ke=kp_ke)
    return t.sum(axis=0) / (t.shape[0] * t.max(axis=0))


def limiting_level(w, *, kp_ke: float = 1.0) -> np.ndarray:
    """The level ``i`` (1..n) whose stage time is largest: it sets ``P_p``."""
    return stage_times(w, kp_ke=kp_ke).argmax(axis=0) + 1


def q_algorithm(S, m: int, k: int, *, alpha: float = 2.0, L: float = L_RECT_5_1, kp_ke: float = 1.0) -> np.ndarray:
    """(7): ``Q_a = T_so / (pq T_s)`` for a ``2**k x 2**k`` matrix on a ``2**m x 2**m`` raster (fig. 5b)."""
    p = 1 << k
    Ts = total_time(windows(S, m - k, p, alpha=alpha, L=L), kp_ke=kp_ke)
    Tso = total_time(windows(S, m, 1, alpha=alpha, L=L), kp_ke=kp_ke)
    return Tso / (p * p * Ts)


def efficiency_pipeline(S, m: int, k: int, **kw) -> np.ndarray:
    """(12): ``Q_p = Q_a R_p`` (fig. 6b, dashed)."""
    p = 1 << k
    w = windows(S, m - k, p, alpha=kw.get("alpha", 2.0), L=kw.get("L", L_RECT_5_1))
    return q_algorithm(S, m, k, **kw) * load_pipeline(w, kp_ke=kw.get("kp_ke", 1.0))


def s_k(k: int, *, m: int = 10, alpha: float = 2.0, L: float = L_RECT_5_1, wfun=None, hi: float = 1e6) -> float:
    """The area where the pixel-level count per processor is 1, ``w_n(S_k) = 1``, by bisection.

    ``wfun(S) -> w_n`` defaults to formula (1) at ``i = n`` for ``p = q = 2**k``, ``n = m - k``.
    Returns 0 when ``w_n(0) >= 1`` already.
    """
    p = 1 << k
    n = m - k
    if wfun is None:
        def wfun(S):
            return float(windows(S, n, p, alpha=alpha, L=L)[n])
    if wfun(0.0) >= 1.0:
        return 0.0
    lo, h = 0.0, hi
    if wfun(h) < 1.0:
        raise RasterhwError(f"sparse theory: w_n stays below 1 up to S = {hi:g}")
    for _ in range(200):
        mid = 0.5 * (lo + h)
        if wfun(mid) < 1.0:
            lo = mid
        else:
            h = mid
        if h - lo < 1e-12 * max(1.0, h):
            break
    return 0.5 * (lo + h)


def s_k_quadratic(k: int, *, alpha: float = 2.0, L: float = L_RECT_5_1) -> float:
    """(4) solved as a quadratic in ``x = sqrt(S_k)``: ``x**2 + alpha L sqrt(2 pi) x + alpha**2 - 4**k = 0``."""
    b = alpha * L * math.sqrt(2.0 * math.pi)
    c = alpha ** 2 - 4.0 ** k
    x = (-b + math.sqrt(b * b - 4.0 * c)) / 2.0
    return max(x, 0.0) ** 2


def summary(S: float, m: int, k: int, **kw) -> dict:
    """Every figure quantity of the formula at one area: windows, stage times, p_s, Q_a, p_p, R_p, Q_p."""
    p = 1 << k
    w = windows(S, m - k, p, alpha=kw.get("alpha", 2.0), L=kw.get("L", L_RECT_5_1))
    kp_ke = kw.get("kp_ke", 1.0)
    return {"w": w, "t": stage_times(w, kp_ke=kp_ke), "p_s": float(perf_stack(w, kp_ke=kp_ke)),
            "Q_a": float(q_algorithm(S, m, k, **kw)), "p_p": float(perf_pipeline(w, kp_ke=kp_ke)),
            "R_p": float(load_pipeline(w, kp_ke=kp_ke)), "Q_p": float(efficiency_pipeline(S, m, k, **kw)),
            "limiting_level": int(limiting_level(w, kp_ke=kp_ke))}
