"""The span PXP HDL's golden side: its DMM/P contents, its visible segments and its exact cycles.

``hdl/experts/pxp_span.py`` is the paper's PXP (span cull and depth search per span, rules of
:mod:`span`) behind its own DMM/P. This module states, in plain Python, what it does line by line
and how many cycles each step takes, so the HDL can be checked pixel for pixel and cycle for cycle.

**DMM/P contents** (:func:`dmm_line`), as the SLP writes them: the line's whole ASL in ASL order
(every record of the line, sorted on (xL, PL order), :mod:`slp_run`'s order), then the range's
block boundary bucket list, then the ``last`` token carrying the block leading segment pointer --
both lists from :func:`slp_run.block_lists` (the golden SLP's walk of the finished ASL), for the
range widened by the A.J. guard pixel each side.

**Resolve cycles of one line** (:func:`resolve`; from the cycle the PXP finds the bank full to the
cycle before it hands the DSLB bank over), every term:

* ``init`` 1: take the bank (range, counts, leading pointer).
* per span, ``cull`` = ``k_old``: one cycle per segment present in the span before (it stays or
  leaves); ``enter`` = ``entered + skipped + 1``: one per candidate entering at the span's left
  pixel (bucket list first, then the ASL from the leading pointer while its first pixel is before
  the guarded range's end), one per candidate with no pixel in the range, one to set the span's
  right end ``r = min(nearest end, next start, range end) - 1``.
* per (sub)span searched (``k >= 2``): ``pass_a`` = ``k`` (z at both end pixels, nearest at the
  left), ``pass_b`` = ``k`` if the (sub)span is wider than one pixel (the guarded tests); a failed
  test halves it at ``(l + r + 1) >> 1`` and both halves are searched, the left first.
* ``write`` = one cycle per pixel of the guarded range (every pixel is written exactly once: by
  the visible segment of its (sub)span, or as background).

**Line schedule** (:func:`schedule`, the input back to back and the output always ready; cycle =
the edge index, edge 0 takes the first word): line ``k`` has ``w_k`` words (ASL, bucket list,
token), resolve cycles ``r_k`` and drain cycles ``d_k`` (:func:`span_drain_cycles`: with A.J. the
entry is read at a segment's boundary pixels only). The
writer starts ``WS_k = max(WE_{k-1} + 1, DE_{k-2} + 1)`` (the bank it writes is released when the
drain has finished the line that used it), ends ``WE_k = WS_k + w_k - 1``; resolve starts
``RS_k = max(WE_k + 1, RH_{k-1} + 1)``, hands over at ``RH_k = max(RS_k + r_k, DE_{k-1} + 1)``;
the drain runs ``RH_k + 1 .. DE_k = RH_k + d_k``. The finish-time counter of line k is
``RH_k - RS_k + 1``; the last pixel leaves at edge ``DE_{N-1}``.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import ADDR_BITS, DZ_FRAC, SLOPE_FRAC, X_FRAC, Z_BITS
from rasterhw.golden_model.experts.model import ExpertsFrame
from rasterhw.golden_model.experts.pxp_cycles import asb_record, drain_cycles, guarded
from rasterhw.golden_model.experts.slp_run import block_lists

__all__ = ["DMM_DEPTH", "Entering", "NO_PTR", "STEPS", "line_asl", "dmm_line", "resolve", "schedule", "span_drain_cycles",
           "one_multiplier", "multiword", "paper_resolve", "paper_jobs", "aj_blends", "paper_drain"]

DMM_DEPTH = 256       # ASBs per DMM/P bank (the block's default)
NO_PTR = 511          # leading pointer: none
STEPS = ("init", "cull", "enter", "pass_a", "pass_b", "write")
_ZMAX_RUN = ((1 << Z_BITS) - 1) << DZ_FRAC


def line_asl(fr: ExpertsFrame, y: int) -> tuple[list[dict], np.ndarray]:
    """The ASL of line ``y`` as the SLP writes it: ASB field dicts in ASL order, and their record ids."""
    if fr.model != "bit":
        raise RasterhwError("experts: the span PXP HDL's golden side needs the bit model")
    rec, st = fr.records, fr.setup
    if st.n >= (1 << ADDR_BITS) - 1 or (st.n and int(st.poly.max()) >= (1 << ADDR_BITS) - 1):
        raise RasterhwError(f"experts: {st.n} triangles do not fit the {ADDR_BITS}-bit ASB address")
    sel = np.flatnonzero(rec.row == y)
    sel = sel[np.lexsort((rec.tri[sel], rec.xl[sel]))]
    return [asb_record(rec, st, r) for r in sel], sel


def dmm_line(fr: ExpertsFrame, y: int, bounds) -> tuple[list[dict], list[int], list[list[int]]]:
    """Line ``y``'s ASL, and per range of ``bounds`` (P + 1,) its leading pointer (``NO_PTR``: none)
    and bucket list (ASL positions), with the A.J. guard when the frame has A.J."""
    segs, ids = line_asl(fr, y)
    if len(segs) > DMM_DEPTH:
        raise RasterhwError(f"experts: line {y} holds {len(segs)} ASBs, a DMM/P bank {DMM_DEPTH}")
    lead, buckets, _ = block_lists(list(range(len(ids))), fr.records.c0[ids], fr.records.c1[ids],
                                   np.asarray(bounds), guard=1 if fr.aj == "c" else 0, width=fr.width)
    return segs, [NO_PTR if v < 0 else v for v in lead], buckets


def _ends(s: dict, glo: int, ghi: int) -> tuple[int, int, int]:
    c0 = (s["xl"] + 31) >> X_FRAC
    c1 = ((s["xr"] + 31) >> X_FRAC) - 1
    return c0, max(c0, glo), min(c1, ghi - 1)


def _zrun(s: dict, col: int) -> int:
    return (s["zl"] << DZ_FRAC) + ((((col << X_FRAC) + (1 << (X_FRAC - 1)) - s["xl"]) * s["dzdx"]) >> X_FRAC)


def _good(zs_l, zs_r, zb_l, zb_r, s_lower: bool) -> bool:
    """:func:`span._stays_nearest`, bit model, one pair."""
    if s_lower:
        return zs_l <= zb_l and zs_r <= zb_r
    g = 1 << DZ_FRAC
    return (zs_l + g <= zb_l and zs_r + g <= zb_r and zb_l >= g and zb_r >= g
            and zs_l < _ZMAX_RUN and zs_r < _ZMAX_RUN)


class Entering:
    """The candidates entering a PXP's range, in the order the PXP reads them: its block boundary
    bucket list, then the ASL from the block leading pointer while a segment's first pixel is
    before ``ghi`` (``ends``: per ASL position ``(c0, a, e)`` of :func:`_ends`)."""

    def __init__(self, bucket: list[int], lead: int, ends: list[tuple[int, int, int]], ghi: int):
        self.bucket, self.ends, self.ghi = bucket, ends, ghi
        self.bi, self.pp = 0, (len(ends) if lead == NO_PTR else lead)

    def take(self, x: int, cyc: dict, enter) -> int:
        """Take every candidate entering at pixel ``x``, one ``cyc["enter"]`` cycle each (one with no
        pixel in the range is skipped in a cycle; ``enter(pos)`` for the others), plus one cycle that
        finds the next start; returns it (``ghi``: none)."""
        while True:
            cyc["enter"] += 1
            if self.bi < len(self.bucket):
                pos, cand = self.bucket[self.bi], True
            else:
                pos = self.pp
                cand = self.pp < len(self.ends) and self.ends[self.pp][0] < self.ghi
            if not cand:
                return self.ghi
            _, a, e = self.ends[pos]
            if not (e < a or a == x):
                return a
            if a <= e:
                enter(pos)
            if self.bi < len(self.bucket):
                self.bi += 1
            else:
                self.pp += 1


def resolve(segs: list[dict], bucket: list[int], lead: int, glo: int, ghi: int) -> tuple[dict, list[int]]:
    """One line of one range through the span PXP: cycles per step (:data:`STEPS`) and the visible
    ASL position of every pixel of ``[glo, ghi)`` (-1: background)."""
    cyc = dict.fromkeys(STEPS, 0)
    cyc["init"] = 1
    vis: list[int] = []
    if ghi <= glo:
        return cyc, vis
    ends = [_ends(s, glo, ghi) for s in segs]
    act: list[int] = []
    walk = Entering(bucket, lead, ends, ghi)
    x = glo
    while x < ghi:
        cyc["cull"] += len(act)
        act = [p for p in act if ends[p][2] >= x]
        minend = min([ghi] + [ends[p][2] + 1 for p in act])
        entered = []
        ns = walk.take(x, cyc, entered.append)
        act += entered
        nxt = min([ns, minend] + [ends[p][2] + 1 for p in entered])
        r = nxt - 1
        if len(act) < 2:
            cyc["write"] += r - x + 1
            vis += [act[0] if act else -1] * (r - x + 1)
        else:
            k = len(act)
            stack: list[int] = []
            lft, rgt = x, r
            while True:
                cyc["pass_a"] += k
                zl = {p: _zrun(segs[p], lft) for p in act}
                zr = {p: _zrun(segs[p], rgt) for p in act}
                S = min(act, key=lambda p: (min(max(zl[p] >> DZ_FRAC, 0), (1 << Z_BITS) - 1), segs[p]["addr"]))
                ok = True
                if lft < rgt:
                    cyc["pass_b"] += k
                    ok = all(p == S or _good(zl[S], zr[S], zl[p], zr[p], segs[S]["addr"] < segs[p]["addr"])
                             for p in act)
                if not ok:
                    stack.append(rgt)
                    rgt = ((lft + rgt + 1) >> 1) - 1
                    continue
                cyc["write"] += rgt - lft + 1
                vis += [S] * (rgt - lft + 1)
                if not stack:
                    break
                lft, rgt = rgt + 1, stack.pop()
        x = r + 1
    return cyc, vis


def schedule(lines: list[tuple[int, int, int]], mul: list[list[int]] | None = None) -> dict:
    """Exact timing of lines ``(words, resolve cycles, drain cycles)`` through the span PXP
    (the module docstring's recurrences). Returns ``{"line_cycles": [...], "last_pixel": DE_{N-1}}``.

    ``mul`` (the paper's datapath with A.J., :func:`paper_drain`): per line, the drain cycles
    (1 = its first, at ``RH_k + 1``) in which its blend holds the one multiplier. The resolve side
    of line ``k`` holds in every such cycle of line ``k - 1``'s drain after the cycle it takes its
    bank (``RS_k``) and before the cycle it would hand over: each adds one cycle."""
    we, rh = -1, -1
    de: list[int] = []
    out = []
    for k, (w, r, d) in enumerate(lines):
        ws = max(we + 1, de[k - 2] + 1 if k >= 2 else 0)
        we = ws + w - 1
        rs = max(we + 1, rh + 1)
        end = rs + r
        if mul is not None and k >= 1:
            for off in mul[k - 1]:
                t = rh + off
                if t >= end:
                    break
                if t > rs:
                    end += 1
        rh = max(end, de[k - 1] + 1 if k >= 1 else 0)
        de.append(rh + d)
        out.append(rh - rs + 1)
    return {"line_cycles": out, "last_pixel": de[-1] if de else -1}


def one_multiplier(steps: dict) -> int:
    """The extra resolve cycles of one line on the paper's datapath (``experts-pxp-span`` with
    ``datapath="paper"``: one 16 x 16 multiplier, "PXPにおいても ... SLP同様、乗算器を装備している",
    seed 000 3.2): every pass A and pass B cycle needs z at the (sub)span's two end pixels, two
    multiplies, so each takes two cycles (z at the left end kept, then the right); the write's one
    multiply a pixel (the intensity) fits its cycle. ``steps``: :func:`resolve`'s counts."""
    return steps["pass_a"] + steps["pass_b"]


def multiword(steps: dict, drawn: int) -> int:
    """The extra resolve cycles of one line that the paper's datapath's two-word z and i add
    (``datapath="paper"``; docs/experts.md, "z and i in two words"): on a 16-bit datapath a
    two-word add, subtract or compare takes two cycles, the low words with the carry / borrow kept,
    then the high words. Each of pass A's and pass B's two cycles a segment (z at the left end,
    then z at the right with the key compare or the guarded tests) operates on two-word z, so
    takes two: 4 cycles a segment, 2 more than :func:`one_multiplier`'s; the write of a pixel
    drawn by a segment (``drawn``, not background) adds its intensity ``i_L + (d * di/dx >> 6)``
    in two words before it saturates it to the pixel: 2 cycles. ``steps``: :func:`resolve`'s."""
    return 2 * (steps["pass_a"] + steps["pass_b"]) + drawn


def paper_jobs(jb: dict) -> dict:
    """A span PXP job list (``sim/experts/pxp_jobs.py: span_job_list``, ours' cycles) at the paper's
    datapath: every line's resolve cycles + :func:`one_multiplier` + :func:`multiword` (``jb["drawn"]``:
    per job, the guarded range's pixels drawn by a segment), with A.J. its drain's cycles and
    multiplier cycles of :func:`paper_drain` (``jb["paper_drain"]``), scheduled again
    (:func:`schedule`, the resolve side holding while the drain blends), and a frame's
    ``pxp_frame_cycles`` (``pxp_sim.jobs``: per ``owner``, its lines back to back); words and
    pixels unchanged. Adds ``datapath`` ``"paper"``. Each line's extra resolve cycles are its
    job's ``paper_extra`` (:func:`line_job`: the PXP's own rule, :func:`paper_resolve` for the span
    PXP, ``coherent.paper_resolve`` for the coherent one), else the span PXP's from its steps."""
    pd = jb.get("paper_drain") or [None] * len(jb["timing"])
    extra = jb.get("paper_extra")
    if extra is None:
        if jb.get("pxp", "span") != "span":
            raise RasterhwError(f"experts: the {jb['pxp']} PXP's jobs carry no paper-datapath cycles")
        extra = [paper_resolve(st, dn) for st, dn in zip(jb["steps"], jb["drawn"], strict=True)]
    lines = [(w, r + x, d if q is None else q["drain"])
             for (w, r, d), x, q in zip(jb["timing"], extra, pd, strict=True)]
    mul = [[] if q is None else q["mul"] for q in pd]
    sch = schedule(lines, mul)
    out = {**jb, "timing": lines, "cycles": np.array(sch["line_cycles"], np.int64),
           "last_pixel": sch["last_pixel"], "datapath": "paper"}
    if "pxp_frame_cycles" in jb:      # a frame's jobs (pxp_sim.jobs): each PXP's own lines back to back
        own: dict = {}
        for k, o in enumerate(jb["owner"]):
            own.setdefault(o, []).append(k)
        per = np.zeros_like(jb["pxp_frame_cycles"])
        for (s_, p), ks in own.items():
            per[s_, p] = schedule([lines[k] for k in ks], [mul[k] for k in ks])["last_pixel"] + 1
        out["pxp_frame_cycles"] = per
    return out


def aj_blends(vis: list[int], segs: list[dict], lo: int, hi: int, *, width: int) -> list[tuple[int, int]]:
    """The boundaries the span PXP's drain blends with A.J. (c) (``hdl/experts/aj.py``), as
    ``(j, multiplies)``: ``j`` the walk index (``glo + j``) of the boundary's right pixel, over the
    guarded range's visible ASL positions ``vis`` (-1 background). A boundary between two
    polygons blends where the right pixel's segment starts (its first pixel ``(xl + 31) >> 6``)
    or else the left pixel's ends; the pixel blended is the right one if the edge's x
    (``xl`` / ``xr``, Q10.6) is in it, else the left; only a pixel of ``[lo, hi)`` (the guard
    pixels are another PXP's). ``multiplies``: 5 (``delta * |dy/dx|`` for alpha, one per field
    R, G, B, I), 4 where the edge is steep (``|dx/dy| <= 1``: alpha is a shift)."""
    glo, _ = guarded(lo, hi, width, "c")
    none = (1 << ADDR_BITS) - 1
    out = []
    for j in range(1, len(vis)):
        pv, cv = vis[j - 1], vis[j]
        if pv == cv:
            continue
        dx = glo + j
        ps = segs[pv] if pv >= 0 else None
        cs = segs[cv] if cv >= 0 else None
        if (ps["poly"] if ps else none) == (cs["poly"] if cs else none):
            continue
        if cs is not None and dx == max((cs["xl"] + 31) >> X_FRAC, 0):
            xe, sl = cs["xl"], cs["sl"]
        elif ps is not None and dx - 1 == min(((ps["xr"] + 31) >> X_FRAC) - 1, width - 1):
            xe, sl = ps["xr"], ps["sr"]
        else:
            continue
        q = dx if (xe >> X_FRAC) >= dx else dx - 1
        if lo <= q < hi:
            out.append((j, 4 if abs(sl) <= (1 << SLOPE_FRAC) else 5))
    return out


def paper_drain(vis: list[int], segs: list[dict], lo: int, hi: int, *, width: int) -> dict:
    """The span PXP's A.J. (c) drain of one line at the paper's datapath (``hdl/experts/drain.py``
    with the PXP's one multiplier): :func:`span_drain_cycles`' walk (per guarded pixel: read the
    DSLB, then the entry at a segment's first pixel, then blend-and-offer), each blended
    boundary (:func:`aj_blends`) repeating its blend-and-offer step once per multiply (the last
    multiply in the cycle that offers). Returns ``drain`` (cycles) and ``mul`` (the drain cycles,
    1 = the first, whose blend holds the multiplier)."""
    glo, ghi = guarded(lo, hi, width, "c")
    nm = dict(aj_blends(vis, segs, lo, hi, width=width))
    t, mul = 0, []
    for j, v in enumerate(vis):
        t += 2 + (1 if v >= 0 and (j == 0 or vis[j - 1] != v) else 0)     # its blend-and-offer cycle
        if j in nm:
            mul += range(t, t + nm[j])
            t += nm[j] - 1
    return {"drain": t + (1 if ghi == hi else 0), "mul": mul}


def paper_resolve(steps: dict, drawn: int, counts: dict | None = None) -> int:
    """The span PXP's extra resolve cycles of one line at the paper's datapath:
    :func:`one_multiplier` + :func:`multiword` (``counts``: unused, the coherent PXP's rule,
    ``coherent.paper_resolve``, takes its own)."""
    return one_multiplier(steps) + multiword(steps, drawn)


def line_job(segs: list[dict], bucket: list[int], lead: int, lo: int, hi: int, *, aj: str, width: int,
             resolver=None, paper=None) -> dict:
    """One PXP line: its words, resolve and drain cycles, visible positions of ``[lo, hi)`` and
    ``drawn``, the guarded range's pixels a segment draws (not background; :func:`multiword`).
    ``resolver``: :func:`resolve` (default, the span PXP) or another PXP's resolve on the same
    DMM/P words, schedule and drain (``coherent.resolve``, or ``coherent.resolve_counts``, whose
    third value, its counts, goes to ``paper``); ``paper``: the PXP's extra resolve cycles at the
    paper's datapath from the line's steps, ``drawn`` and counts (default :func:`paper_resolve`,
    the span PXP's), kept as ``paper_extra`` (:func:`paper_jobs`)."""
    glo, ghi = guarded(lo, hi, width, aj)
    cyc, vis, *more = (resolver or resolve)(segs, bucket, lead, glo, ghi)
    drawn = sum(1 for v in vis if v >= 0)
    return {"words": len(segs) + len(bucket) + 1, "resolve": sum(cyc.values()), "steps": cyc,
            "drain": span_drain_cycles(vis, lo, hi, aj=aj, width=width),
            "paper_drain": paper_drain(vis, segs, lo, hi, width=width) if aj == "c" else None,
            "paper_extra": (paper or paper_resolve)(cyc, drawn, more[0] if more else None),
            "drawn": drawn, "visible": vis[lo - glo:lo - glo + (hi - lo)]}


def span_drain_cycles(vis: list[int], lo: int, hi: int, *, aj: str, width: int) -> int:
    """Drain cycles of one span-PXP line (``hdl/experts/drain.py``, ``boundary_only``): without
    A.J. ``2 R``; with A.J. (c) 2 per guarded pixel, + 1 per pixel whose visible segment (``vis``,
    the guarded range's ASL positions, -1 background) is not background and differs from the
    pixel on its left (or is the walk's first), + 1 flush at the frame's right edge."""
    if aj != "c":
        return drain_cycles(lo, hi, aj=aj, width=width)
    glo, ghi = guarded(lo, hi, width, aj)
    reads = sum(1 for q, v in enumerate(vis) if v >= 0 and (q == 0 or vis[q - 1] != v))
    return 2 * (ghi - glo) + reads + (1 if ghi == hi else 0)
