"""The coherent span PXP's cycle model: span cull once per segment, depth search only where the visible segment can change.

Seed 000, section 4 prices the PXP with two terms (:mod:`cost`): "iv) ... 《span cull》" at one
operation per segment per line, and "v) ... 《depth search》" at a number of searches per line that
grows as sqrt(Fr), not as the segments' ends (docs/experts.md, cost model). Section 2.2 names the
coherence it rests on: "一旦可視セグメントが決定されればその中では一様な計算で各画素の値を決める
ことができる (span coherence)", with Watkins [8]. This PXP (``experts-pxp-coherent``, ours: the
paper gives the two terms and Watkins, not the steps) keeps the visible segment ``V`` and the last
pixel ``vu`` up to which it has been shown nearest, and searches again only where the visible
segment can change (Watkins' span coherence):

* an **entering** segment ``E`` (at its first pixel ``x``) is tested against ``V`` over
  ``[x, vu]`` by the guarded end-depth test of :mod:`span` (``V`` stays nearest at every pixel);
  if it fails (``E`` nearer at its start, or the two cross before ``vu``), a depth search at ``x``;
* ``V`` **ending** (or the end ``vu`` of the span it was shown for): a depth search at ``vu + 1``;
* two segments **crossing**: the search's guarded tests fail and the span is halved (the crossing
  rule of :mod:`span`: "halve where the end depths flip", ``r = ((l + r + 1) >> 1) - 1``); the
  nearest at the left pixel does not change with ``r``, so only the tests run again.

Everything else is one pass per segment per line: a segment is read once when it enters (and
tested against ``V`` in that cycle) and dropped once from the active list, in the first search
after its last pixel (the active list is compacted by the search's first pass).

**Resolve cycles of one line** (:func:`resolve`; the same framing as :mod:`span_cycles`: DMM/P
contents, schedule and drain are shared), every term:

* ``init`` 1: take the bank.
* ``enter``, per span (a span starts at ``glo``, at a segment start, or after ``vu``): one cycle per
  candidate entering at the span's left pixel ``x`` (bucket list first, then the ASL from the
  leading pointer; tested against ``V`` in the same cycle), one per candidate with no pixel in the
  range, and one that sets the span's right end ``ns - 1`` (``ns``: the next start, or ``ghi``).
* per depth search (at ``x``, when a test failed or ``x > vu``): ``drop`` one cycle per active entry
  that ended before ``x`` (it leaves the list), ``pass_a`` one per segment present (z at ``x``, the
  nearest ``S`` at ``x``: 16-bit key, ties to the lower ASB address); then ``r = min(S's last
  pixel, ghi - 1)``; while ``r > x`` and ``k >= 2``: ``pass_b`` one per segment present (the guarded
  test of ``S`` against it over ``[x, r]``); a failed pass halves ``r``. ``V = S``, ``vu = r``; no
  segment present: background up to ``ns - 1``.
* ``write`` one cycle per pixel of the guarded range, ``[x, min(vu, ns - 1)]`` per span.

The visible segment of every pixel is the per-pixel search's (:func:`resolve` is checked against
the golden frame's ``win`` on every scene in ``tests/experts/test_experts_pxp_coherent.py``): at a
pixel ``p`` written with ``V``, ``V`` is present and every other present segment was either in
the search that chose ``V`` (``S`` nearest at its left pixel and, by the guarded test on the two
lines, at every pixel up to ``vu``) or entered later and passed the test against ``V`` up to
``vu``. A segment's line is used beyond its last pixel in these tests: that can only fail a test
(a needless halving), never pass a wrong one.
"""

from __future__ import annotations

from rasterhw.golden_model.experts.formats import DZ_FRAC, Z_BITS
from rasterhw.golden_model.experts.span_cycles import Entering, _ends, _good, _zrun

__all__ = ["STEPS", "TERMS", "paper_resolve", "resolve", "resolve_counts"]

STEPS = ("init", "enter", "drop", "pass_a", "pass_b", "write")
#: the paper's two terms from the steps: span cull (iv) and depth search (v)
TERMS = {"span_cull": ("enter", "drop"), "depth_search": ("pass_a", "pass_b")}


def _key(s: dict, col: int) -> tuple[int, int]:
    return min(max(_zrun(s, col) >> DZ_FRAC, 0), (1 << Z_BITS) - 1), s["addr"]


def _test(s: dict, b: dict, zsl: int, x: int, rb: int) -> bool:
    """The guarded test of ``s`` against ``b`` over ``[x, rb]`` (``rb``: ``b``'s last pixel in the
    span: the test runs over the pixels where ``b`` is present)."""
    return _good(zsl, _zrun(s, rb), _zrun(b, x), _zrun(b, rb), s["addr"] < b["addr"])


def resolve(segs: list[dict], bucket: list[int], lead: int, glo: int, ghi: int) -> tuple[dict, list[int]]:
    """One line of one range through the coherent span PXP: cycles per step (:data:`STEPS`) and
    the visible ASL position of every pixel of ``[glo, ghi)`` (-1: background). The counts
    ``searches`` (depth searches run: first passes) and ``halvings`` ride in the step dict's
    companion :func:`resolve_counts`."""
    cyc, vis, _ = resolve_counts(segs, bucket, lead, glo, ghi)
    return cyc, vis


def resolve_counts(segs: list[dict], bucket: list[int], lead: int, glo: int,
                   ghi: int) -> tuple[dict, list[int], dict]:
    """:func:`resolve`, and its counts: ``searches`` (depth searches with at least two segments
    present), ``searches_all`` (every first pass), ``halvings``, ``spans``, ``tests_enter`` (entering
    segments tested against the visible one: :func:`paper_resolve`)."""
    cyc = dict.fromkeys(STEPS, 0)
    cnt = {"searches": 0, "searches_all": 0, "halvings": 0, "spans": 0, "tests_enter": 0}
    cyc["init"] = 1
    vis: list[int] = []
    if ghi <= glo:
        return cyc, vis, cnt
    ends = [_ends(s, glo, ghi) for s in segs]
    act: list[int] = []
    walk = Entering(bucket, lead, ends, ghi)
    x = glo
    V, vu = -1, glo - 1
    while x < ghi:
        cnt["spans"] += 1
        entered: list[int] = []
        ns = walk.take(x, cyc, entered.append)
        act += entered
        # each entering segment tested against the visible one up to vu (in its entering cycle)
        if V >= 0 and vu >= x:
            cnt["tests_enter"] += len(entered)
        fail = V >= 0 and vu >= x and not all(
            _good(_zrun(segs[V], x), _zrun(segs[V], min(vu, ends[p][2])), _zrun(segs[p], x),
                  _zrun(segs[p], min(vu, ends[p][2])), segs[V]["addr"] < segs[p]["addr"]) for p in entered)
        if fail or x > vu:
            cnt["searches_all"] += 1
            cyc["drop"] += sum(1 for p in act if ends[p][2] < x)
            act = [p for p in act if ends[p][2] >= x]
            k = len(act)
            cyc["pass_a"] += k
            if not k:
                V, vu = -1, ns - 1
            else:
                S = min(act, key=lambda p: _key(segs[p], x))
                r = min(ends[S][2], ghi - 1)
                if k >= 2:
                    cnt["searches"] += 1
                zsl = _zrun(segs[S], x)
                i = 0
                while k >= 2 and r > x and i < k:
                    cyc["pass_b"] += 1
                    p = act[i]
                    if p == S or _test(segs[S], segs[p], zsl, x, min(r, ends[p][2])):
                        i += 1
                        continue
                    cnt["halvings"] += 1
                    r = ((x + r + 1) >> 1) - 1
                V, vu = S, r
        wend = min(vu, ns - 1)
        cyc["write"] += wend - x + 1
        vis += [V] * (wend - x + 1)
        x = wend + 1
    return cyc, vis, cnt


def paper_resolve(steps: dict, drawn: int, counts: dict) -> int:
    """The extra resolve cycles of one line at the paper's datapath (``experts-pxp-coherent`` with
    ``datapath="paper"``; docs/experts.md, "The coherent PXP at the paper's datapath"): the PXP's one
    16 x 16 multiplier gives one product a cycle, and z and i are two 16-bit words added a word a
    cycle, low word first with the carry kept (the span PXP's rule, ``span_cycles.multiword``), so a
    running z or i takes two cycles. Per step:

    * pass A, a segment present (``pass_a``): z at ``x`` (2 cycles; the key and the nearest in the
      second): +1; a segment dropped (``drop``) multiplies nothing: 1 cycle, as ours;
    * pass B, a test (``pass_b``): S's z at ``x`` is kept from pass A; S's z at the test's right
      pixel, the segment's z at ``x`` and at the right pixel (2 cycles each; the guarded tests'
      low words with the last one's low word, their high words with its high word): 6 cycles, +5;
    * an entering segment tested against the visible one (``counts["tests_enter"]``): the visible
      one's z at ``x`` as well: 8 cycles, +7;
    * the write of a pixel drawn by a segment (``drawn``): its intensity in two words, +1.

    ``steps``, ``counts``: :func:`resolve_counts`'."""
    return steps["pass_a"] + 5 * steps["pass_b"] + 7 * counts["tests_enter"] + drawn
