"""The compiled fast path of the video processor's cycle model (numba).

:mod:`.vpcycles` is the specification: :class:`~.vpcycles.VPCycleModel` steps one processor's
registers in plain Python, one object per processor, and :func:`~.vpcycles.coupled_matrix_vp`
couples ``p*q`` of them through the broadcast. This module steps the same registers with the same
rules in one compiled loop, every processor's state held in arrays:

* ``R[k]`` (:data:`NR` fields): the set-up FSM, the pixel processor's next pixel and its two
  register stages, and the ``held`` / ``active`` counts that make ``busy``;
* ``S[k]`` (:data:`NF` fields of ``n + 1`` entries): per FIFO ``j`` (0: set-up into level 1, ``n``:
  into the pixel processor) the window and header FIFOs' inner levels and output-register valid
  bits; per level stage ``s`` its state (``IDLE`` / ``TEST`` / ``PARAM``), parameter credit and
  countdown, the window held and the next to take, the sub-window under test, whether the
  triangle's header went out, and the ``tests`` / ``stalls`` counters.

:func:`_step` is :meth:`VPCycleModel.step` line for line (the FIFO edge at the end, every read
before it of the registered values); the stage-busy count and the ``fresh`` flag, which no result
of the coupled or standalone run reads, are not kept. The control streams are
:func:`~.vpcycles.vp_streams`', packed per processor into flat arrays (:func:`pack`).
``tests/sparse/test_sparse_vpcycles_fast.py`` holds every returned key identical to the
specification's.

This module imports numba at the top: :mod:`.vpcycles` loads it on first use
(:class:`rasterhw.golden_model.fastpath.FastPath`) and runs the Python specification, with one
line on stderr, when that fails. Kernels are cached on disk (``cache=True``,
:func:`rasterhw.golden_model.numba_jit.njit_cached`).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.numba_jit import njit_cached

__all__ = ["coupled", "pack", "standalone"]

# S[k] rows: FIFO j in 0..n
WL, WV, HL, HV = 0, 1, 2, 3  # window FIFO inner level, output valid; header FIFO likewise
# S[k] rows: level stage s in 0..n-1
ST, CREDIT, PCOUNT, PEND, CHILD, CUR, NXT, SENT, TESTS, STALLS = range(4, 14)
NF = 14
# R[k] fields
SETUP, PX, V1, V2, HELD, ACTIVE = range(6)
NR = 6
# rows of the per-cycle scratch: FIFO j's write and read enables, stage s's next state
W_WEN, H_WEN, W_REN, H_REN, ST_NEXT = range(5)
# status of a run
OK, RUNAWAY_FEED, RUNAWAY_DRAIN, RUNAWAY_FRAME = range(4)


@njit_cached
def _accept(k, s, S, newv, newoff, tmp):  # pragma: no cover - compiled
    """Stage ``s`` takes the next window (and its header if it starts a triangle) when FIFO ``s``
    offers it: ``VPCycleModel.step``'s ``accept``."""
    j = S[k, NXT, s]
    valid = S[k, WV, s] != 0
    need = newv[newoff[k, s] + j] != 0 if valid else False
    hv = S[k, HV, s] != 0
    tmp[W_REN, s] = 1 if ((not need) or hv) else 0
    tmp[H_REN, s] = 1 if (valid and need) else 0
    if valid and ((not need) or hv):
        S[k, CUR, s] = j
        S[k, NXT, s] = j + 1
        S[k, CHILD, s] = 0
        if need:
            S[k, SENT, s] = 0
            S[k, CREDIT, s] = 0
        tmp[ST_NEXT, s] = 1
    else:
        tmp[ST_NEXT, s] = 0


@njit_cached
def _step(k, in_valid, n, caps, kp, ke, okv, okoff, newv, newoff, S, R, tmp):  # pragma: no cover - compiled
    """One clock cycle of processor ``k`` with the broadcast input's ``valid``; returns whether it
    took the record (``VPCycleModel.step``)."""
    tmp[:, :] = 0
    # ---- set-up
    accepted = False
    setup = R[k, SETUP]
    setup_next = setup
    if setup == 0:
        if in_valid:
            accepted = True
            setup_next = 1
    elif setup == 1:
        tmp[H_WEN, 0] = 1
        if S[k, HL, 0] != caps[0]:
            setup_next = 2
    else:
        tmp[W_WEN, 0] = 1
        if S[k, WL, 0] != caps[0]:
            setup_next = 0
    # ---- level stages
    for s in range(n):
        tmp[ST_NEXT, s] = S[k, ST, s]
    for s in range(n):
        st = S[k, ST, s]
        if st == 0:
            _accept(k, s, S, newv, newoff, tmp)
            continue
        if st == 2:
            S[k, PCOUNT, s] -= 1
            if S[k, PCOUNT, s] == 0:
                if S[k, PEND, s]:
                    _accept(k, s, S, newv, newoff, tmp)
                else:
                    tmp[ST_NEXT, s] = 1
            continue
        c = S[k, CHILD, s]
        extra = 0
        ok = okv[(okoff[k, s] + S[k, CUR, s]) * 4 + c] != 0
        advance = False
        if ok and S[k, SENT, s] == 0:
            tmp[H_WEN, s + 1] = 1
            if S[k, HL, s + 1] != caps[s + 1]:
                S[k, SENT, s] = 1
        elif ok:
            tmp[W_WEN, s + 1] = 1
            if S[k, WL, s + 1] != caps[s + 1]:
                advance = True
                if kp:
                    # stack.param_cycles: kp additions on ke adders, the credit left kept
                    need = kp - S[k, CREDIT, s]
                    if need <= 0:
                        S[k, CREDIT, s] = -need
                    else:
                        extra = (need + ke - 1) // ke
                        S[k, CREDIT, s] = extra * ke - need
            else:
                S[k, STALLS, s] += 1
        else:
            advance = True
        if advance:
            S[k, TESTS, s] += 1
            S[k, CHILD, s] = c + 1
            if extra:
                S[k, PCOUNT, s] = extra
                S[k, PEND, s] = 1 if c == 3 else 0
                tmp[ST_NEXT, s] = 2
            elif c == 3:
                _accept(k, s, S, newv, newoff, tmp)
    # ---- pixel processor
    take = False
    if S[k, WV, n]:
        need = newv[newoff[k, n] + R[k, PX]] != 0
        hv = S[k, HV, n] != 0
        tmp[W_REN, n] = 1 if ((not need) or hv) else 0
        tmp[H_REN, n] = 1 if need else 0
        take = (not need) or hv
        if take:
            R[k, PX] += 1
    else:
        tmp[W_REN, n] = 1  # i.ready = ~need | i_hdr.valid on a stale payload: no transfer
    R[k, V2] = R[k, V1]
    R[k, V1] = 1 if take else 0
    # ---- FIFOs (the edge): m = 0 windows, 1 headers
    held = 0
    for j in range(n + 1):
        for m in range(2):
            lv = 2 * m  # WL or HL; the valid bit is the next row
            lev = S[k, lv, j]
            vv = S[k, lv + 1, j]
            ren = tmp[W_REN + m, j] != 0
            do_write = tmp[W_WEN + m, j] != 0 and lev != caps[j]
            do_inner_read = lev != 0 and (vv == 0 or ren)
            if do_inner_read:
                vv = 1
            elif ren:
                vv = 0
            if do_write:
                lev += 1
            if do_inner_read:
                lev -= 1
            S[k, lv, j] = lev
            S[k, lv + 1, j] = vv
            held += lev + vv
    R[k, HELD] = held
    R[k, SETUP] = setup_next
    active = 0
    for s in range(n):
        S[k, ST, s] = tmp[ST_NEXT, s]
        if tmp[ST_NEXT, s]:
            active += 1
    R[k, ACTIVE] = active
    return accepted


@njit_cached
def _busy(k, R):  # pragma: no cover - compiled
    """The HDL's ``busy`` of processor ``k`` for the current cycle (``VPCycleModel.busy``)."""
    return R[k, SETUP] != 0 or R[k, V1] != 0 or R[k, V2] != 0 or R[k, HELD] != 0 or R[k, ACTIVE] != 0


@njit_cached
def _coupled(okv, okoff, newv, newoff, P, n, T, D, g, caps, kp, ke, max_cycles):  # pragma: no cover - compiled
    """``coupled_matrix_vp``'s loop; returns ``(status, cycles, offer, bc, acc, peak, busy, S)``."""
    S = np.zeros((P, NF, n + 1), np.int64)
    R = np.zeros((P, NR), np.int64)
    tmp = np.zeros((5, n + 1), np.int64)
    lev = np.zeros(P, np.int64)
    peak = np.zeros(P, np.int64)
    busy = np.zeros(P, np.int64)
    acc = np.zeros((P, T), np.int64)
    taken = np.zeros(P, np.int64)
    bc = np.zeros(T, np.int64)
    offer = np.zeros(T, np.int64)
    vb = np.zeros(P, np.bool_)
    t = 0
    o = 0
    c = 0
    while True:
        any_lev = False
        any_busy = False
        max_lev = 0
        for k in range(P):
            vb[k] = _busy(k, R)
            any_busy = any_busy or vb[k]
            any_lev = any_lev or lev[k] != 0
            max_lev = max(max_lev, lev[k])
        if t == T and not any_lev and not any_busy:
            break
        push = t < T and c >= o and max_lev < D
        for k in range(P):
            if vb[k]:
                busy[k] += 1
            valid = lev[k] > 0
            if not valid and not vb[k]:
                continue  # an idle processor with nothing offered keeps its state
            if _step(k, valid, n, caps, kp, ke, okv, okoff, newv, newoff, S, R, tmp):
                acc[k, taken[k]] = c
                taken[k] += 1
                lev[k] -= 1
        if push:
            offer[t] = o
            bc[t] = c
            t += 1
            o = c + g
            for k in range(P):
                lev[k] += 1
                if lev[k] > peak[k]:
                    peak[k] = lev[k]
        c += 1
        if c > max_cycles:
            return RUNAWAY_FRAME, c, offer, bc, acc, peak, busy, S
    return OK, c, offer, bc, acc, peak, busy, S


@njit_cached
def _standalone(okv, okoff, newv, newoff, n, records, caps, kp, ke, max_cycles):  # pragma: no cover - compiled
    """``vp_standalone``'s loop for one processor; returns ``(status, cycles, accept, S)``."""
    S = np.zeros((1, NF, n + 1), np.int64)
    R = np.zeros((1, NR), np.int64)
    tmp = np.zeros((5, n + 1), np.int64)
    acc = np.zeros(records, np.int64)
    c = 0
    idx = 0
    while idx < records:
        if _step(0, True, n, caps, kp, ke, okv, okoff, newv, newoff, S, R, tmp):
            acc[idx] = c
            idx += 1
        c += 1
        if c > max_cycles:
            return RUNAWAY_FEED, c, acc, S
    _step(0, False, n, caps, kp, ke, okv, okoff, newv, newoff, S, R, tmp)
    c += 1
    while _busy(0, R):
        _step(0, False, n, caps, kp, ke, okv, okoff, newv, newoff, S, R, tmp)
        c += 1
        if c > max_cycles:
            return RUNAWAY_DRAIN, c, acc, S
    return OK, c + 1, acc, S


def pack(streams) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every processor's control streams (``[(oks, news, new_px), ...]``, each :func:`vp_streams`'),
    as flat arrays: ``okv`` (the survivor bits, 4 per window, uint8), ``okoff`` ((P, n): the first
    window of processor ``k``'s level ``s + 1`` in ``okv``, in windows), ``newv`` (the ``new``
    flags of every level, then of the pixels, uint8) and ``newoff`` ((P, n + 1))."""
    P = len(streams)
    n = len(streams[0][0]) if P else 0
    oks = [o for oks_k, _, _ in streams for o in oks_k]
    news = [x for _, news_k, px in streams for x in (*news_k, px)]
    rows = np.array([o.shape[0] for o in oks], dtype=np.int64)
    lens = np.array([x.size for x in news], dtype=np.int64)
    okoff = (np.cumsum(rows) - rows).reshape(P, n)
    newoff = (np.cumsum(lens) - lens).reshape(P, n + 1)
    okv = np.concatenate([np.asarray(o, dtype=np.uint8).reshape(-1) for o in oks]) if oks else np.zeros(0, np.uint8)
    newv = np.concatenate([np.asarray(x, dtype=np.uint8) for x in news]) if news else np.zeros(0, np.uint8)
    return okv, okoff, newv, newoff


def coupled(streams, T: int, D: int, g: int, caps: list[int], kp: int, ke: int, max_cycles: int):
    """The coupled matrix of ``len(streams)`` processors (:func:`.vpcycles.coupled_matrix_vp`'s
    loop): ``(status, frame_cycles, offer, broadcast, accept, fifo_peak, busy, tests, stalls)``,
    ``status`` 0 or :data:`RUNAWAY_FRAME`."""
    okv, okoff, newv, newoff = pack(streams)
    P, n = okoff.shape
    status, c, offer, bc, acc, peak, busy, S = _coupled(okv, okoff, newv, newoff, P, n, int(T), int(D), int(g),
                                                        np.asarray(caps, dtype=np.int64), int(kp), int(ke),
                                                        int(max_cycles))
    return status, int(c), offer, bc, acc, peak, busy, S[:, TESTS, :n], S[:, STALLS, :n]


def standalone(stream, records: int, caps: list[int], kp: int, ke: int, max_cycles: int):
    """One processor run as the Verilator bench (:func:`.vpcycles.vp_standalone`'s loop):
    ``(status, cycles, accept, tests, stalls)``, ``status`` 0, :data:`RUNAWAY_FEED` or
    :data:`RUNAWAY_DRAIN`."""
    okv, okoff, newv, newoff = pack([stream])
    n = okoff.shape[1]
    status, c, acc, S = _standalone(okv, okoff, newv, newoff, n, int(records), np.asarray(caps, dtype=np.int64),
                                    int(kp), int(ke), int(max_cycles))
    return status, int(c), acc, S[0, TESTS, :n], S[0, STALLS, :n]
