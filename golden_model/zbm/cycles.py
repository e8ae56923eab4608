"""ZB/M cycle model: the paper's Table 1 formula and an event-level count for any edge-pair stream.

Paper (seed 003, sec. 6.1), assumptions, our translation:
 1. each polygon is expanded into 2 edge pairs;  2. an edge pair is 5 x 5 = 25 pixels on
 average;  3. the ZB/M input clock is 25 MHz;  4. loading an edge pair into the segment
 generator takes 9 cycles;  5. while an edge pair is loaded the ZB/M gets no input: 9 idle
 cycles;  6. input to a ZB/M waits on average "the segment length per ZB/M" cycles, and takes 8
 cycles from the start of input;  7. half of the time is lost waiting, because of timing skew
 with the neighbouring ZB/M.
 => cycles per edge pair = 9 + (len_chip + 8) * 5, polygons/s = 25e6 / cycles / 2 / 2.

``len_chip`` is the segment length on the busiest chip: a 5-pixel segment spread over I
interleaved chips gives ceil(5 / I) = 5, 3, 2, 1, 1 pixels for I = 1, 2, 4, 8, 16 -- exactly
the paper's "average segment length per ZB/M" values (for I = 2 the chips get 3 and 2; the
segment is done when the busier chip is done).

Two counts of one unit: ``event_cycles`` applies the paper's stated conditions as rules R1, R2, R4, R5
(it does NOT describe our HDL); ``hdl_cycles`` is a cycle-stepped model of the control of
``hdl/zbm/unit.py`` and equals its pysim cycle count exactly (tests/zbm/test_zbm_unit_pysim.py).

Paper rules of ``event_cycles`` (``docs/zbm.md`` lists them):
 R1 a line starts by loading, from the input FIFO, every edge pair whose top line has been
    reached, while the active-edge-pair memory has room: 9 cycles each, no segment issued;
 R2 then the active pairs are read in memory order; a pair whose segment is empty after the
    fill rule and clipping costs 1 cycle; a non-empty segment is broadcast to all chips of the
    unit and costs ``max over chips (n_c + 8)`` = ``ceil(len / I) + 8`` cycles (a chip that owns
    none of its pixels drops it in 1 cycle; the busiest chip sets the pace);
 R4 the merge side streams each chip's ``ceil(W / I)`` pixels of the previous line, one per
    merge cycle, while the loop works on the current line (double-buffered pixel memories);
    a line ends when both are done (merge clock = segment clock unless ``merge_ratio`` given).
 R5 the skew of condition 7 is not modelled (chips of a unit are in lock-step); the formula's
    factor 2 is reported separately.
"""

from __future__ import annotations

import math

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import EdgePairs, segment_generator
from rasterhw.golden_model.zbm.formats import (
    AEP_CAPACITY,
    CHANNELS,
    EP_LOAD_CYCLES,
    GAP_PENDING,
    INTERLEAVES,
    PACKET_FLITS,
    SCHEDULES,
    check_interleave,
    paper_lead,
)
from rasterhw.golden_model.zbm.paper import PAPER_CLOCK_HZ, PAPER_LEN_CHIP

# table 1 (K polygons/s per unit) and its "average segment length per ZB/M": the paper's, with quotes
from rasterhw.golden_model.zbm.paper import PAPER_KPOLYS as PAPER_TABLE1_KPOLYS

__all__ = ["PAPER_TABLE1_KPOLYS", "PAPER_LEN_CHIP", "len_chip", "formula_cycles_per_edge_pair",
           "formula_polygons_per_s", "paper_table1", "event_cycles", "paper_workload", "hdl_cycles",
           "FIFO_LATENCY", "MERGE_OUT_LATENCY", "SCHEDULES", "paper_lead", "check_schedule"]

CLOCK_HZ = PAPER_CLOCK_HZ  # condition 3 (golden_model/zbm/paper.py)


def len_chip(seg_len: int, interleave: int) -> int:
    """Pixels of a ``seg_len``-pixel segment on the busiest of ``interleave`` chips."""
    check_interleave(interleave)
    if seg_len < 0:
        raise RasterhwError(f"segment length must be >= 0, not {seg_len!r}")
    return math.ceil(seg_len / interleave)


def formula_cycles_per_edge_pair(interleave: int, *, seg_len: int = 5, lines: int = 5,
                                 load: int = EP_LOAD_CYCLES, packet: int = PACKET_FLITS) -> int:
    """Paper's formula: ``load + (len_chip + packet) * lines`` (74, 64, 59, 54, 54)."""
    return load + (len_chip(seg_len, interleave) + packet) * lines


def formula_polygons_per_s(interleave: int, *, clock_hz: float = CLOCK_HZ, skew: float = 2.0,
                           eps_per_polygon: int = 2, units: int = 1, **kw) -> float:
    """Paper's throughput: ``clock / cycles / skew / eps_per_polygon * units``."""
    return clock_hz / formula_cycles_per_edge_pair(interleave, **kw) / skew / eps_per_polygon * units


def paper_table1() -> list[dict]:
    """Rows: interleave, len_chip, cycles, K polygons/s (formula), paper value, ratio."""
    rows = []
    for i in INTERLEAVES:
        k = formula_polygons_per_s(i) / 1e3
        rows.append({"interleave": i, "len_chip": len_chip(5, i), "cycles_per_edge_pair":
                     formula_cycles_per_edge_pair(i), "kpolys_formula": round(k, 1),
                     "kpolys_paper": PAPER_TABLE1_KPOLYS[i], "ratio": k / PAPER_TABLE1_KPOLYS[i]})
    return rows


def event_cycles(eps: EdgePairs, height: int, *, width: int = 512, interleave: int = 8,
                 capacity: int = AEP_CAPACITY, merge_ratio: float = 1.0) -> dict:
    """Count cycles of one unit (segment generator + ``interleave`` chips) under rules R1, R2, R4, R5.

    Returns totals (``loop_cycles``: R1 and R2 summed; ``frame_cycles``: with R4's overlap),
    per-line arrays and per-edge-pair averages.
    """
    check_interleave(interleave)
    if not merge_ratio > 0:
        raise RasterhwError(f"merge_ratio must be > 0, not {merge_ratio!r}")
    segs = segment_generator(eps, height, width=width, capacity=capacity)
    seg_cost = -(-segs.len // interleave) + PACKET_FLITS
    per_seg_line = np.bincount(segs.y, weights=seg_cost, minlength=height).astype(np.int64)
    load = segs.loads * EP_LOAD_CYCLES
    loop = load + per_seg_line + segs.empty
    merge_line = math.ceil(math.ceil(width / interleave) * merge_ratio)
    busy = np.flatnonzero(loop > 0)
    # R4: line y's loop overlaps the merge of line y-1 (only lines with work are merged here).
    frame = 0
    prev_merge = 0
    for y in busy:
        frame += max(int(loop[y]), prev_merge)
        prev_merge = merge_line
    frame += prev_merge
    n = max(len(eps), 1)
    return {"edge_pairs": len(eps), "segments": int(segs.y.size),
            "load_cycles": int(load.sum()), "segment_cycles": int(per_seg_line.sum()),
            "empty_cycles": int(segs.empty.sum()),
            "loop_cycles": int(loop.sum()), "frame_cycles": int(frame),
            "loop_cycles_per_edge_pair": float(loop.sum()) / n,
            "loop_per_line": loop, "merge_cycles_per_line": merge_line,
            "segment_stats": segs.stats}


def paper_workload(n_pairs: int, *, interleave_phase: int = 0, lines_apart: int = 5,
                   width: int | None = None) -> EdgePairs:
    """``n_pairs`` edge pairs of exactly 5 lines x 5 pixels (the paper's cond. 2), stacked so
    that each starts ``lines_apart`` lines below the previous (wrapping within 512 lines),
    left end at pixel ``interleave_phase`` + a per-pair shift (so all chip alignments occur);
    with ``width`` the left ends stay within ``0 .. width - 5``."""
    if n_pairs < 1:
        raise RasterhwError(f"n_pairs must be >= 1, not {n_pairs!r}")
    one = 1 << 40
    i = np.arange(n_pairs)
    y = (i * lines_apart) % (512 - 5)
    if width is not None and width < 5:
        raise RasterhwError(f"width must be >= 5, not {width!r}")
    x0 = (interleave_phase + 7 * i) % (400 if width is None else width - 4)
    o = np.argsort(y, kind="stable")
    z = np.zeros((n_pairs, 5), np.int64)
    return EdgePairs(y=y[o], h=np.full(n_pairs, 5), x=(x0[o] * one), dxdy=np.zeros(n_pairs, np.int64),
                     len=np.full(n_pairs, 5 * one), dlendy=np.zeros(n_pairs, np.int64),
                     val=z, ddy=z.copy(), ddx=z.copy(), tag=i[o])


# ====================================================================== the HDL's own timing
#: cycles from a word's write into the segment generator's input FIFO (``SyncFIFOBuffered``)
#: until the generator can read it
FIFO_LATENCY = 2
#: segment clocks from a chip's swap of line ``y`` to the clock after its merge output's last word of
#: that line, beyond the line's ``chip_pixels`` words (one a clock; outputs ready, merge clock = segment
#: clock): the merge-bus reader's first read the clock after the swap, its data register, the
#: AsyncFIFO's write and two-flop read synchroniser, the merger's output register, and the clock after
#: the transfer. Held line for line against the HDL by tests/zbm/test_zbm_driver.py::test_line_log_equals_cycle_model
MERGE_OUT_LATENCY = 6
#: ``"overlap"``: our design (the chip buffers a packet, loads overlap the loop's work);
#: ``"paper"``: the paper's sec. 6.1 schedule (a load leaves the loop idle 9 cycles, nothing
#: runs ahead of the loop), see ``docs/zbm.md#paper-schedule``.
def check_schedule(schedule: str) -> str:
    if schedule not in SCHEDULES:
        raise RasterhwError(f"schedule must be 'overlap' or 'paper', not {schedule!r}")
    return schedule


def _line_entries(eps: EdgePairs, segs, height: int) -> list[list[tuple[int, int, int]]]:
    """Per line, the active pairs in memory order (= FIFO order: appended in order, compacted
    in place): (x, len, keep) with len = 0 for an empty segment, keep = written back."""
    out = []
    for y in range(height):
        act = np.flatnonzero((eps.y <= y) & (y < eps.y + eps.h))
        sl = segs.line(y)
        seg = {int(e): (int(x), int(n)) for e, x, n in zip(segs.ep[sl], segs.x[sl], segs.len[sl], strict=True)}
        out.append([(*seg.get(int(i), (0, 0)), int(eps.y[i] + eps.h[i] - y > 1)) for i in act])
    return out


def hdl_cycles(eps: EdgePairs, height: int, *, width: int = 512, interleave: int = 8,
               capacity: int = AEP_CAPACITY, schedule: str = "overlap",
               max_cycles: int = 10_000_000) -> dict:
    """Cycle-exact count of one ``hdl/zbm/unit.py`` unit on ``eps`` (one frame).

    A cycle-stepped model of the control of ``ZbmSegmentGenerator``, the unit's broadcast
    and each ``ZbmChip`` (initial processor, segment processor and ring spacing, line swap,
    merge-bus reader); data values are not modelled. Assumptions (as the tests and
    ``sim/zbm/cycles_hdl.py`` run it): the edge-pair words are offered one per cycle from
    cycle 0 (word k readable in cycle ``k + FIFO_LATENCY`` at the earliest), the merge outputs
    are always ready and the merge clock equals the segment clock (the merge-bus reader never
    waits). Returns ``cycles`` = the first cycle in which every chip has swapped the last
    line (``ZbmUnit.lines == height``), ``seggen_done`` = cycle of the last end-of-line word,
    per-cause counts of the generator's cycles and ``line_cycles`` ((height,) int64: per line, the
    clock after the last merge word of that line left every chip, each chip's swap + its pixels +
    :data:`MERGE_OUT_LATENCY`: the per-line log of a scene run, ``sim/zbm/testbench.py:
    UnitBench.line_cycles``; its last entry is the run's ``cycles``).

    ``schedule="paper"`` models the paper-schedule configuration (``schedule="paper"`` of the
    HDL blocks): a chip takes a segment header only when its ring gap (cycles until the ring
    could start a packet; ``GAP_PENDING`` while a packet waits in the chip) is at most
    ``paper_lead(mode)``, and the generator starts a load only when every chip's gap is at
    most ``paper_lead(mode) + 1`` -- the 9 load cycles then leave the ring idle for exactly 9
    cycles (``count["wait_zbm"]`` counts the generator's cycles waiting for that).
    """
    check_interleave(interleave)
    paper = check_schedule(schedule) == "paper"
    lead = paper_lead(int(eps.mode))
    segs = segment_generator(eps, height, width=width, capacity=capacity)   # raises if over capacity
    lines = _line_entries(eps, segs, height)
    n_words = 9 * len(eps) + 1
    n_flits = len(CHANNELS[eps.mode])
    lg = interleave.bit_length() - 1
    ni = interleave
    # generator registers
    st, y, n_mem, r, w, c, word, k = "CHECK", 0, 0, 0, 0, 0, 0, 0
    gen_done = None
    # chip registers (lists over chips)
    npx = [-(-(width - ch) // ni) for ch in range(ni)]
    recv = [0] * ni
    keep = [0] * ni
    n_pend = [0] * ni        # pixels of the packet being received
    pkt_valid = [0] * ni
    pkt_n = [0] * ni
    eol = [0] * ni
    full = [0] * ni
    buf_n = [0] * ni
    inj = [0] * ni
    wait = [0] * ni
    q = list(npx)
    dv = [0] * ni
    nlines = [0] * ni
    swaps = [[] for _ in range(ni)]   # per chip, the cycle of each line's swap
    count = {"check": 0, "load": 0, "seg_words": 0, "empty": 0, "eol": 0, "wait_chips": 0, "wait_zbm": 0}
    t = 0
    while min(nlines) < height:
        if t >= max_cycles:
            raise RasterhwError("hdl_cycles: no progress (model bug)")
        # ---------------- generator: what it offers this cycle
        r_rdy = k < n_words and t >= k + FIFO_LATENCY
        ent = lines[y][r - 1] if st in ("SEG", "FLIT") else None
        o_valid = (st == "SEG" and ent[1] > 0) or st in ("FLIT", "EOL")
        # ---------------- chips: comb
        gap = [GAP_PENDING if pkt_valid[ch] or (full[ch] and inj[ch] == 0) else wait[ch] for ch in range(ni)]
        hdr_word = st == "SEG"          # a segment header is offered (o_valid checked below)
        i_ready = [not pkt_valid[ch] and eol[ch] != 2 and not (paper and hdr_word and gap[ch] > lead)
                   for ch in range(ni)]
        all_ready = all(i_ready)
        xfer = o_valid and all_ready
        swap = [eol[ch] != 0 and not full[ch] and wait[ch] <= 1 and q[ch] == npx[ch] and not dv[ch]
                for ch in range(ni)]
        # ---------------- chips: update
        for ch in range(ni):
            accept = pkt_valid[ch] and (eol[ch] == 0 or (eol[ch] == 1 and swap[ch])) and not full[ch]
            start = full[ch] and inj[ch] == 0 and wait[ch] == 0
            injecting = full[ch] and (inj[ch] != 0 or start)
            eol_in = 0
            nrecv, nkeep, npv = recv[ch], keep[ch], pkt_valid[ch]
            if xfer:
                if recv[ch] == 0:
                    if st == "EOL":
                        eol_in = 1
                    else:
                        x, ln = ent[0], ent[1]
                        jj = (ch - x) % ni
                        n = ((ln - jj + ni - 1) >> lg) if ln > jj else 0
                        nrecv, nkeep, n_pend[ch] = n_flits, int(n != 0), n
                else:
                    nrecv = recv[ch] - 1
                    if recv[ch] == 1 and keep[ch]:
                        npv, pkt_n[ch] = 1, n_pend[ch]
            if accept:
                npv = 0
                full[ch], buf_n[ch], inj[ch] = 1, pkt_n[ch], 0
            if wait[ch] != 0:
                wait[ch] -= 1
            if start:
                wait[ch] = buf_n[ch] + PACKET_FLITS - 1
            if injecting:
                inj[ch] += 1
                if inj[ch] == PACKET_FLITS:
                    full[ch], inj[ch] = 0, 0
            recv[ch], keep[ch], pkt_valid[ch] = nrecv, nkeep, npv
            eol[ch] += eol_in - swap[ch]
            rd = q[ch] != npx[ch]
            dv[ch] = int(rd)
            q[ch] += rd
            if swap[ch]:
                q[ch] = 0
                nlines[ch] += 1
                swaps[ch].append(t)
        # ---------------- generator: update
        if o_valid and not xfer:
            count["wait_chips"] += 1

        def retire(ent=ent):
            nonlocal w, st, n_mem, r
            w += ent[2]
            if r == n_mem:
                st, n_mem = "EOL", w
            else:
                r += 1
                st = "SEG"

        if st == "CHECK":
            count["check"] += 1
            if r_rdy:
                marker = k == n_words - 1
                i = k // 9
                if not marker and eps.y[i] <= y:
                    assert n_mem < capacity
                    if paper and max(gap) > lead + 1:
                        count["wait_zbm"] += 1      # cond. 5: load only when the ZB/M runs dry
                    else:
                        k += 1
                        word = 1
                        st = "LOAD"
                elif n_mem == 0:
                    st = "EOL"
                else:
                    r, w, st = 1, 0, "SEG"
        elif st == "LOAD":
            count["load"] += 1
            if r_rdy:
                k += 1
                if word == 8:
                    n_mem += 1
                    st = "CHECK"
                word += 1
        elif st == "SEG":
            if ent[1] > 0:
                if xfer:
                    count["seg_words"] += 1
                    c, st = 0, "FLIT"
            else:
                count["empty"] += 1
                retire()
        elif st == "FLIT":
            if xfer:
                count["seg_words"] += 1
                c += 1
                if c == n_flits:
                    retire()
        elif st == "EOL":
            if xfer:
                count["eol"] += 1
                if y == height - 1:
                    st, gen_done = "FRAME_END", t
                else:
                    y, st = y + 1, "CHECK"
        t += 1
    # ``lines`` reaches height the cycle after the last swap: that cycle's number is t.
    n = max(len(eps), 1)
    sw = np.asarray(swaps, np.int64)                                  # (chips, height)
    return {"cycles": t, "edge_pairs": len(eps), "cycles_per_edge_pair": t / n,
            "seggen_done": gen_done, "generator": count,
            "line_cycles": (sw + np.asarray(npx, np.int64)[:, None] + MERGE_OUT_LATENCY).max(axis=0)}
