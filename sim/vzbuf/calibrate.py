"""A calibration of the FACOM timing model on the paper's table 2, shown as a fit with its
out-of-sample error on tables 3-7 (report rows ``fit:table2``).

Every price of :func:`~rasterhw.golden_model.vzbuf.facom.price` is linear in three named
parameters (:data:`~rasterhw.golden_model.vzbuf.facom.LINEAR`: the scalar clock period, the
vector start-up and the pipelines per peak, which set every element time), so a stage's time is
``sum(theta[p] * component[p])``. :func:`fit` chooses the three values that minimise the squared
log error over table 2's stage cells (scalar, VP100 and VP200, every scene; nothing else), by
Gauss-Newton on the logs of the parameters. The fitted model then predicts tables 3-7, which it
has not seen: the spread of those predictions around the paper's cells is the out-of-sample
error. The conclusions are never drawn from these rows: they stay the uncalibrated model's
(``model:*``), whose parameters come from published facts or are chosen and marked.
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.vzbuf.facom import LINEAR, components
from rasterhw.golden_model.vzbuf.paper import COLUMN
from rasterhw.golden_model.vzbuf.render import table_stages
from rasterhw.golden_model.vzbuf.trace import Trace

__all__ = ["FIT_TABLE", "error_factors", "fit", "predict", "stage_components", "summary"]

FIT_TABLE = "table 2"
MACHINES = ("scalar", "vp100", "vp200")


def stage_components(tr: Trace, alg: int, sh: str) -> dict:
    """``{machine: {param: {stage: ms}}}``: each table stage's time split by :data:`LINEAR`."""
    st = table_stages(alg, sh)
    out = {}
    for m in MACHINES:
        c = components(tr, m)
        out[m] = {p: {k.split()[0]: 1e3 * sum(ph.get(x, 0.0) for x in v) for k, v in st.items()}
                  for p, ph in c.items()}
    return out


def predict(comp: dict, theta: dict) -> dict:
    """``{machine: {stage: ms, "total": ms}}`` of one (table, scene) at parameters ``theta``."""
    out = {}
    for m, parts in comp.items():
        stages = next(iter(parts.values())).keys()
        d = {s: sum(theta[p] * parts[p][s] for p in LINEAR) for s in stages}
        d["total"] = sum(d.values())
        out[m] = d
    return out


def _entries(by_key: dict, tables: dict, table: str):
    """(scene, machine's entry, the paper's rows of that machine) of every ``(table, scene)`` of
    ``by_key`` (``{(table, scene): {machine: entry}}``) whose machine the paper's ``table`` has."""
    T = tables[table]
    for (t, n), per_m in sorted(by_key.items()):
        if t != table:
            continue
        for m, entry in per_m.items():
            if COLUMN[m] in T:
                yield n, entry, T[COLUMN[m]]


def _cells(comps: dict, tables: dict, table: str):
    """(component row, paper value) of every stage cell of ``table`` with a paper value."""
    rows, paper = [], []
    for n, parts, Tm in _entries(comps, tables, table):
        for s in next(iter(parts.values())):
            pv = Tm.get(s, {}).get(n)
            if pv:
                rows.append([parts[p][s] for p in LINEAR])
                paper.append(float(pv))
    return np.array(rows, float), np.array(paper, float)


def fit(comps: dict, tables: dict, start: dict, table: str = FIT_TABLE, iters: int = 100) -> dict:
    """The :data:`LINEAR` values minimising sum(log(model / paper)^2) over ``table``'s stage cells
    only (``comps``: ``{(table, scene): stage_components(...)}``; ``tables``: the paper's tables;
    ``start``: the model's own values). Returns ``{param: value}``."""
    A, p = _cells(comps, tables, table)
    if not len(p):
        raise ValueError(f"calibrate: no cells of {table} to fit")
    keep = [j for j in range(A.shape[1]) if A[:, j].any()]   # a parameter the cells do not see stays put
    x = np.log([float(start[k]) for k in LINEAR])
    lam = 1e-3

    def cost(x):
        y = A @ np.exp(x)
        return float(np.sum((np.log(y) - np.log(p)) ** 2))

    c = cost(x)
    for _ in range(iters):
        th = np.exp(x)
        y = A @ th
        r = np.log(y) - np.log(p)
        J = (A * th) / y[:, None]
        Jk = J[:, keep]
        H = Jk.T @ Jk
        g = Jk.T @ r
        step = np.linalg.solve(H + lam * np.diag(np.diag(H) + 1e-12), -g)
        xn = x.copy()
        xn[keep] += step
        cn = cost(xn)
        if cn < c:
            x, c, lam = xn, cn, lam / 3
            if np.max(np.abs(step)) < 1e-10:
                break
        else:
            lam *= 10
    return dict(zip(LINEAR, np.exp(x).tolist(), strict=True))


def error_factors(pred: dict, tables: dict, table: str) -> list[float]:
    """``max(r, 1/r)`` of ``r`` = predicted / paper over every stage and total cell of ``table``
    (``pred``: ``{(table, scene): predict(...)}``)."""
    out = []
    for n, d, Tm in _entries(pred, tables, table):
        for s, v in d.items():
            pv = Tm.get(s, {}).get(n)
            if pv and v > 0:
                out.append(max(v / pv, pv / v))
    return out


def summary(factors: list[float]) -> tuple[float, float]:
    """(median factor, geometric-mean factor) of :func:`error_factors`."""
    if not factors:
        return float("nan"), float("nan")
    return float(np.median(factors)), float(math.exp(np.mean(np.log(factors))))
