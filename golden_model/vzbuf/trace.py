"""Vector-operation trace: the loops the paper's vectorised FORTRAN issues, recorded as the
NumPy algorithms run.

A NumPy call is not a vector instruction. What is recorded is the loop the paper describes:
each call of :meth:`Trace.loop` is one DO loop of ``n`` iterations whose body is a fixed list
of per-element operations (:data:`BODIES`: kind, element width in bytes, count per element),
recorded with the length the data gives it (a span, the occupied s-list slots, the vertices,
...). The vectorising compiler strip-mines a loop by the machine's vector register length, so
the trace keeps the logical length and the timing model (:mod:`.facom`) cuts it. Work the paper
says stays scalar (list walking, loop control per segment or line, clipping, linking the y-list)
is recorded with :meth:`Trace.scalar` as a count of units of scalar work (:data:`SCALAR_BODIES`).

Operation kinds (what a FACOM VP instruction does to one element):

``load`` / ``store``      contiguous (stride-1) memory access
``gather`` / ``scatter``  list-vector (indirect) load / store, ``A(L(I))``
``masked_store``          store under the mask (contiguous)
``masked_scatter``        list-vector store under the mask
``add``                   add, subtract, convert, logical (floating or fixed)
``mul``                   multiply
``div``                   divide (and square root)
``compare``               compare into the mask register, mask and/or
``compress``              collect the elements where the mask is on into an index list
                          ("収集"; the paper's "収集・拡散手続き")
``reduce``                maximum / sum over the vector

Element width: 8 bytes for every floating value (3.1 e): "演算はすべて倍精度"), 4 bytes for
pointers, indices, counts and the packed RGBI word ("整数型データの処理量が比較的多い", 2.3.1 2)).
The timing model (:mod:`.facom`) prices each operation by its kind *and* its width.

The trace is grouped by *phase* (``setup``, ``segments``, ``split``, ``init``, ``hsr``,
``shadow``, ``light``, ``transform``, ...); :func:`~.render.table_stages` maps
phases to each table's stages the same way the CPU-time stages are.

Work the paper keeps scalar is recorded by :meth:`Trace.scalar` as a count of one of the
:data:`SCALAR_BODIES` (the same ``(kind, width, count)`` operations, run one at a time on the
scalar unit of every machine).
"""

from __future__ import annotations

from collections import Counter

import numpy as np

__all__ = ["BODIES", "KINDS", "SCALAR_BODIES", "Trace"]

KINDS = ("load", "store", "gather", "scatter", "masked_store", "masked_scatter", "add", "mul", "div", "compare",
         "compress", "reduce")

F, I4 = 8, 4


def _b(*ops):
    for k, w, c in ops:
        assert k in KINDS and c > 0 and w in (I4, F), (k, w, c)
    return tuple(ops)


#: per-element loop bodies, each ``(kind, width, count)``; the FORTRAN each stands for is in
#: ``docs/vzbuf.md`` ("The trace"). Floating operation counts as counted from the formulas
#: (a 4x4 product = 16 mul + 12 add; a plane distance = 1 add; ...).
BODIES = {
    # set-up (2.2 a)): view + perspective transform of every vertex, (x,y,z,1) x 4x4, divide by w
    "vertex transform": _b(("load", F, 3), ("mul", F, 16), ("add", F, 12), ("div", F, 1), ("mul", F, 3),
                           ("store", F, 3)),
    # lighting of every vertex (2.2 b)): normal through the vertex's normal pointer,
    # I = Ia + k(-N.L)/|N||L|: N.L and N.N (6 mul, 4 add), sqrt and divide, the lit test, k x + Ia
    "vertex lighting": _b(("load", I4, 1), ("gather", F, 3), ("mul", F, 6), ("add", F, 4), ("div", F, 2),
                          ("compare", F, 1), ("mul", F, 1), ("add", F, 1), ("store", F, 1)),
    # back-face test of every polygon (2.2 c)): its first three screen vertices through the vertex
    # pointer, the z of the cross product (5 subtractions, 2 products)
    "back-face test": _b(("load", I4, 1), ("gather", F, 6), ("add", F, 5), ("mul", F, 2), ("compare", F, 1),
                         ("store", I4, 1)),
    # the lit / unlit test of every face (2.2 b): "陽面(光源光のあたる面)と陰面(光源光のあたらない面)を
    # 判定し"): its world normal from two edges through the vertex pointer (6 subtractions, a cross
    # product), N.L, the sign into the polygon block's flag
    "face lit test": _b(("load", I4, 1), ("gather", F, 9), ("add", F, 6), ("mul", F, 6), ("add", F, 3),
                        ("mul", F, 3), ("add", F, 2), ("compare", F, 1), ("store", I4, 1)),
    # collect the surviving polygons into a list
    "collect polygons": _b(("load", I4, 1), ("compare", I4, 1), ("compress", I4, 1)),
    # segment building: edge block of every segment side (x, dx/dy, z, dz/dy, i, di/dy at its first
    # line): differences, 1/dy, three slopes, the values at the first line
    "edge block": _b(("gather", F, 8), ("add", F, 10), ("mul", F, 8), ("div", F, 1), ("store", F, 6)),
    # the plane of every processed polygon, for its segments' dz/dx (the segment block's "dz/dx",
    # 2.3.2 1)): three screen vertices through the vertex pointer, the normal, -a/c
    "polygon plane": _b(("load", I4, 1), ("gather", F, 9), ("add", F, 6), ("mul", F, 6), ("add", F, 3),
                        ("div", F, 1), ("mul", F, 1), ("store", F, 1)),
    # dz/dx of every segment from its polygon's plane
    "segment dzdx": _b(("load", I4, 1), ("gather", F, 2), ("mul", F, 1), ("store", F, 1)),
    # algorithm 2's split: mean lengths (reductions), then the test and the collection of long ones
    "segment lengths": _b(("load", F, 2), ("add", F, 2), ("reduce", F, 2)),
    "select long segments": _b(("load", F, 2), ("compare", F, 2), ("compress", I4, 1)),
    # a piece of a split segment: its two edge blocks and its segment block, moved along its lines
    "split piece": _b(("gather", F, 12), ("add", F, 8), ("mul", F, 6), ("scatter", F, 14)),
    # buffers: one element store per buffer element ("Zバッファ <- Z値の最大値")
    "clear": _b(("store", F, 1),),
    # --- algorithm 1 (2.3.2 2)(i))
    # drop exited segments from the x-list: test y end, collect the survivors
    "a1 drop exited": _b(("load", I4, 1), ("gather", I4, 1), ("compare", I4, 1), ("compress", I4, 1)),
    # span ends and di/dx of every x-list segment, from its two edges
    "a1 span set-up": _b(("load", I4, 1), ("gather", F, 6), ("add", F, 5), ("mul", F, 1), ("div", F, 1),
                         ("store", F, 5)),
    # the Z test along one span: vector length = the span (one-line Z-buffer, contiguous); the
    # winner's z and its RGBI word (I to 7 bits, packed with the face's RGB: 3.1 d)) are stored
    "a1 z-test real": _b(("add", F, 4), ("mul", F, 3), ("load", F, 1), ("compare", F, 1), ("masked_store", F, 1),
                         ("masked_store", I4, 1)),
    "a1 z-test shadow": _b(("add", F, 1), ("mul", F, 1), ("load", F, 1), ("compare", F, 1), ("load", I4, 1),
                           ("add", I4, 1), ("masked_store", I4, 1)),
    "a1 z-test depth": _b(("add", F, 1), ("mul", F, 1), ("load", F, 1), ("compare", F, 1), ("masked_store", F, 1)),
    # step both edges of every x-list segment: x, z, i += dx/dy, dz/dy, di/dy (edge blocks by pointer)
    "edge update": _b(("load", I4, 1), ("gather", F, 6), ("add", F, 3), ("scatter", F, 3)),
    # --- algorithm 2 (2.3.2 2)(ii), fig. 2); vector length = scan lines (slots)
    # (1) drop exited segments: slot non-null and y end < y -> null
    "a2 drop exited": _b(("load", I4, 1), ("compare", I4, 1), ("gather", I4, 1), ("compare", I4, 2),
                         ("masked_store", I4, 1)),
    # (2) empty slot and a waiting y-list: take its head, advance the y-list
    "a2 take y-list head": _b(("load", I4, 2), ("compare", I4, 2), ("gather", I4, 1), ("masked_store", I4, 2)),
    # (3) collect the non-null slots ("slist(y)#nullの要素を収集")
    "a2 collect slots": _b(("load", I4, 1), ("compare", I4, 1), ("compress", I4, 1)),
    # span ends, di/dx and pixel base of every occupied slot; longest span (the repeat count)
    "a2 span set-up": _b(("gather", I4, 1), ("gather", F, 8), ("add", F, 6), ("mul", F, 3), ("div", F, 1),
                         ("store", F, 6), ("reduce", F, 1)),
    # one masked Z-test step k over every occupied slot: mask k < length, Z-buffer by list vector
    "a2 z-test real": _b(("compare", F, 1), ("add", F, 5), ("mul", F, 3), ("gather", F, 1), ("compare", F, 2),
                         ("masked_scatter", F, 1), ("masked_scatter", I4, 1)),
    "a2 z-test shadow": _b(("compare", F, 1), ("add", F, 2), ("mul", F, 1), ("gather", F, 1), ("compare", F, 2),
                           ("gather", I4, 1), ("add", I4, 1), ("masked_scatter", I4, 1)),
    "a2 z-test depth": _b(("compare", F, 1), ("add", F, 2), ("mul", F, 1), ("gather", F, 1), ("compare", F, 2),
                          ("masked_scatter", F, 1)),
    # (4) slist(i+1) <- slist(i), slist(0) <- null
    "a2 shift s-list": _b(("load", I4, 1), ("store", I4, 1)),
    # --- shadows (2.5)
    # silhouette test of every edge: the two faces' N.L through the edge's polygon pointers
    "silhouette test": _b(("load", I4, 2), ("gather", F, 6), ("mul", F, 6), ("add", F, 4), ("compare", F, 3),
                          ("compress", I4, 1)),
    # the shadow quad of a silhouette edge: its two vertices swept along L to the ground plane
    "shadow quad": _b(("gather", F, 6), ("mul", F, 10), ("add", F, 12), ("div", F, 1), ("store", F, 12)),
    # darken the pixels whose count > 0: replace the I bits of the RGBI word by Ia's
    "shadow darken": _b(("load", I4, 2), ("compare", I4, 1), ("add", I4, 2), ("masked_store", I4, 1)),
    # ray casting (2.5 2) c)): every pixel with Z < max to light space (4x4), shadow-buffer test
    "to light space": _b(("load", F, 1), ("compare", F, 1), ("mul", F, 16), ("add", F, 14), ("div", F, 1),
                         ("mul", F, 3), ("add", F, 1), ("gather", F, 1), ("compare", F, 2), ("masked_store", F, 1)),
}

#: work the paper keeps scalar, one entry per unit of work (what :meth:`Trace.scalar` counts),
#: each ``(kind, width, count)`` run one operation at a time on the scalar unit; the passage
#: each stands for is in ``docs/vzbuf.md`` ("The trace", scalar work)
SCALAR_BODIES = {
    # Sutherland's re-entrant clipper (2.2 c), ref. [1]): one vertex against one plane of the view
    # pyramid: read x,y,z,w, the plane distance, its sign test, write the vertex out, count it
    "clip vertex x plane": _b(("load", F, 4), ("add", F, 1), ("compare", F, 1), ("store", F, 4), ("add", I4, 1)),
    # the clipper's own work per polygon and plane: the polygon's vertex pointer and count in, the
    # output pointer and count out, the loop over its vertices
    "clip polygon x plane": _b(("load", I4, 2), ("store", I4, 2), ("add", I4, 2), ("compare", I4, 1)),
    # fig. 1 per polygon (2.3.2 1): "すべての処理対象多角形に対して、図1に示す手順で頂点データから…セグメント・
    # ブロックを作成する": its vertex pointer and count, the top and bottom vertex, the two chains set up
    "polygon chains": _b(("load", I4, 2), ("add", I4, 4), ("compare", I4, 2), ("store", I4, 2)),
    # fig. 1 per segment: which chain reaches the next vertex line first, that chain advanced, the
    # segment block written (y end, polygon, left edge, right edge: 2.3.2 1) (i)) and allocated
    "segment block": _b(("compare", F, 1), ("load", I4, 2), ("add", I4, 2), ("store", I4, 4)),
    # algorithm 1 with Gouraud shading, per span: "スムーズ・シェイディング処理を行うか否かの判定処理"
    # (3.3 3) ②): the polygon's flag through the segment's polygon pointer, tested
    "shading decision": _b(("load", I4, 1), ("load", I4, 1), ("compare", I4, 1)),
    # fig. 1 (segment building), per polygon vertex: its y through the vertex pointer, the order
    # test that finds the vertex lines, the index step
    "vertex line": _b(("load", I4, 1), ("gather", F, 1), ("compare", F, 1), ("add", I4, 2), ("store", I4, 1)),
    # 2.3.2 1): "セグメント・ブロックを y の初期値によって、y listをヘッダとする線形リストにつなぐ"
    "y-list link": _b(("add", F, 1), ("load", I4, 2), ("store", I4, 2), ("add", I4, 1)),
    # algorithm 1, per scan line: the line loop and the bypass of a line with no data
    # ("処理データのないスキャンラインの処理をバイパスできる", 3.3 1) ①)
    "line loop": _b(("add", I4, 1), ("compare", I4, 1)),
    # algorithm 1: "y list(y)につながれているセグメントを新たに x listにつなぐ", per entering segment
    "x-list append": _b(("load", I4, 2), ("store", I4, 1), ("add", I4, 1), ("compare", I4, 1)),
    # algorithm 1, per line with segments: one-line Z-buffer base, x-list length, loop bounds
    "line set-up": _b(("add", I4, 3), ("load", I4, 2), ("store", I4, 1)),
    # algorithm 1, per x-list segment: the Z-test loop of its span is set up (its ends, its length,
    # the empty-span test): "すべての x list中のセグメントについて"
    "span loop set-up": _b(("load", F, 2), ("add", F, 2), ("add", I4, 2), ("compare", I4, 1), ("store", I4, 1)),
    # algorithm 2, per pass: "処理可能セグメント数 >0 の間" (count, test, loop control)
    "pass control": _b(("add", I4, 4), ("load", I4, 2), ("compare", I4, 2), ("store", I4, 2)),
    # algorithm 2, per masked step: "最大長のセグメントの長さだけ繰り返す"
    "z-test step": _b(("add", I4, 1), ("compare", I4, 1), ("add", I4, 1)),
}
for _k in SCALAR_BODIES:
    assert _k not in BODIES, _k


class Trace:
    """Records loops and scalar instructions by phase (see the module docstring)."""

    def __init__(self) -> None:
        self.loops: Counter = Counter()     # (phase, body, n) -> how many times
        self.scalars: Counter = Counter()   # (phase, what) -> units of SCALAR_BODIES[what]
        self.phase = "setup"

    def at(self, phase: str) -> Trace:
        self.phase = phase
        return self

    def loop(self, body: str, n, times: int = 1) -> None:
        """One DO loop of ``n`` iterations over :data:`BODIES` ``[body]`` (``times`` such loops)."""
        if body not in BODIES:
            raise KeyError(f"trace: no loop body {body!r}")
        n = int(n)
        if n > 0 and times > 0:
            self.loops[(self.phase, body, n)] += int(times)

    def loops_of(self, body: str, lengths) -> None:
        """One loop per entry of ``lengths`` (e.g. one Z test per span)."""
        a = np.asarray(lengths, np.int64)
        a = a[a > 0]
        if a.size:
            v, c = np.unique(a, return_counts=True)
            for n, t in zip(v.tolist(), c.tolist(), strict=True):
                self.loops[(self.phase, body, n)] += t

    def scalar(self, what: str, units) -> None:
        """``units`` times the scalar work :data:`SCALAR_BODIES` ``[what]`` (the part the paper
        keeps scalar)."""
        if what not in SCALAR_BODIES:
            raise KeyError(f"trace: no scalar body {what!r}")
        k = int(units)
        if k > 0:
            self.scalars[(self.phase, what)] += k

    # ------------------------------------------------------------------ summaries
    def phases(self) -> list[str]:
        return sorted({p for p, _, _ in self.loops} | {p for p, _ in self.scalars})

    def elements(self, kind: str | None = None, phase: str | None = None) -> int:
        """Element operations of ``kind`` (all kinds if None) over the loops of ``phase``."""
        tot = 0
        for (p, body, n), t in self.loops.items():
            if phase is not None and p != phase:
                continue
            per = sum(c for k, _w, c in BODIES[body] if kind is None or k == kind)
            tot += per * n * t
        return tot

    def instructions(self, vl: int, phase: str | None = None) -> Counter:
        """Vector instructions by kind once every loop is strip-mined at vector length ``vl``."""
        out: Counter = Counter()
        for (p, body, n), t in self.loops.items():
            if phase is not None and p != phase:
                continue
            strips = -(-n // vl)
            for k, _w, c in BODIES[body]:
                out[k] += c * strips * t
        return out

    def mean_length(self, body: str) -> float:
        tot = cnt = 0
        for (_p, b, n), t in self.loops.items():
            if b == body:
                tot += n * t
                cnt += t
        return tot / cnt if cnt else 0.0
