"""Hidden-surface removal: the paper's algorithm 1 and algorithm 2, vectorised its way.

NumPy plays the vector unit: one NumPy call on an array is one vector instruction, and the
counters below count those "vector passes" and their lengths.

**Algorithm 1** (2.3.2 2)(i)) -- per scan line ``y``: drop the exited segments from the
x-list, append the y-list(y) segments, clear a one-line Z-buffer, then *for every x-list
segment* Z-test its span with vector length = span length (a Python loop over segments, each
test whole-array over the span's pixels: the paper's short vectors), and finally step every
x-list edge at once (whole-array over the x-list: "処理速度の向上に寄与しているのは、主として
稜線の更新処理である"). Lines with no segment are bypassed. With ``full_frame=True`` the
Z-buffer is one frame cleared once (the ray-casting runs, table 6).

**Algorithm 2** (2.3.2 2)(ii), fig. 2) -- full-frame Z-buffer; while processable segments
remain: (1) drop exited segments from the s-list, (2) where slist(y) is empty and ylist(y) is
not, take ylist(y)'s head, (3) Z-test all non-empty slots at once, masked, repeating for the
longest segment's span length, (4) step the edges, slist(i+1) <- slist(i), slist(0) <- empty.
Slot ``y`` always holds the segment being drawn on line ``y`` (asserted every pass), so a pass
touches each line at most once: no recurrent Z-buffer references within a vector. The mask of
step k ("k < span length") is applied as a prefix: the pass's slots are ordered by span length
once, so every masked step is a slice of the pass's vectors (same elements, same order of
writes per pixel, since no two slots share a line).

Both write the same outputs: ``depth`` (H, W) (+inf = the Z-buffer's "maximum"), ``qid`` (H, W)
screen-polygon index (-1 = background), ``inten`` (H, W) intensity. ``mode="shadow"`` runs
shadow segments against a finished Z-buffer instead, adding ``sign`` (+1 front, -1 back) into
a count buffer where ``z < Z-buffer``; ``mode="depth"`` writes depth only (the light-space
pass of ray casting).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.vzbuf.segments import SegmentBlock, span_from_n, ylist

__all__ = ["Counters", "algorithm1", "algorithm2", "new_buffers"]


@dataclass
class Counters:
    """Vector passes and lengths (one NumPy call on an array = one vector instruction)."""

    passes: int = 0               # alg 1: lines processed; alg 2: loop iterations
    ztests: int = 0               # Z-test vector steps (alg 1: one per span; alg 2: one per k)
    elements: int = 0             # pixels Z-tested
    masked_off: int = 0           # alg 2: slots masked off inside a Z-test step
    written: int = 0              # pixels that passed the Z test (Z-buffer writes)
    edge_updates: int = 0         # edge-update vector steps
    edge_elements: int = 0        # elements in them
    max_slots: int = 0            # alg 2: largest s-list occupancy
    t_ztest: float = 0.0          # fig. 3 "hidden-surface removal": span set-up and Z tests (s)
    t_update1: float = 0.0        # fig. 3 update 1: edge updates (s)
    t_update2: float = 0.0        # fig. 3 update 2: segments entering and leaving (s)
    slot_hist: list = field(default_factory=list)

    @property
    def mean_vector_length(self) -> float:
        return self.elements / self.ztests if self.ztests else 0.0

    def as_dict(self) -> dict:
        return {"passes": self.passes, "ztests": self.ztests, "elements": self.elements,
                "masked_off": self.masked_off, "written": self.written, "edge_updates": self.edge_updates,
                "edge_elements": self.edge_elements, "max_slots": self.max_slots,
                "t_ztest": self.t_ztest, "t_update1": self.t_update1, "t_update2": self.t_update2,
                "mean_vector_length": self.mean_vector_length}



def _step(values: tuple, steps: tuple, edges: np.ndarray) -> None:
    """One line down for ``edges``: every per-edge value (x, z, intensity, normal) += its step."""
    for v, d in zip(values, steps, strict=True):
        v[edges] += d[edges]

def new_buffers(width: int, height: int) -> dict:
    return {"depth": np.full((height, width), np.inf), "qid": np.full((height, width), -1, np.int64),
            "inten": np.zeros((height, width)), "count": np.zeros((height, width), np.int64)}


def _state(seg: SegmentBlock):
    e = seg.edges
    return e.x.copy(), e.z.copy(), e.i.copy(), e.n.copy()


def algorithm1(seg: SegmentBlock, width: int, height: int, buf: dict, *, mode: str = "real",
               sign: np.ndarray | None = None, full_frame: bool = False, zline_of: np.ndarray | None = None,
               counters: Counters | None = None, trace=None) -> Counters:
    """Algorithm 1 over ``seg`` into ``buf`` (see the module docstring); ``trace`` (a
    :class:`~.trace.Trace`) records the paper's loops as they run."""
    c = counters or Counters()
    if seg.n == 0:
        return c
    head, nxt = ylist(seg, height)
    ex, ez, ei, en = _state(seg)
    e = seg.edges
    dxdy, dzdy, didy, dn, ss = e.dxdy, e.dzdy, e.didy, e.dn, e.ss
    yend, left, right, dzdx, part, parts = seg.yend, seg.left, seg.right, seg.dzdx, seg.part, seg.parts
    depth, qid, inten, count = buf["depth"], buf["qid"], buf["inten"], buf["count"]
    poly = seg.poly
    active = np.zeros(0, np.int64)
    zline = np.empty(width)
    clk = time.process_time
    for y in range(height):
        ta = clk()
        if trace is not None:
            trace.scalar("line loop", 1)
            trace.loop("a1 drop exited", active.size)
        if active.size:
            active = active[yend[active] >= y]
        s = head[y]
        if s >= 0:
            new = []
            while s >= 0:
                new.append(s)
                s = nxt[s]
            active = np.concatenate([active, np.asarray(new, np.int64)])
            if trace is not None:
                trace.scalar("x-list append", len(new))
        tb = clk()
        c.t_update2 += tb - ta
        if active.size == 0:
            continue
        c.passes += 1
        L, R = left[active], right[active]
        lo, hi = span_from_n(en[L], ss[L], en[R], ss[R], part[active], parts[active], width)
        xl, zl, il, xr, ir = ex[L], ez[L], ei[L], ex[R], ei[R]
        with np.errstate(divide="ignore", invalid="ignore"):
            didx = np.where(xr > xl, (ir - il) / (xr - xl), 0.0)
        if trace is not None:
            trace.scalar("line set-up", 1)
            if mode == "real" and not full_frame:
                trace.loop("clear", width)
            trace.loop("a1 span set-up", active.size)
            trace.scalar("span loop set-up", active.size)
            if mode == "real":
                trace.scalar("shading decision", active.size)
            trace.loops_of(f"a1 z-test {mode}", hi - lo + 1)
            trace.loop("edge update", 2 * active.size)
        if mode == "real":
            zrow = depth[y] if full_frame else zline
            if not full_frame:
                zrow.fill(np.inf)
            irow, qrow = inten[y], qid[y]
        elif mode == "shadow":
            zrow = zline_of[y] if zline_of is not None else depth[y]
            crow = count[y]
        else:
            zrow = depth[y]
        for k in range(active.size):
            a, b = int(lo[k]), int(hi[k]) + 1
            if b <= a:
                continue
            xc = np.arange(a, b) + 0.5 - xl[k]
            z = zl[k] + dzdx[active[k]] * xc
            win = z < zrow[a:b]
            c.ztests += 1
            c.elements += b - a
            c.written += int(np.count_nonzero(win))
            if mode == "real":
                zrow[a:b][win] = z[win]
                qrow[a:b][win] = poly[active[k]]
                irow[a:b][win] = (il[k] + didx[k] * xc)[win]
            elif mode == "shadow":
                crow[a:b][win] += sign[active[k]]
            else:
                zrow[a:b][win] = z[win]
        if mode == "real" and not full_frame:
            depth[y] = zline
        tc = clk()
        c.t_ztest += tc - tb
        # step the edges of every x-list segment at once
        both = np.concatenate([L, R])
        _step((ex, ez, ei, en), (dxdy, dzdy, didy, dn), both)
        c.edge_updates += 4
        c.edge_elements += 4 * both.size
        c.t_update1 += clk() - tc
    return c


def algorithm2(seg: SegmentBlock, width: int, height: int, buf: dict, *, mode: str = "real",
               sign: np.ndarray | None = None, counters: Counters | None = None, trace=None) -> Counters:
    """Algorithm 2 over ``seg`` into ``buf`` (see the module docstring); ``trace`` records the
    paper's loops (vector length = scan lines or occupied slots, masked Z-test steps)."""
    c = counters or Counters()
    if seg.n == 0:
        return c
    head, nxt = ylist(seg, height)
    ptr = head.copy()
    ex, ez, ei, en = _state(seg)
    e = seg.edges
    dxdy, dzdy, didy, dn, ss = e.dxdy, e.dzdy, e.didy, e.dn, e.ss
    yend, left, right, dzdx, part, parts, poly = (seg.yend, seg.left, seg.right, seg.dzdx, seg.part,
                                                   seg.parts, seg.poly)
    crow = seg.y0.copy()          # the line each segment is on (for the one-per-line assertion)
    depth = buf["depth"].reshape(-1)
    qid, inten, count = buf["qid"].reshape(-1), buf["inten"].reshape(-1), buf["count"].reshape(-1)
    slist = np.full(height, -1, np.int64)
    clk = time.process_time
    while True:
        ta = clk()
        if trace is not None:
            trace.scalar("pass control", 1)
            trace.loop("a2 drop exited", height)
            trace.loop("a2 take y-list head", height)
            trace.loop("a2 collect slots", height)
        # (1) drop exited segments
        ys = np.flatnonzero(slist >= 0)
        if ys.size:
            gone = yend[slist[ys]] < ys
            slist[ys[gone]] = -1
        # (2) empty slot and a waiting y-list: take its head
        fill = np.flatnonzero((slist < 0) & (ptr >= 0))
        if fill.size:
            slist[fill] = ptr[fill]
            ptr[fill] = nxt[ptr[fill]]
        ys = np.flatnonzero(slist >= 0)
        if ys.size == 0:
            c.t_update2 += clk() - ta
            break
        segs = slist[ys]
        assert np.array_equal(crow[segs], ys), "algorithm 2: an s-list slot holds a segment of another line"
        c.passes += 1
        c.max_slots = max(c.max_slots, int(ys.size))
        c.slot_hist.append(int(ys.size))
        tb = clk()
        c.t_update2 += tb - ta
        # (3) masked Z-test of every slot at once, k = 0 .. longest span - 1
        L, R = left[segs], right[segs]
        lo, hi = span_from_n(en[L], ss[L], en[R], ss[R], part[segs], parts[segs], width)
        ln = np.maximum(hi - lo + 1, 0)
        xl, zl, il, xr, ir = ex[L], ez[L], ei[L], ex[R], ei[R]
        with np.errstate(divide="ignore", invalid="ignore"):
            didx = np.where(xr > xl, (ir - il) / (xr - xl), 0.0)
        # The mask "k < span length" is a prefix once the slots are ordered by span length
        # (longest first): each masked step is then a slice of the pass's vectors.
        o = np.argsort(-ln, kind="stable")
        ln_o = ln[o]
        lo_o, xl_o, zl_o = lo[o], xl[o], zl[o]
        dz_o = dzdx[segs][o]
        base_o = ys[o] * width + lo_o
        if mode == "real":
            il_o, did_o, q_o = il[o], didx[o], poly[segs][o]
        elif mode == "shadow":
            sg_o = sign[segs][o]
        mx = int(ln_o[0]) if ln_o.size else 0
        if trace is not None:
            trace.loop("a2 span set-up", ys.size)
            trace.loop(f"a2 z-test {mode}", ys.size, times=mx)   # every slot, masked, mx times
            trace.scalar("z-test step", mx)
            trace.loop("edge update", 2 * ys.size)
            trace.loop("a2 shift s-list", height)
        live = ln_o.size - np.searchsorted(ln_o[::-1], np.arange(mx), side="right")
        for k in range(mx):
            m = int(live[k])
            pix = base_o[:m] + k
            xc = (lo_o[:m] + k) + 0.5 - xl_o[:m]
            z = zl_o[:m] + dz_o[:m] * xc
            win = z < depth[pix]
            c.ztests += 1
            c.elements += m
            c.masked_off += ys.size - m
            c.written += int(np.count_nonzero(win))
            if mode == "real":
                p = pix[win]
                depth[p] = z[win]
                qid[p] = q_o[:m][win]
                inten[p] = (il_o[:m] + did_o[:m] * xc)[win]
            elif mode == "shadow":
                count[pix[win]] += sg_o[:m][win]
            else:
                depth[pix[win]] = z[win]
        tc = clk()
        c.t_ztest += tc - tb
        # (4) step the edges, shift the s-list one line down
        both = np.concatenate([L, R])
        _step((ex, ez, ei, en), (dxdy, dzdy, didy, dn), both)
        crow[segs] += 1
        c.edge_updates += 5
        c.edge_elements += 4 * both.size + segs.size
        td = clk()
        c.t_update1 += td - tc
        slist[1:] = slist[:-1].copy()
        slist[0] = -1
        c.t_update2 += clk() - td
    return c
