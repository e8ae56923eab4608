"""The stack-based raster processor: one video processor searching depth first with a stack.

Seed 002 compares two raster processors inside a video processor: a pipeline of one stage per
level (``hdl/sparse/``) and a "процессор со стеком" (eq. (8): ``Q(S) = P_s(S) / [pq P_so(S)]``),
which keeps the windows still to be split on a stack and runs one coverage-test unit over all
levels. This is its golden model, in plain Python integers as the hardware would hold them:

* set-up (``SETUP_CYCLES`` = 3: take the record, rewrite it, load the root): the broadcast
  record rewritten for processor ``(a, b)`` (``A' = pA``, ``B' = qB``, ``C' = C + aA + bB``,
  depth plane likewise); the root window goes into the current-window register;
* loop, one cycle per coverage test (τ = one cycle): test the current window's four sub-windows
  in the order ``(0,0), (1,0), (0,1), (1,1)`` with the same tests as the pipeline (window
  rectangle against the edges and the bounding box below level ``n``, the top-left point test at
  level ``n``). A surviving sub-window of the first three is pushed onto the stack; a surviving
  fourth becomes the next current window at once (it would be pushed and popped in one cycle);
  otherwise the top of the stack is popped into the register in the cycle of the fourth test. A
  pixel goes to the pixel processor (Z test into the local memory) in the cycle of its test. The
  record is done in the cycle of a fourth test with no survivor and an empty stack, and the next
  record is taken on the next cycle;
* so a record costs ``SETUP_CYCLES`` plus one cycle per test (``cycles.service_times(vp="stack")``),
  and the order is depth first, the last surviving sub-window first (ours: the paper gives the
  stack processor's cost, (6), not its order).

This is the register-level behaviour of ``hdl/sparse/stack_vp.py`` (``StackProcessor``), which is
held to it bit and cycle for cycle. The window counts do not depend on the order of the search, so
the stack processor's image and counts equal the breadth-first golden search's
(:func:`.search.sparse_render`, tested); what it adds is the order, the stack's depth (at most
``3 (n - 1)`` entries: three siblings waiting per level above the pixel level) and its cycles.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles
from rasterhw.golden_model.sparse.cycles import (
    KE_EDGES,
    SETUP_CYCLES,
    coupled_matrix,
    service_times,
)
from rasterhw.golden_model.sparse.edges import edge_setup
from rasterhw.golden_model.sparse.formats import Z_FRAC_BITS, parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import sparse_render

__all__ = ["broadcast_records_rgb", "coupled_stack_matrix", "param_cycles", "stack_processor"]

#: cycles the pixel processor (``hdl/sparse/pixel.py``: read, then compare and write) holds a pixel
PIXEL_LATENCY = 2
_SUB = 1 << SUBPIXEL_BITS
_HALF = _SUB // 2


def broadcast_records_rgb(tris: ScreenTriangles) -> list[dict]:
    """``fixed.broadcast_records`` with the colour planes: ``c00``, ``cx``, ``cy`` (3 channels each,
    8-bit levels with ``Z_FRAC_BITS`` fraction bits over full-raster pixel indices), what the HDL
    stack processor takes with ``colour=True`` (``BROADCAST_RGB``)."""
    from rasterhw.golden_model.sparse.fixed import broadcast_records, colour_planes

    recs = broadcast_records(tris)
    xy, _, _ = tris.validate(who="sparse broadcast", max_coord=float(1 << 13))
    pl = colour_planes(tris, edge_setup(xy))
    for t, r in enumerate(recs):
        for j, key in enumerate(("c00", "cx", "cy")):
            r[key] = [int(pl[ch, j, t]) for ch in range(3)]
    return recs


def param_cycles(credit: int, kp: int, ke: int) -> tuple[int, int]:
    """Formula (5)'s surface-parameter term as the stack processor spends it, one survivor at a
    time: a surviving window (or pixel) of a level needs ``kp`` parameter additions on the ``ke``
    edge adders; ``credit`` additions are left from the level's last parameter cycle. Returns
    (cycles to spend now, credit left). Over ``w`` survivors of one level of one record (credit
    from 0) the cycles add up to ``ceil(w kp / ke)``, ``cycles.stage_cycles``' term (tested)."""
    need = kp - credit
    if need <= 0:
        return 0, -need
    c = -(-need // ke)
    return c, c * ke - need


def stack_processor(tris: ScreenTriangles, matrix, a: int, b: int, *, alpha: int = 2, beta: int = 2,
                    kp: int = 0, ke: int = KE_EDGES, colour: bool = False) -> dict:
    """Run processor ``(a, b)`` of a ``p x q`` matrix as a stack processor over every broadcast
    record. Returns its local memories ``tri`` and ``zq`` (``2**n x 2**n``, -1 where empty),
    ``cycles`` (per record: set-up plus tests), ``accept`` (the cycle each record is taken when the
    records wait at the input from cycle 0: ``accept[t] = sum(cycles[:t])``), ``busy``
    (``sum(cycles)``), ``tail`` (per record: cycles its last pixels keep the pixel processor busy
    after the record is done), ``tests`` per level (``(n,)``), ``max_stack`` (the most windows the stack
    held) and ``writes`` (pixels that passed the Z test).

    ``kp`` > 0 prices ``kp`` surface parameters as formula (5) does (``ke`` edge adders,
    :func:`param_cycles` per surviving window and pixel, the level's credit reset per record):
    ``cycles`` then equal ``cycles.service_times(vp="stack", kp=kp, ke=ke)``. ``colour``: the
    vertex colours as three more linear functions (``fixed.colour_planes``, rewritten for the
    lattice as the edges) evaluated at each written pixel and rounded as ``fixed.colour_rgb8``:
    ``rgb`` (``2**n x 2**n x 3``, 0 where empty)."""
    from rasterhw.golden_model.sparse.fixed import COLOUR_BITS, colour_planes, depth_plane

    p, q = parse_matrix(matrix)
    n = sparse_geometry(tris.width, tris.height, p, q)
    for name, v in (("a", a), ("b", b)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise RasterhwError(f"sparse stack: {name} must be an integer, not {v!r}")
    if not (0 <= a < p and 0 <= b < q):
        raise RasterhwError(f"sparse stack: processor ({a}, {b}) is outside a {p}x{q} matrix")
    for name, v, lo in (("kp", kp, 0), ("ke", ke, 1)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
            raise RasterhwError(f"sparse stack: {name} must be an integer >= {lo}, not {v!r}")
    xy, _, _ = tris.validate(who="sparse stack", max_coord=float(1 << 13))
    es = edge_setup(xy)
    Z0, Zu, Zv = depth_plane(tris, es, p, q)
    pl = colour_planes(tris, es) if colour else None  # (3 channels, [C00, Cx, Cy], T)
    cmax, chalf = (1 << COLOUR_BITS) - 1, 1 << (Z_FRAC_BITS - 1)
    Ns = 1 << n
    ctab = [(0, 0, 0)] * (Ns * Ns)
    zmax = (1 << tris.z_bits) - 1
    ztab = [zmax + 1] * (Ns * Ns)
    ttab = [-1] * (Ns * Ns)
    T = es.tri.size
    cycles = np.zeros(T, dtype=np.int64)
    tail = np.zeros(T, dtype=np.int64)
    tests = [0] * (n + 1)
    max_stack = 0
    writes = 0
    order = ((0, 0), (1, 0), (0, 1), (1, 1))
    for t in range(T):
        A = [int(v) * p for v in es.A[:, t]]  # A' per sparse pixel
        B = [int(v) * q for v in es.B[:, t]]
        thr = [int(v) for v in es.thr[:, t]]
        ext = [(abs(int(es.A[k, t])) * alpha + abs(int(es.B[k, t])) * beta) // 2 for k in range(3)]
        pos = [max(A[k], 0) + max(B[k], 0) for k in range(3)]
        bx0, bx1, by0, by1 = (int(v) for v in es.bbox[:, t])
        E0 = [int(es.C[k, t]) + a * int(es.A[k, t]) + b * int(es.B[k, t]) for k in range(3)]
        z0, zu, zv = int(Z0[t, b, a]), int(Zu[t]), int(Zv[t])
        tri = int(es.tri[t])
        last_px = -1  # cycle (from the take) of the record's last pixel sent to the pixel processor
        cur = (0, 0, 0, E0)  # the current window: (level, u, v, edge values at its first pixel)
        if colour:
            col = [(int(pl[ch, 0, t]) + a * int(pl[ch, 1, t]) + b * int(pl[ch, 2, t]), p * int(pl[ch, 1, t]),
                    q * int(pl[ch, 2, t])) for ch in range(3)]
        credit = [0] * (n + 1)
        stack = []
        ntest = 0
        npar = 0
        while cur is not None:
            lvl, u, v, E = cur
            i = lvl + 1
            N = 1 << (n - i)
            nxt = None
            for c, (du, dv) in enumerate(order):
                ntest += 1
                tests[i] += 1
                uc, vc = u + du * N, v + dv * N
                Ec = [E[k] + A[k] * du * N + B[k] * dv * N for k in range(3)]
                if i < n:
                    x0 = (p * uc + a) * _SUB + _HALF - alpha * _HALF
                    x1 = (p * (uc + N - 1) + a) * _SUB + _HALF + alpha * _HALF
                    y0 = (q * vc + b) * _SUB + _HALF - beta * _HALF
                    y1 = (q * (vc + N - 1) + b) * _SUB + _HALF + beta * _HALF
                    ok = (x1 >= bx0 and x0 <= bx1 and y1 >= by0 and y0 <= by1
                          and all(Ec[k] + pos[k] * (N - 1) + ext[k] >= thr[k] for k in range(3)))
                    if ok and kp:
                        dc, credit[i] = param_cycles(credit[i], kp, ke)
                        npar += dc
                    if ok and c < 3:
                        stack.append((i, uc, vc, Ec))
                        max_stack = max(max_stack, len(stack))
                    elif ok:
                        nxt = (i, uc, vc, Ec)
                elif all(Ec[k] >= thr[k] for k in range(3)):
                    last_px = SETUP_CYCLES + ntest - 1 + npar
                    if kp:
                        dc, credit[i] = param_cycles(credit[i], kp, ke)
                        npar += dc
                    zq = min(max((z0 + zu * uc + zv * vc) >> Z_FRAC_BITS, 0), zmax)
                    adr = vc * Ns + uc
                    if zq < ztab[adr]:
                        ztab[adr], ttab[adr] = zq, tri
                        writes += 1
                        if colour:
                            ctab[adr] = tuple(min(max((c0 + cu * uc + cv * vc + chalf) >> Z_FRAC_BITS, 0), cmax)
                                              for c0, cu, cv in col)
            cur = nxt if nxt is not None else (stack.pop() if stack else None)
        cycles[t] = SETUP_CYCLES + ntest + npar
        # the pixel processor holds a pixel for PIXEL_LATENCY cycles after its test (its colour is
        # written with its depth): what the record's last pixels keep busy after the record is done
        tail[t] = max(0, last_px + PIXEL_LATENCY + 1 - int(cycles[t])) if last_px >= 0 else 0
    tri_m = np.array(ttab, dtype=np.int64).reshape(Ns, Ns)
    zq_m = np.where(tri_m >= 0, np.array(ztab, dtype=np.int64).reshape(Ns, Ns), -1)
    accept = np.concatenate([[0], np.cumsum(cycles)[:-1]]).astype(np.int64) if T else cycles.copy()
    out_rgb = np.array(ctab, dtype=np.int64).reshape(Ns, Ns, 3) if colour else None
    return {"rgb": out_rgb, "tri": tri_m, "zq": zq_m, "tail": tail, "cycles": cycles, "accept": accept, "busy": int(cycles.sum()), "tests": np.array(tests[1:], dtype=np.int64),
            "max_stack": max_stack, "writes": writes, "n": n}


def coupled_stack_matrix(tris: ScreenTriangles, p: int, q: int, fifo_depth: int, *, kp: int = 0,
                         ke: int = KE_EDGES) -> dict:
    """The golden coupled model of a ``p x q`` matrix of stack processors, keyed as
    ``vpcycles.coupled_matrix_vp``'s: ``cycles.coupled_matrix`` on the stack service times
    (formula (5)'s parameter cycles with ``kp``), the frame extended by the last pixels' drain
    (:func:`stack_processor`'s per-record ``tail``), and the per-level tests (the stack processor
    has no per-level stalls: ``stalls`` are 0)."""
    f = sparse_render(tris, (p, q), depth="fixed", per_record=True)
    s = service_times(f.stats["windows_per_record"], vp="stack", kp=kp, ke=ke)
    tail = np.stack([stack_processor(tris, (p, q), k % p, k // p, kp=kp, ke=ke)["tail"] for k in range(p * q)])
    r = coupled_matrix(s, fifo_depth)
    frame = int((r.pop + s + tail).max()) if s.size else 0
    return {"frame_cycles": frame, "stall_cycles": r.stall_cycles, "fifo_peak": r.fifo_peak.tolist(),
            "fifo_peak_max": int(r.fifo_peak.max(initial=0)), "busy": r.busy.tolist(),
            "idle": (frame - r.busy).tolist(), "tests": f.tests_per_proc[:, 1:].tolist(),
            "stalls": [[0] * f.n for _ in range(p * q)]}
