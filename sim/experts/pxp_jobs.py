"""The EXPERTS PXP's jobs: stimulus words, expected pixels and cycles from the golden model.

A job is one PXP line ``(y, lo, hi)``: its words (the line PXP: the range's segments; the span PXP:
the DMM/P words the SLP writes), then the ``last`` token carrying the next job's range above the
payload (``{next_hi[10:0], next_lo[9:0], payload}``, the bench adapter
``sim/experts/testbench.py: RangeFromTokens`` puts it on ``lo``/``hi``). Used by the testbenches
(``sim/experts/testbench.py``) and the scene runs (``sim/experts/scene.py``).
"""

from __future__ import annotations

from operator import itemgetter

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import ExpertsFrame
from rasterhw.golden_model.experts.pxp import pixel_words
from rasterhw.golden_model.experts.pxp_cycles import line_segments, schedule

__all__ = ["RANGE_BITS", "SEG_BITS", "SPAN_BITS", "job_list", "range_word", "span_job_list"]

SEG_BITS = 194          # seg_layout().size (checked in job_list)
SPAN_BITS = 204         # dmm_layout().size (checked in span_job_list)
RANGE_BITS = 22         # above the payload: next_lo[9:0], next_hi[10:0], and the range word's flag


def range_word(lo: int, hi: int, seg_bits: int) -> int:
    """The word that sets the PXP's range ``[lo, hi)`` before its first job (flag bit
    ``seg_bits + 21``; the range in the fields a ``last`` token carries the next range in); the
    adapter takes it itself and starts the PXP's clock after it (``RangeFromTokens``)."""
    return (1 << (seg_bits + RANGE_BITS - 1)) | (hi << (seg_bits + 10)) | (lo << seg_bits)


def _pack(seg: dict, layout) -> int:
    from rasterhw.hdl.pack import pack
    return pack(layout, seg)


def pack_rows(layout, rows: list[dict]) -> list[int]:
    """``[pack(layout, r) for r in rows]`` (``hdl/pack.py``: missing fields 0, each wrapped to its
    width) for a flat struct layout of fields up to 63 bits, a field at a time in NumPy: the words go
    into 64-bit limbs, then one ``int.from_bytes`` per row (a frame's ~45,000 ASBs: 5x faster)."""
    from amaranth import Shape
    plan = [(n, f.offset, Shape.cast(f.shape).width) for n, f in layout]
    if not rows or max(w for *_, w in plan) > 63:
        return [_pack(r, layout) for r in rows]
    plan = [p for p in plan if p[0] in rows[0]]     # the rest are 0 (the rows of one list share their keys)
    if not plan:
        return [0] * len(rows)
    cols = np.array(list(map(itemgetter(*(n for n, *_ in plan)), rows)), np.int64).reshape(len(rows), len(plan))
    limbs = np.zeros((len(rows), (layout.size + 63) // 64 + 1), np.uint64)
    for j, (_, off, width) in enumerate(plan):
        v = (cols[:, j] & ((1 << width) - 1)).astype(np.uint64)
        k, sh = divmod(off, 64)
        limbs[:, k] |= v << np.uint64(sh)
        if sh + width > 64:
            limbs[:, k + 1] |= v >> np.uint64(64 - sh)
    return [int.from_bytes(r.tobytes(), "little") for r in limbs.astype("<u8")]


def job_list(fr: ExpertsFrame, todo: list[tuple[int, int, int]]) -> dict:
    """Stimulus, expected pixels and cycles for PXP lines ``(y, lo, hi)`` run one after another."""
    from rasterhw.hdl.experts.pxp import seg_layout
    lay = seg_layout()
    if lay.size != SEG_BITS:
        raise RasterhwError(f"experts: the bench expects {SEG_BITS}-bit segments, the PXP has {lay.size}")
    aj = fr.aj
    W = fr.width
    words, exp_pix, lines, per_job = [], [], [], []
    pix = pixel_words(fr.setup, fr.fields).reshape(fr.height, W)
    for k, (y, lo, hi) in enumerate(todo):
        segs = line_segments(fr, y, lo, hi, aj=aj)
        for s in segs:
            words.append(_pack({"last": 0, **s}, lay))
        _, nlo, nhi = todo[k + 1] if k + 1 < len(todo) else todo[k]
        words.append((nhi << (SEG_BITS + 10)) | (nlo << SEG_BITS) | _pack({"last": 1}, lay))
        lines.append((segs, lo, hi))
        per_job.append(segs)
        exp_pix.append(pix[y, lo:hi])
    sch = schedule(lines, aj=aj, width=W)
    return {"words": words, "pixels": np.concatenate(exp_pix).astype(np.int64) if exp_pix else np.zeros(0, np.int64),
            "cycles": np.array(sch["line_cycles"], np.int64), "last_pixel": sch["last_pixel"],
            "lo0": todo[0][1], "hi0": todo[0][2], "lines": len(todo), "aj": aj, "segments": per_job,
            "seg_bits": SEG_BITS}



def span_job_list(fr: ExpertsFrame, todo: list[tuple[int, int, int]], slp: dict | None = None, *,
                  pxp: str = "span") -> dict:
    """:func:`job_list` for the span PXP (``experts-pxp-span``): per PXP line ``(y, lo, hi)`` the
    DMM/P words the SLP writes (the line's whole ASL, the range's bucket list, the ``last`` token
    with the leading pointer and the next job's range), the expected pixels and the cycles of
    ``golden_model/experts/span_cycles.py``; ``visible`` per job (ASL record ids, -1 background);
    ``paper_drain`` per job (with A.J.: ``span_cycles.paper_drain``, for ``span_cycles.paper_jobs``)
    and ``drawn`` (the guarded range's pixels drawn by a segment, for ``span_cycles.multiword``);
    ``paper_extra`` per job (the PXP's extra resolve cycles at the paper's datapath, for ``paper_jobs``).
    ``slp``: ``{(y, lo, hi): (the ASBs in ASL order, leading pointer, bucket list)}`` as an SLP
    (the ``experts-slp`` HDL) wrote them, instead of the golden SLP's. ``pxp="coherent"``: the
    coherent span PXP's cycles (``golden_model/experts/coherent.py``, ``experts-pxp-coherent``:
    the same words and pixels)."""
    from rasterhw.golden_model.experts import coherent
    from rasterhw.golden_model.experts.span_cycles import schedule as span_schedule
    from rasterhw.golden_model.experts.span_cycles_fast import NO_PTR, dmm_line, line_asl, line_job
    from rasterhw.hdl.experts.pxp_span import dmm_layout
    from rasterhw.hdl.pack import pack
    lay = dmm_layout()
    if lay.size != SPAN_BITS:
        raise RasterhwError(f"experts: the bench expects {SPAN_BITS}-bit DMM/P words, the span PXP has {lay.size}")
    W = fr.width
    aj = fr.aj
    pix = pixel_words(fr.setup, fr.fields).reshape(fr.height, W)
    # the DMM/P words of a line's jobs at once: its ASL packed once, the block lists of all its ranges
    # in one walk (dmm_line per range is the same walk, once per range), bucket and token words by value
    ranges: dict[int, list[tuple[int, int]]] = {}
    for y, lo, hi in todo:
        ranges.setdefault(y, []).append((lo, hi))
    cache: dict[int, tuple] = {}
    bucket_word: dict[int, int] = {}
    words, exp_pix, lines, steps, visible, pdrain, drawn, pextra = [], [], [], [], [], [], [], []
    for k, (y, lo, hi) in enumerate(todo):
        if y not in cache:
            segs, ids = line_asl(fr, y)
            if slp is not None:       # the SLP's ASBs in its ASL order (wrong ones show as wrong pixels)
                rid = {s["addr"]: r for s, r in zip(segs, ids, strict=True)}
                segs = slp[(y, lo, hi)][0]
                if sorted(s["addr"] for s in segs) != sorted(rid):
                    raise RasterhwError(f"experts: the SLP's ASL of line {y} is not the line's segments")
                ids = np.array([rid[s["addr"]] for s in segs], np.int64)
            rs = ranges[y]
            tiled = slp is None and all(a[1] == b[0] for a, b in zip(rs, rs[1:], strict=False))
            lists = dict(zip(rs, zip(*dmm_line(fr, y, [rs[0][0], *(h for _, h in rs)])[1:], strict=True),
                             strict=False)) if tiled else {}
            cache = {y: (segs, ids, pack_rows(lay, segs), lists)}
        segs, ids, packed, lists = cache[y]
        if slp is not None:
            _, ld, bk = slp[(y, lo, hi)]
            lead, bucket = NO_PTR if ld < 0 else ld, bk
        elif (lo, hi) in lists:
            lead, bucket = lists[(lo, hi)]
        else:
            _, (lead,), (bucket,) = dmm_line(fr, y, [lo, hi])
        job = line_job(segs, bucket, lead, lo, hi, aj=aj, width=W,
                       **({"resolver": coherent.resolve_counts, "paper": coherent.paper_resolve}
                          if pxp == "coherent" else {}))
        _, nlo, nhi = todo[k + 1] if k + 1 < len(todo) else todo[k]
        words += packed
        for b in bucket:
            if b not in bucket_word:
                bucket_word[b] = pack(lay, {"list": 1, "ptr": b})
            words.append(bucket_word[b])
        words.append((nhi << (SPAN_BITS + 10)) | (nlo << SPAN_BITS) | pack(lay, {"last": 1, "ptr": lead}))
        lines.append((job["words"], job["resolve"], job["drain"]))
        steps.append(job["steps"])
        pdrain.append(job.get("paper_drain"))
        drawn.append(job["drawn"])
        pextra.append(job["paper_extra"])
        vis = np.asarray(job["visible"], np.int64)
        visible.append(np.where(vis >= 0, ids[np.maximum(vis, 0)], -1) if len(ids) else np.full(vis.size, -1, np.int64))
        exp_pix.append(pix[y, lo:hi])
    sch = span_schedule(lines)
    return {"words": words, "pixels": np.concatenate(exp_pix).astype(np.int64) if exp_pix else np.zeros(0, np.int64),
            "cycles": np.array(sch["line_cycles"], np.int64), "last_pixel": sch["last_pixel"],
            "lo0": todo[0][1], "hi0": todo[0][2], "lines": len(todo), "aj": aj, "steps": steps,
            "visible": visible, "timing": lines, "seg_bits": SPAN_BITS, "pxp": pxp, "paper_drain": pdrain,
            "drawn": drawn, "paper_extra": pextra}
