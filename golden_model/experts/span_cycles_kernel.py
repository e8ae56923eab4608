"""The compiled loop of :mod:`.span_cycles_fast`: :func:`.span_cycles.resolve`, one line of one
range through the span PXP, on arrays.

Line for line the specification's walk (:mod:`.span_cycles`: ``resolve``, ``Entering.take``,
``_ends``, ``_zrun``, ``_good``): the active list kept in ASL-entry order in an array, the
(sub)span stack in another, the first minimum of the depth key taken as Python's ``min`` takes
it. Segments come as ``seg`` (5, n): xl, xr, zl, dzdx, addr. Returns the step counts in
``span_cycles.STEPS`` order and the visible ASL position of every pixel of ``[glo, ghi)``.

This module imports numba at the top: :mod:`.span_cycles_fast` loads it on first use
(:class:`rasterhw.golden_model.fastpath.FastPath`); kernels are cached on disk
(:func:`rasterhw.golden_model.numba_jit.njit_cached`).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.experts.span_cycles import NO_PTR
from rasterhw.golden_model.numba_jit import njit_cached

__all__ = ["block_lists", "resolve"]

INIT, CULL, ENTER, PASS_A, PASS_B, WRITE = range(6)


@njit_cached
def resolve(seg, bucket, lead, glo, ghi, xfrac, dzfrac, zbits):  # pragma: no cover - compiled
    """``span_cycles.resolve`` on arrays: (cycles per step (6,), visible positions (ghi - glo,))."""
    cyc = np.zeros(6, np.int64)
    cyc[INIT] = 1
    if ghi <= glo:
        return cyc, np.zeros(0, np.int64)
    n = seg.shape[1]
    nb = bucket.shape[0]
    xl, xr, zl0, dzdx, addr = seg[0], seg[1], seg[2], seg[3], seg[4]
    c0 = np.empty(n, np.int64)
    a = np.empty(n, np.int64)
    e = np.empty(n, np.int64)
    for i in range(n):          # _ends
        c0[i] = (xl[i] + 31) >> xfrac
        a[i] = max(c0[i], glo)
        e[i] = min(((xr[i] + 31) >> xfrac) - 1, ghi - 1)
    zmax = (1 << zbits) - 1
    zmax_run = zmax << dzfrac
    g = 1 << dzfrac
    half = 1 << (xfrac - 1)
    vis = np.empty(ghi - glo, np.int64)
    nv = 0
    act = np.empty(n + nb, np.int64)
    na = 0
    entered = np.empty(n + nb, np.int64)
    zl = np.empty(n + nb, np.int64)
    zr = np.empty(n + nb, np.int64)
    stack = np.empty(ghi - glo + 2, np.int64)
    bi = 0
    pp = n if lead == NO_PTR else lead
    x = glo
    while x < ghi:
        cyc[CULL] += na
        m = 0
        for i in range(na):
            if e[act[i]] >= x:
                act[m] = act[i]
                m += 1
        na = m
        minend = ghi
        for i in range(na):
            minend = min(minend, e[act[i]] + 1)
        # Entering.take
        ne = 0
        while True:
            cyc[ENTER] += 1
            if bi < nb:
                pos = bucket[bi]
                cand = True
            else:
                pos = pp
                cand = pp < n and c0[pp] < ghi
            if not cand:
                ns = ghi
                break
            if not (e[pos] < a[pos] or a[pos] == x):
                ns = a[pos]
                break
            if a[pos] <= e[pos]:
                entered[ne] = pos
                ne += 1
            if bi < nb:
                bi += 1
            else:
                pp += 1
        nxt = min(ns, minend)
        for i in range(ne):
            nxt = min(nxt, e[entered[i]] + 1)
            act[na] = entered[i]
            na += 1
        r = nxt - 1
        if na < 2:
            cyc[WRITE] += r - x + 1
            v = act[0] if na else -1
            for _ in range(r - x + 1):
                vis[nv] = v
                nv += 1
        else:
            k = na
            top = 0
            lft, rgt = x, r
            while True:
                cyc[PASS_A] += k
                best = 0
                for i in range(k):
                    p = act[i]
                    zl[i] = (zl0[p] << dzfrac) + ((((lft << xfrac) + half - xl[p]) * dzdx[p]) >> xfrac)
                    zr[i] = (zl0[p] << dzfrac) + ((((rgt << xfrac) + half - xl[p]) * dzdx[p]) >> xfrac)
                    key = min(max(zl[i] >> dzfrac, 0), zmax)
                    if i == 0:
                        bkey, baddr = key, addr[p]
                    elif key < bkey or (key == bkey and addr[p] < baddr):
                        best, bkey, baddr = i, key, addr[p]
                s = act[best]
                ok = True
                if lft < rgt:
                    cyc[PASS_B] += k
                    zsl, zsr = zl[best], zr[best]
                    for i in range(k):
                        p = act[i]
                        if p == s:
                            continue
                        if addr[s] < addr[p]:     # _good, s_lower
                            good = zsl <= zl[i] and zsr <= zr[i]
                        else:
                            good = (zsl + g <= zl[i] and zsr + g <= zr[i] and zl[i] >= g and zr[i] >= g
                                    and zsl < zmax_run and zsr < zmax_run)
                        if not good:
                            ok = False
                            break
                if not ok:
                    stack[top] = rgt
                    top += 1
                    rgt = ((lft + rgt + 1) >> 1) - 1
                    continue
                cyc[WRITE] += rgt - lft + 1
                for _ in range(rgt - lft + 1):
                    vis[nv] = s
                    nv += 1
                if top == 0:
                    break
                top -= 1
                lft, rgt = rgt + 1, stack[top]
        x = r + 1
    return cyc, vis[:nv]


@njit_cached
def block_lists(c0, c1, glo, ghi, live):  # pragma: no cover - compiled
    """``slp_run.block_lists`` on arrays, the ASL being ``range(len(c0))`` (``c0``/``c1`` per ASL
    position; ``glo``/``ghi``/``live`` per range, the guard applied): (leading pointer per range,
    -1 none; bucket entries as (range, position) rows in the specification's order)."""
    P = glo.shape[0]
    lead = np.full(P, -1, np.int64)
    rows = np.empty((c0.shape[0] * max(P, 1), 2), np.int64)
    nr = 0
    q = 0
    for pos in range(c0.shape[0]):
        a, e = c0[pos], c1[pos]
        if e < a:
            continue
        while q < P and a >= glo[q]:
            if live[q] and a < ghi[q]:
                lead[q] = pos
            q += 1
        k = q
        while k < P and glo[k] <= e:
            if live[k]:
                rows[nr, 0] = k
                rows[nr, 1] = pos
                nr += 1
            k += 1
    return lead, rows[:nr]
