"""Cycle model of the HDL video processor as built (``hdl/sparse/vp.py``), cycle by cycle.

The pipeline abstraction of :mod:`.cycles` prices a record at its busiest stage; the HDL
processor overlaps consecutive records across its stages through FIFOs. This module steps the
processor's registers as the HDL does, so that its input acceptance -- the cycle on which it takes
each broadcast record -- and its last busy cycle are the HDL's:

* set-up FSM ``IDLE -> HDR -> ROOT``: ``i.ready`` in ``IDLE``; the header into header FIFO 0 (when
  it has room), then the root window into window FIFO 0;
* ``n`` level stages (``hdl/sparse/stage.py``), ``IDLE`` / ``TEST``: a window (with its header when
  it is marked ``new``) is taken in ``IDLE`` or in the cycle of the last test; each of the four
  sub-windows takes one cycle, plus one for the triangle's header before its first survivor; a
  survivor or header waits while the next FIFO is full;
* ``2 (n + 1)`` ``SyncFIFOBuffered`` FIFOs (Amaranth 0.5: an inner memory of ``depth - 1`` entries
  and an output register; ``w_rdy = inner_level != depth - 1``; an entry written on cycle ``c``
  is at the output on cycle ``c + 2``);
* the pixel processor: takes one pixel per cycle, two register stages (``idle`` when both empty);
* with surface parameters priced (``kp`` > 0, formula (5)): after a survivor has gone out, the stage
  waits ``param_cycles`` whole cycles (``PARAM``) while ``kp`` additions run on ``ke`` adders, the
  additions left over from a cycle kept for the stage's next survivor of the same triangle; after a
  fourth sub-window the next window is taken in the last of those cycles. (Colour itself costs no
  cycle: it travels in the same FIFO words.)

Only the control flow is modelled: which sub-windows survive and which windows start a triangle
come from the golden search (``sparse_render(..., trace=True)``), which the HDL is held to bit for
bit. ``busy`` is the HDL's: anything held in the set-up, a stage, a FIFO or the pixel pipeline.

:func:`vp_standalone` replays the processor's frame bench (``sim/sparse/testbench.py``
``ProcessorBench``): records offered back to back, ``cycles`` counted from the first cycle a record
is offered to the first cycle, after the feed phase ended, on which the processor is not busy
(inclusive).
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.fastpath import FastPath
from rasterhw.golden_model.sparse.cycles import KE_EDGES, _check_int
from rasterhw.golden_model.sparse.stack import param_cycles

__all__ = ["ENGINE_ENV", "HDL_FIFO_DEPTH", "SHALLOW_FIFO_DEPTH", "VPCycleModel", "choose_engine", "coupled_matrix_vp", "vp_standalone",
           "vp_streams"]

#: ``VideoProcessor(fifo_depth=8)``: eight-entry FIFOs between the levels (ours: a queue of windows
#: inside the processor), the default every driver builds, the coupled matrix's too. The paper gives
#: no buffer size: it asks only for a "sufficient" input FIFO ("при малой размерности матрицы и
#: достаточном объеме FIFO") and refers the micro-pipeline to its reference [3] ("Такой микроконвейер
#: подробно описан и исследован в [3]"). Eight is the depth at which the processor reproduces the
#: paper's formulas (9) and (10): its frame comes within a few per cent of its busiest stage's time
#: and its load equals (10) on its own window counts; with two-entry buffers the frame runs 17-44 %
#: above the busiest stage (measured: ``rasterhw report sparse``, rows "(9) / (10), HDL frame
#: time"; docs/sparse.md#the-inner-buffer-depth).
HDL_FIFO_DEPTH = 8

#: the shallowest inner buffer Amaranth's buffered FIFO takes, two entries (ours, a comparison
#: point: ``rasterhw sim sparse --vp-fifo-depth 2``)
SHALLOW_FIFO_DEPTH = 2

#: Environment variable choosing the engine of :func:`coupled_matrix_vp` and :func:`vp_standalone`
#: when a call does not: ``python`` (this module's code, the specification), ``numba`` (the compiled
#: fast path, :mod:`.vpcycles_fast`; an error where numba cannot load), or ``auto`` / unset (numba
#: where it loads, else Python with one line on stderr).
ENGINE_ENV = "RASTERHW_VPCYCLES"
_FAST = FastPath("rasterhw.golden_model.sparse.vpcycles_fast", env=ENGINE_ENV, spec="python",
                 fallback="the sparse video processor's cycle model runs its Python specification (same "
                      "cycles, slower)")


def choose_engine(engine: str | None = None) -> str:
    """``"numba"`` or ``"python"``: the engine that runs the cycle model for ``engine`` (``None`` =
    the environment variable :data:`ENGINE_ENV`, default ``auto``)."""
    return _FAST.choose(engine)


def _check_params(fifo_depth, setup_fifo_depth, kp, ke) -> list[int]:
    """The processor's parameters checked; returns the FIFOs' inner capacities but the last's
    (0: the set-up's, then every level's: ``[setup_fifo_depth - 1, fifo_depth - 1]``)."""
    setup_fifo_depth = fifo_depth if setup_fifo_depth is None else setup_fifo_depth
    for name, v in (("fifo_depth", fifo_depth), ("setup_fifo_depth", setup_fifo_depth)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 2:
            raise RasterhwError(f"sparse VP cycles: {name} must be an integer >= 2, not {v!r}")
    for name, v, lo in (("kp", kp, 0), ("ke", ke, 1)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
            raise RasterhwError(f"sparse VP cycles: {name} must be an integer >= {lo}, not {v!r}")
    return [setup_fifo_depth - 1, fifo_depth - 1]


def vp_streams(frame, k: int) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """Processor ``k``'s control streams from a frame drawn with ``trace=True``: per level ``i``
    (list index ``i - 1``) the survivor bits ``ok`` ``(R_i, 4)`` and the ``new`` flags ``(R_i,)`` of
    the windows entering it, and the ``new`` flags of the pixels reaching the pixel processor."""
    tr = frame.stats.get("trace")
    if tr is None:
        raise RasterhwError("sparse VP cycles: the frame was drawn without trace=True")
    P = frame.p * frame.q
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k < P:
        raise RasterhwError(f"sparse VP cycles: processor index must be in 0..{P - 1}, not {k!r}")
    oks, news = [], []
    for proc, rt, ok in tr:
        sel = proc == k
        oks.append(np.ascontiguousarray(ok[sel]))
        r = rt[sel]
        new = np.ones(r.size, dtype=bool)
        new[1:] = r[1:] != r[:-1]
        news.append(new)
    # pixels: the survivors of the last level, in order
    proc, rt, ok = tr[-1]
    sel = proc == k
    rt_px = np.repeat(rt[sel], 4)[ok[sel].ravel()]
    new_px = np.ones(rt_px.size, dtype=bool)
    new_px[1:] = rt_px[1:] != rt_px[:-1]
    return oks, news, new_px


class VPCycleModel:
    """One video processor's registers, stepped one cycle at a time (see the module docstring).

    ``step(in_valid) -> accepted``: one clock cycle with the broadcast input's ``valid``; returns
    whether the processor took the record in that cycle. ``busy`` is the HDL's ``busy`` output
    for the current cycle (before ``step``). Counters ``tests[i]`` (coverage tests of stage ``i + 1``)
    and ``stalls[i]`` are the HDL stage's; ``stage_busy[i]`` counts the cycles stage ``i + 1`` was
    not idle (testing, sending a header, stalled or waiting for parameter additions). ``kp``, ``ke``: formula (5)'s parameter cycles, as
    ``VideoProcessor(kp=..., ke=...)`` spends them.
    """

    def __init__(self, oks: list[np.ndarray], news: list[np.ndarray], new_px: np.ndarray, *,
                 fifo_depth: int = HDL_FIFO_DEPTH, setup_fifo_depth: int | None = None, kp: int = 0,
                 ke: int = KE_EDGES):
        cap0, cap = _check_params(fifo_depth, setup_fifo_depth, kp, ke)
        self.kp, self.ke = int(kp), int(ke)
        self.n = n = len(oks)
        self.ok = [[tuple(bool(b) for b in row) for row in o] for o in oks]
        self.new = [list(map(bool, x)) for x in news] + [list(map(bool, new_px))]
        # inner capacity of FIFO k (0: the set-up's, into level 1)
        self.caps = [cap0] + [cap] * n
        # FIFO k (0..n) feeds stage k + 1 (the pixel processor for k = n); w: windows, h: headers
        self.wl = [0] * (n + 1)   # inner levels
        self.wv = [False] * (n + 1)  # output registers valid
        self.hl = [0] * (n + 1)
        self.hv = [False] * (n + 1)
        self.setup = 0  # 0 IDLE, 1 HDR, 2 ROOT
        self.st = [0] * n  # 0 IDLE, 1 TEST, 2 PARAM
        self.credit = [0] * n  # parameter additions left from the stage's last parameter cycle
        self.pcount = [0] * n  # parameter cycles still to wait
        self.pend = [False] * n  # ... then take the next window
        self.child = [0] * n
        self.cur = [0] * n  # index of the window held
        self.nxt = [0] * n  # index of the next window to take
        self.sent = [False] * n
        self.fresh = [False] * n
        self.tests = [0] * n
        self.stalls = [0] * n
        self.stage_busy = [0] * n
        self.px_next = 0
        self.v1 = self.v2 = False
        self.held = 0
        self.active = 0

    @property
    def busy(self) -> bool:
        # held: entries in all FIFOs (inner levels plus output registers); active: stages in TEST
        return bool(self.setup or self.v1 or self.v2 or self.held or self.active)

    def step(self, in_valid: bool) -> bool:
        n, caps = self.n, self.caps
        wl, wv, hl, hv = self.wl, self.wv, self.hl, self.hv
        w_wen = [False] * (n + 1)
        h_wen = [False] * (n + 1)
        w_ren = [False] * (n + 1)
        h_ren = [False] * (n + 1)
        # ---- set-up
        accepted = False
        setup_next = self.setup
        if self.setup == 0:
            if in_valid:
                accepted = True
                setup_next = 1
        elif self.setup == 1:
            h_wen[0] = True
            if hl[0] != caps[0]:
                setup_next = 2
        else:
            w_wen[0] = True
            if wl[0] != caps[0]:
                setup_next = 0
        # ---- level stages
        st_next = list(self.st)
        for s in range(n):
            ok_s, new_in = self.ok[s], self.new[s]
            if self.st[s]:
                self.stage_busy[s] += 1

            def accept(s=s, new_in=new_in):
                # take the next window (and its header if it starts a triangle)
                j = self.nxt[s]
                valid = wv[s]
                need = new_in[j] if valid else False
                w_ren[s] = (not need) or hv[s]
                h_ren[s] = valid and need
                if valid and ((not need) or hv[s]):
                    self.cur[s] = j
                    self.nxt[s] = j + 1
                    self.child[s] = 0
                    if need:
                        self.sent[s] = False
                        self.fresh[s] = False
                        self.credit[s] = 0
                    st_next[s] = 1
                else:
                    st_next[s] = 0

            if self.st[s] == 0:
                accept()
                continue
            if self.st[s] == 2:
                self.pcount[s] -= 1
                if self.pcount[s] == 0:
                    if self.pend[s]:
                        accept()
                    else:
                        st_next[s] = 1
                continue
            c = self.child[s]
            extra = 0
            ok = ok_s[self.cur[s]][c]
            advance = False
            if ok and not self.sent[s]:
                h_wen[s + 1] = True
                if hl[s + 1] != caps[s + 1]:
                    self.sent[s] = True
                    self.fresh[s] = True
            elif ok:
                w_wen[s + 1] = True
                if wl[s + 1] != caps[s + 1]:
                    advance = True
                    self.fresh[s] = False
                    if self.kp:
                        extra, self.credit[s] = param_cycles(self.credit[s], self.kp, self.ke)
                else:
                    self.stalls[s] += 1
            else:
                advance = True
            if advance:
                self.tests[s] += 1
                self.child[s] = c + 1
                if extra:
                    self.pcount[s], self.pend[s] = extra, c == 3
                    st_next[s] = 2
                elif c == 3:
                    accept()
        # ---- pixel processor
        take = False
        if wv[n]:
            need = self.new[n][self.px_next]
            w_ren[n] = (not need) or hv[n]
            h_ren[n] = need
            take = (not need) or hv[n]
            if take:
                self.px_next += 1
        else:
            w_ren[n] = True  # i.ready = ~need | i_hdr.valid on a stale payload: no transfer
        self.v2 = self.v1
        self.v1 = take
        # ---- FIFOs (the edge)
        held = 0
        for k in range(n + 1):
            for lv, vv, wen, ren in ((wl, wv, w_wen[k], w_ren[k]), (hl, hv, h_wen[k], h_ren[k])):
                lev = lv[k]
                do_write = wen and lev != caps[k]
                do_inner_read = lev != 0 and ((not vv[k]) or ren)
                if do_inner_read:
                    vv[k] = True
                elif ren:
                    vv[k] = False
                lev += (1 if do_write else 0) - (1 if do_inner_read else 0)
                lv[k] = lev
                held += lev + vv[k]
        self.held = held
        self.setup = setup_next
        self.st = st_next
        self.active = sum(1 for v in st_next if v)
        return accepted


def vp_standalone(oks, news, new_px, records: int, *, fifo_depth: int = HDL_FIFO_DEPTH,
                  max_cycles: int = 50_000_000, kp: int = 0, ke: int = KE_EDGES, engine: str | None = None) -> dict:
    """The Verilator bench's run of one processor: ``cycles`` (as the bench counts them),
    ``accept`` (cycle each record was taken, from the first cycle after reset), ``tests``,
    ``stalls`` per level. ``engine``: ``"python"`` (this code, the specification), ``"numba"`` (the
    compiled fast path, the same results), ``None`` / ``"auto"`` (:func:`choose_engine`)."""
    if choose_engine(engine) == "numba":
        cap0, cap = _check_params(fifo_depth, None, kp, ke)
        fast = _FAST.module()
        status, c, acc, tests, stalls = fast.standalone((oks, news, new_px), records, [cap0] + [cap] * len(oks),
                                                        int(kp), int(ke), max_cycles)
        if status:
            raise RasterhwError(f"sparse VP cycles: runaway {'feed' if status == fast.RUNAWAY_FEED else 'drain'}")
        return {"cycles": c, "accept": acc.tolist(), "tests": tests.tolist(), "stalls": stalls.tolist()}
    vp = VPCycleModel(oks, news, new_px, fifo_depth=fifo_depth, kp=kp, ke=ke)
    acc = []
    c = 0
    idx = 0
    # feed phase: valid while records remain; it ends on the cycle after the last is taken
    while idx < records:
        if vp.step(True):
            acc.append(c)
            idx += 1
        c += 1
        if c > max_cycles:
            raise RasterhwError("sparse VP cycles: runaway feed")
    vp.step(False)  # the bench's cycle that sees idx == ntri
    c += 1
    while vp.busy:  # drain: the bench counts the cycle on which busy is seen low
        vp.step(False)
        c += 1
        if c > max_cycles:
            raise RasterhwError("sparse VP cycles: runaway drain")
    return {"cycles": c + 1, "accept": acc, "tests": list(vp.tests), "stalls": list(vp.stalls)}


def coupled_matrix_vp(frame, depth: int, *, issue_interval: int = 1, fifo_depth: int = HDL_FIFO_DEPTH,
                      setup_fifo_depth: int | None = None, kp: int = 0, ke: int = KE_EDGES,
                      max_cycles: int = 100_000_000, engine: str | None = None) -> dict:
    """The coupled matrix of :mod:`.cycles` (same broadcast, FIFO and counting rules) with every
    processor the HDL video processor as built (:class:`VPCycleModel`) instead of a server: a
    processor takes the record at the head of its matrix FIFO on a cycle on which its set-up is
    idle (``i.ready``), and ``busy`` is the HDL's ``busy`` output. ``frame`` must be drawn with
    ``trace=True``. ``kp``, ``ke``: every processor prices its surface parameters as formula (5)
    (:class:`VPCycleModel`). Returns the keys of :meth:`~.cycles.CoupledResult.as_dict` plus ``accept``
    ((P, T) cycle each processor took each record) and ``broadcast`` ((T,)). ``engine``:
    ``"python"`` (this code, the specification), ``"numba"`` (the compiled fast path,
    :mod:`.vpcycles_fast`, the same results), ``None`` / ``"auto"`` (:func:`choose_engine`)."""
    D = _check_int("FIFO depth", depth, 1)
    g = _check_int("issue interval", issue_interval, 1)
    P = frame.p * frame.q
    T = frame.triangles
    if choose_engine(engine) == "numba":
        cap0, cap = _check_params(fifo_depth, setup_fifo_depth, kp, ke)
        streams = [vp_streams(frame, k) for k in range(P)]
        caps = [cap0] + [cap] * len(streams[0][0])
        status, c, offer, bc, acc, peak_a, busy_a, tests, stalls = _FAST.module().coupled(
            streams, T, D, g, caps, int(kp), int(ke), max_cycles)
        if status:
            raise RasterhwError("sparse VP cycles: runaway coupled frame")
        tests, stalls = tests.tolist(), stalls.tolist()
    else:
        c, offer, bc, acc, peak_a, busy_a, tests, stalls = _coupled_python(frame, D, g, fifo_depth, setup_fifo_depth,
                                                                           kp, ke, max_cycles)
    return {"frame_cycles": c, "stall_cycles": int((bc - offer).sum()), "fifo_peak": peak_a.tolist(),
            "fifo_peak_max": int(peak_a.max(initial=0)), "busy": busy_a.tolist(), "idle": (c - busy_a).tolist(),
            "depth": D, "issue_interval": g, "accept": acc, "broadcast": bc, "tests": tests, "stalls": stalls}


def _coupled_python(frame, D, g, fifo_depth, setup_fifo_depth, kp, ke, max_cycles):
    """:func:`coupled_matrix_vp`'s loop, the specification: ``(frame_cycles, offer, broadcast,
    accept, fifo_peak, busy, tests, stalls)``."""
    P = frame.p * frame.q
    T = frame.triangles
    vps = [VPCycleModel(*vp_streams(frame, k), fifo_depth=fifo_depth, setup_fifo_depth=setup_fifo_depth, kp=kp,
                        ke=ke) for k in range(P)]
    lev = [0] * P
    peak = [0] * P
    busy = [0] * P
    acc = np.zeros((P, T), dtype=np.int64)
    taken = [0] * P
    bc = np.zeros(T, dtype=np.int64)
    offer = np.zeros(T, dtype=np.int64)
    t = 0
    o = 0
    c = 0
    while True:
        vb = [vp.busy for vp in vps]
        if t == T and not any(lev) and not any(vb):
            break
        push = t < T and c >= o and max(lev) < D
        for k in range(P):
            if vb[k]:
                busy[k] += 1
            valid = lev[k] > 0
            if not valid and not vb[k]:
                continue  # an idle processor with nothing offered keeps its state
            if vps[k].step(valid):
                acc[k, taken[k]] = c
                taken[k] += 1
                lev[k] -= 1
        if push:
            offer[t], bc[t] = o, c
            t += 1
            o = c + g
            for k in range(P):
                lev[k] += 1
                if lev[k] > peak[k]:
                    peak[k] = lev[k]
        c += 1
        if c > max_cycles:
            raise RasterhwError("sparse VP cycles: runaway coupled frame")
    return (c, offer, bc, acc, np.array(peak, dtype=np.int64), np.array(busy, dtype=np.int64),
            [vp.tests for vp in vps], [vp.stalls for vp in vps])
