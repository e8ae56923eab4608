"""Cycle models of the matrix: each video processor's cycles per broadcast record, and the
coupled matrix (one broadcast, a FIFO in front of every processor, the slowest holding it back).

Seed 002 (fig. 1): "Геометрический процессор ... выдает описания геометрических примитивов всем
видеопроцессорам матрицы в режиме Broadcast. Описания определяют очереди на входах растровых
процессоров" -- every processor has an input FIFO ("Память типа FIFO на входе хранит очередь
описаний геометрических примитивов"). The paper's load and efficiency figures assume that the
coupling through the common input is small "при малой размерности матрицы и достаточном объеме
FIFO"; :func:`coupled_matrix` measures it.

Per-record service time (cycles a processor spends on one record)
-----------------------------------------------------------------
Priced from the golden search's per-record window counts ``w[k, t, i]`` (processor ``k``,
record ``t``, windows leaving level ``i``; ``w[..., 0] = 1``; level ``n`` counts pixels), with
τ = one cycle per coverage test as the HDL stage (``hdl/sparse/stage.py``):

* stage ``i`` of the pipeline on record ``t``: ``4 w_(i-1)`` tests, plus one cycle for the
  triangle's header where it has survivors (``w_i > 0``; the HDL's header cycle), plus
  ``ceil(w_i k_p / k_e)`` cycles for the surface-parameter additions when they are priced
  (formula (5)'s ``w_i k_p / k_e`` term: ``k_p`` parameter planes stepped on the ``k_e`` edge
  adders; our HDL steps depth in the test cycle, so it prices them at 0: ``kp=0``).
* ``vp="pipeline"``: the record holds the processor for its busiest stage's cycles (formula (9):
  "производительность ... равна производительности каскада конвейера с наибольшим временем
  обработки многоугольника"), at least the set-up's ``SETUP_CYCLES``. This is the paper's
  pipeline as a server; the HDL video processor also overlaps consecutive records across its
  stages (its inner FIFOs), which this abstraction does not.
* ``vp="stack"``: the stack-based raster processor (one coverage-test unit and a stack of
  windows, depth first): ``SETUP_CYCLES`` plus every stage's cycles without header cycles,
  ``sum_i (4 w_(i-1) + ceil(w_i k_p / k_e))`` -- formula (6)'s ``T(S) = sum t_i``. Exact for a
  processor that takes its next record only when it has finished this one.

Cycle semantics of the coupled matrix (what an HDL implements to be cycle-exact with it)
-----------------------------------------------------------------------------------------
Cycles are numbered from 0; every state change happens at the clock edge that ends a cycle.

* The geometry processor (GP) offers record 0 on cycle 0 and record ``t + 1`` on cycle
  ``b_t + g`` (``g = issue_interval``, OURS: the paper gives no GP rate; ``g = 1`` by default,
  so the broadcast is never the bottleneck and every stall is the processors').
* FIFO level ``L_k(c)`` is the registered level at the start of cycle ``c`` (pushes at edges
  ``< c`` minus pops at edges ``< c``). The GP's record is broadcast on the first cycle
  ``c >= offer`` on which ``L_k(c) < D`` for every processor ``k`` (``w_rdy = level != depth``,
  registered: a pop in the same cycle does not make room for the push). ``b_t`` is that cycle;
  the record is pushed into all ``p*q`` FIFOs at its end.
* A pushed record is visible to its processor from cycle ``b_t + 1``. Processor ``k`` pops record
  ``t`` on cycle ``pop[k, t] = max(b_t + 1, pop[k, t-1] + s[k, t-1])``: the first cycle on which
  its FIFO holds the record and it has finished the previous one (a record popped on cycle ``c``
  holds the processor on cycles ``c .. c + s - 1``). The pop happens at the end of that cycle.
* ``stall_cycles = sum_t (b_t - offer_t)``: cycles a ready record waited for a full FIFO.
* ``fifo_peak[k]``: the largest registered level, ``max_t (t + 1 - #{u : pop[k, u] <= b_t})``
  (levels peak right after a push), never above ``D``.
* ``frame_cycles``: the cycle on which the last processor becomes free after its last record,
  ``max_k (pop[k, T-1] + s[k, T-1])``; ``busy[k] = sum_t s[k, t]``, ``idle = frame - busy``.
* The video controller's read-out of the interleaved local memories is a separate phase:
  ``readout_cycles = W*H`` at one pixel per cycle (OURS; the paper gives no rate).

With ``D`` at least the record count the broadcast never waits and
``frame = max_k max_t (t g + 1 + sum_(u >= t) s[k, u])`` (``= 1 + max_k sum_t s[k, t]`` when
``g <= min s``): the slowest processor's own time plus the one-cycle push.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rasterhw.golden_model.errors import RasterhwError

__all__ = ["GP_ISSUE_INTERVAL", "KE_EDGES", "SETUP_CYCLES", "CoupledResult", "coupled_matrix", "matrix_cycles",
           "service_times", "stage_cycles"]

#: the HDL set-up FSM (``hdl/sparse/vp.py``): accept the record, push the header, push the root window
SETUP_CYCLES = 3
#: OURS, not the paper's: cycles between two records the geometry processor can offer
GP_ISSUE_INTERVAL = 1
#: edges of a triangle: formula (5)'s k_e
KE_EDGES = 3


def _check_w(w: np.ndarray) -> np.ndarray:
    w = np.asarray(w)
    if w.ndim != 3 or w.shape[2] < 2 or not np.issubdtype(w.dtype, np.integer) or (w.size and w.min() < 0):
        raise RasterhwError("sparse cycles: windows per record must be a non-negative integer array "
                            f"(processors, records, n + 1), not shape {w.shape} dtype {w.dtype}")
    return w.astype(np.int64)


def _check_int(name: str, v, lo: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
        raise RasterhwError(f"sparse cycles: {name} must be an integer >= {lo}, not {v!r}")
    return int(v)


def stage_cycles(w: np.ndarray, *, kp: int = 0, ke: int = KE_EDGES, headers: bool = True) -> np.ndarray:
    """``(P, T, n)`` cycles of stage ``i`` (1..n) per processor and record: ``4 w_(i-1)`` tests,
    ``[w_i > 0]`` header cycles (``headers``), ``ceil(w_i kp / ke)`` parameter cycles."""
    w = _check_w(w)
    kp, ke = _check_int("kp", kp, 0), _check_int("ke", ke, 1)
    c = 4 * w[:, :, :-1]
    if headers:
        c = c + (w[:, :, 1:] > 0)
    if kp:
        c = c + -(-w[:, :, 1:] * kp // ke)
    return c


def service_times(w: np.ndarray, *, vp: str = "pipeline", kp: int = 0, ke: int = KE_EDGES) -> np.ndarray:
    """``(P, T)`` cycles each processor is held by each record (see the module docstring)."""
    if vp == "pipeline":
        return np.maximum(stage_cycles(w, kp=kp, ke=ke).max(axis=2), SETUP_CYCLES)
    if vp == "stack":
        return SETUP_CYCLES + stage_cycles(w, kp=kp, ke=ke, headers=False).sum(axis=2)
    raise RasterhwError(f"sparse cycles: vp must be 'pipeline' or 'stack', not {vp!r}")


@dataclass
class CoupledResult:
    """The coupled matrix on one frame (cycle numbers as in the module docstring).

    frame_cycles, stall_cycles : int.
    fifo_peak : (P,) int — each processor's largest FIFO level.
    busy, idle : (P,) int — cycles holding a record / not, over the frame.
    offer, broadcast : (T,) int — cycle each record was offered / pushed.
    pop : (P, T) int — cycle each processor popped each record.
    depth, issue_interval : the FIFO depth and the GP's issue interval of the run.
    """

    frame_cycles: int
    stall_cycles: int
    fifo_peak: np.ndarray
    busy: np.ndarray
    idle: np.ndarray
    offer: np.ndarray
    broadcast: np.ndarray
    pop: np.ndarray
    depth: int
    issue_interval: int

    def as_dict(self) -> dict:
        return {"frame_cycles": self.frame_cycles, "stall_cycles": self.stall_cycles,
                "fifo_peak": self.fifo_peak.tolist(), "fifo_peak_max": int(self.fifo_peak.max(initial=0)),
                "busy": self.busy.tolist(), "idle": self.idle.tolist(), "depth": self.depth,
                "issue_interval": self.issue_interval}


def coupled_matrix(service: np.ndarray, depth: int, *, issue_interval: int = GP_ISSUE_INTERVAL) -> CoupledResult:
    """One broadcast into ``P`` FIFOs of ``depth`` entries, processor ``k`` holding record ``t``
    for ``service[k, t]`` cycles (>= 1). Loops over records, vectorised over processors."""
    s = np.asarray(service)
    if s.ndim != 2 or not np.issubdtype(s.dtype, np.integer) or (s.size and s.min() < 1):
        raise RasterhwError(f"sparse cycles: service times must be integers >= 1 of shape (processors, records), "
                            f"not shape {s.shape} dtype {s.dtype}")
    D = _check_int("FIFO depth", depth, 1)
    g = _check_int("issue interval", issue_interval, 1)
    s = s.astype(np.int64)
    P, T = s.shape
    offer = np.zeros(T, dtype=np.int64)
    bc = np.zeros(T, dtype=np.int64)
    pop = np.zeros((P, T), dtype=np.int64)
    free = np.zeros(P, dtype=np.int64)
    o = 0
    for t in range(T):
        b = o
        if t >= D:  # room in every FIFO: record t - D popped on an earlier cycle
            b = max(b, int(pop[:, t - D].max()) + 1)
        offer[t], bc[t] = o, b
        pk = np.maximum(free, b + 1)
        pop[:, t] = pk
        free = pk + s[:, t]
        o = b + g
    frame = int(free.max()) if T else 0
    peak = np.zeros(P, dtype=np.int64)
    if T:
        cnt = np.arange(1, T + 1)
        for k in range(P):
            peak[k] = int((cnt - np.searchsorted(pop[k], bc, side="right")).max())
    busy = s.sum(axis=1)
    return CoupledResult(frame_cycles=frame, stall_cycles=int((bc - offer).sum()), fifo_peak=peak, busy=busy,
                         idle=frame - busy, offer=offer, broadcast=bc, pop=pop, depth=D, issue_interval=g)


def matrix_cycles(frame, depth: int, *, vp: str = "pipeline", kp: int = 0, ke: int = KE_EDGES,
                  issue_interval: int = GP_ISSUE_INTERVAL) -> dict:
    """The coupled matrix on a :class:`~rasterhw.golden_model.sparse.search.SparseFrame` drawn with
    ``per_record=True``: the :class:`CoupledResult` as a dict, plus per-stage busy cycles of every
    processor (``stage_busy``, (P, n)), ``readout_cycles`` and the standalone (uncoupled) time of
    the slowest processor (``slowest_alone = 1 + max_k sum_t s``)."""
    w = frame.stats.get("windows_per_record")
    if w is None:
        raise RasterhwError("sparse cycles: the frame was drawn without per_record=True")
    s = service_times(w, vp=vp, kp=kp, ke=ke)
    r = coupled_matrix(s, depth, issue_interval=issue_interval)
    out = r.as_dict()
    sb = stage_cycles(w, kp=kp, ke=ke, headers=(vp == "pipeline")).sum(axis=1)
    out.update({"vp": vp, "kp": kp, "ke": ke, "stage_busy": sb.tolist(), "slowest_alone": int(1 + s.sum(axis=1).max()),
                "readout_cycles": int(frame.tri_id.size), "matrix": f"{frame.p}x{frame.q}", "n": frame.n,
                "records": int(s.shape[1])})
    return out
