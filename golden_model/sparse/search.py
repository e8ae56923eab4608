"""Recursive pixel search on sparse rasters: the golden model of a p x q matrix of video processors.

Seed 002 ("Число окон, генерируемых многоугольником на i-м уровне"): the full raster is
``p*2**n x q*2**n`` pixels; video processor ``(a, b)`` owns every p-th pixel of every q-th line,
``(x, y) = (p*u + a, q*v + b)`` for its sparse pixel ``(u, v)`` in ``0 .. 2**n - 1``. It searches
its own ``2**n x 2**n`` lattice by recursive division: level ``i`` (1..n) holds windows of
``2**(n-i) x 2**(n-i)`` sparse pixels, whose centres form a ``2**i x 2**i`` raster spaced
``p*2**(n-i)``, ``q*2**(n-i)`` px; each window entering level ``i`` is split in four and each
sub-window gets a coverage test (``4*w_(i-1)`` tests, ``w_i`` survivors, ``w_0 = 1``).

Coverage tests
--------------
* Levels ``i < n``: the sub-window is the rectangle ``[p(2**(n-i) - 1) + alpha] x
  [q(2**(n-i) - 1) + beta]`` px around its centre (the paper's window, aperture ``alpha x beta``).
  The window survives unless one edge's largest value over the rectangle is below the fill-rule
  threshold or (``test="exact"``, the default) the rectangle misses the triangle's bounding box:
  together these are the separating-axis test, so a window survives exactly when it meets the
  (closed) triangle, and the count is the paper's "filtered polygon" count. ``test="edges"`` is
  the edges-only test. Neither rejects a window holding a covered pixel centre (``alpha, beta >=
  0``), so no pixel is lost.
* Level ``n`` (pixels): the reference rasteriser's point test, ``E_k >= thr_k`` for the three
  edges at the pixel centre (top-left rule, vertices on the 1/256 px grid), exactly. The same
  level also counts the windows that pass the aperture test (``w_n`` of the theory).

Each processor rewrites the broadcast edge coefficients for its lattice, ``A' = pA, B' = qB,
C' = C + aA + bB`` (exact integers, formats in :mod:`.formats`), and from then on only adds:
a child window's corner value is its parent's plus ``A' * du * 2**(n-i) + B' * dv * 2**(n-i)``.

Surface parameters and the pixel processor
-------------------------------------------
Depth and colour are linear functions over the triangle. The float layer evaluates them as the
reference rasteriser does (barycentric weights ``E_k / E`` from the exact edge values, summed in
vertex order), so its image equals the reference bit for bit; the bit-accurate layer
(``depth="fixed"``) interpolates the quantised depth as a fixed-point plane over the sparse
lattice (:mod:`.formats`). The pixel processor Z-tests (``z_new < z_stored``, submission order)
into the processor's local memory; the video controller reads the ``p*q`` local memories as one
memory interleaved on both axes.

Vectorised over (triangle, processor, window) records: one NumPy step per level for all
processors at once, as the matrix runs every processor on every broadcast triangle.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles
from rasterhw.golden_model.sparse.edges import edge_setup
from rasterhw.golden_model.sparse.fixed import depth_plane
from rasterhw.golden_model.sparse.formats import (
    EDGE_BITS,
    Z_FRAC_BITS,
    check_signed,
    parse_matrix,
    sparse_geometry,
)
from tqdm import tqdm

__all__ = ["SparseFrame", "sparse_render", "interleave"]

_SUB = 1 << SUBPIXEL_BITS
_HALF = _SUB // 2

@dataclass
class SparseFrame:
    """A frame drawn by a p x q matrix of video processors.

    Attributes
    ----------
    p, q, n : matrix and sparse-raster size (``2**n x 2**n`` per processor).
    colour : (H, W, 3) float64, depth : (H, W) float64 (``+inf`` empty), tri_id : (H, W) int64
        (``-1`` empty) — the interleaved read-out of the local memories.
    writer : (H, W) int64 — processor index ``b*p + a`` that wrote the pixel (-1 never written).
    local_tri : (q, p, 2**n, 2**n) int64 — each processor's local memory (triangle ids).
    windows : (n + 1,) int64 — windows leaving each level summed over processors (level 0: one
        root per triangle per processor; level n: pixels passing the point test).
    tests : (n + 1,) int64 — coverage tests made at each level (``tests[0] = 0``).
    windows_aperture_n : windows of level n passing the aperture test (``w_n`` of the theory).
    windows_per_proc : (p*q, n + 1) int64 — ``windows`` for each processor.
    tests_per_proc : (p*q, n + 1) int64.
    fragments : pixels passing the point test, all triangles (overdraw included).
    pixels_written : fragments that passed the Z test when they arrived (serial Z-buffer).
    triangles : triangles broadcast (non-degenerate after snapping).
    """

    p: int
    q: int
    n: int
    colour: np.ndarray
    depth: np.ndarray
    tri_id: np.ndarray
    writer: np.ndarray
    local_tri: np.ndarray
    windows: np.ndarray
    tests: np.ndarray
    windows_aperture_n: int
    windows_per_proc: np.ndarray
    tests_per_proc: np.ndarray
    fragments: int
    pixels_written: int
    triangles: int
    stats: dict = field(default_factory=dict)

    def to_rgb8(self) -> np.ndarray:
        """(H, W, 3) uint8 as the reference's ``Frame.to_rgb8`` (round half up, clamped)."""
        return np.clip(np.floor(self.colour * 255.0 + 0.5), 0, 255).astype(np.uint8)

    def depth_words(self, z_bits: int) -> np.ndarray:
        """(H, W) int64: the depth as the HDL stores it, ``round(depth * 2**z_bits)``, -1 where empty
        (of a frame drawn with ``depth="fixed"``, whose depths are multiples of ``2**-z_bits``)."""
        return np.where(self.tri_id >= 0, np.rint(self.depth * (1 << z_bits)), -1).astype(np.int64)


def interleave(local: np.ndarray) -> np.ndarray:
    """Video controller read-out: ``(q, p, N, N, ...)`` local memories -> ``(q*N, p*N, ...)`` frame,
    ``frame[q*v + b, p*u + a] = local[b, a, v, u]``."""
    q, p, N, M = local.shape[:4]
    rest = local.shape[4:]
    return local.transpose(2, 0, 3, 1, *range(4, local.ndim)).reshape(q * N, p * M, *rest)


def _check_aperture(name: str, v) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
        raise RasterhwError(f"sparse: aperture {name} must be a non-negative integer (pixels), not {v!r}")
    return int(v)


#: root records (triangles x processors) from which a search shows a progress bar on a terminal
BIG_RECORDS = 1_000_000


def sparse_render(tris: ScreenTriangles, matrix="4x4", *, alpha: int = 2, beta: int = 2,
                  test: str = "exact", depth: str = "float", background=(0.0, 0.0, 0.0),
                  per_record: bool = False, trace: bool = False) -> SparseFrame:
    """Draw ``tris`` with a ``p x q`` matrix of video processors by recursive pixel search.

    Parameters
    ----------
    tris : screen triangles (``width = p*2**n``, ``height = q*2**n``).
    matrix : ``"PxQ"`` or ``(p, q)``, powers of two.
    alpha, beta : the filter aperture in pixels (window size at levels below n; the paper's
        examples use 2 x 2). Any value >= 0 gives the same image; it changes the counts.
    test : window coverage test below the pixel level: ``"exact"`` (the window rectangle meets
        the triangle: the three edges and the triangle's bounding box, the paper's "filtered
        polygon" count) or ``"edges"`` (the three edges only). Same image either way.
    depth : ``"float"`` (reference arithmetic, bit-identical image) or ``"fixed"`` (quantised
        depth as a fixed-point plane, the bit-accurate layer).
    per_record : also keep ``stats["windows_per_record"]``, ``(p*q, T, n + 1)`` int32: the windows
        leaving each level for every (processor, broadcast record) pair (level 0: the root, 1;
        level n: pixels passing the point test), what the cycle models of :mod:`.cycles` price.
    trace : also keep ``stats["trace"]``: for every level ``i`` (list index ``i - 1``) the windows
        entering it in the order a processor's stage takes them, as ``(proc (R,), rt (R,), ok (R, 4))``
        (``ok``: which of the four sub-windows survive, in the order ``(0,0), (1,0), (0,1), (1,1)``);
        what the video processor's cycle model (:mod:`.vpcycles`) steps through.
    """
    p, q = parse_matrix(matrix)
    W, H = tris.width, tris.height
    n = sparse_geometry(W, H, p, q)
    al, be = _check_aperture("alpha", alpha), _check_aperture("beta", beta)
    if test not in ("exact", "edges"):
        raise RasterhwError(f"sparse: test must be 'exact' or 'edges', not {test!r}")
    if depth not in ("float", "fixed"):
        raise RasterhwError(f"sparse: depth must be 'float' or 'fixed', not {depth!r}")
    xy, z, vcol = tris.validate(who="sparse", max_coord=float(1 << 13))
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (3,) or not np.all(np.isfinite(bg)):
        raise RasterhwError(f"sparse: background must be three finite numbers, not {background!r}")
    es = edge_setup(xy)
    T = es.tri.size
    P = p * q
    Ns = 1 << n

    # Root records: every kept triangle on every processor (the broadcast).
    proc = np.tile(np.arange(P, dtype=np.int64), T)
    rt = np.repeat(np.arange(T, dtype=np.int64), P)  # kept-triangle index of each record
    pa, pb = proc % p, proc // p
    A, B = es.A[:, rt], es.B[:, rt]  # (3, R) per full-raster pixel
    Ap, Bp = p * A, q * B  # per sparse pixel
    E = es.C[:, rt] + pa * A + pb * B  # C' = C + aA + bB, the value at sparse pixel (0, 0)
    u0 = np.zeros(rt.size, dtype=np.int64)
    v0 = np.zeros(rt.size, dtype=np.int64)
    windows = np.zeros(n + 1, dtype=np.int64)
    tests = np.zeros(n + 1, dtype=np.int64)
    wpp = np.zeros((P, n + 1), dtype=np.int64)
    tpp = np.zeros((P, n + 1), dtype=np.int64)
    windows[0] = rt.size
    wpp[:, 0] = T
    wrec = np.zeros((P, T, n + 1), dtype=np.int32) if per_record else None
    if per_record:
        wrec[:, :, 0] = 1
    tr: list = []
    thr_all = es.thr
    ext_all = (np.abs(es.A) * al + np.abs(es.B) * be) // 2  # aperture growth, exact (A, B even)
    ap_n = 0
    # a big matrix is millions of records (64x64 on c300: 7.3 M, about a minute): a bar per level
    # for a person at a terminal (logs and pipes get nothing)
    big = rt.size >= BIG_RECORDS and sys.stderr.isatty()
    for i in tqdm(range(1, n + 1), desc=f"sparse {p}x{q}: {rt.size:,} records, level", disable=not big,
                  file=sys.stderr, leave=False):
        N = 1 << (n - i)
        # Four children per record: origins (u0 + du*N, v0 + dv*N), corner values by increments.
        du = np.array([0, 1, 0, 1], dtype=np.int64)
        dv = np.array([0, 0, 1, 1], dtype=np.int64)
        R = rt.size
        tests[i] = 4 * R
        tpp[:, i] = 4 * np.bincount(proc, minlength=P)
        rt4 = np.repeat(rt, 4)
        proc4 = np.repeat(proc, 4)
        du4 = np.tile(du, R) * N
        dv4 = np.tile(dv, R) * N
        Ap4 = np.repeat(Ap, 4, axis=1)
        Bp4 = np.repeat(Bp, 4, axis=1)
        E4 = np.repeat(E, 4, axis=1) + Ap4 * du4 + Bp4 * dv4
        thr = thr_all[:, rt4]
        u4 = np.repeat(u0, 4) + du4
        v4 = np.repeat(v0, 4) + dv4
        if test == "exact":
            # The window rectangle (sub-pixel units) against the triangle's bounding box.
            pa4, pb4 = proc4 % p, proc4 // p
            bb = es.bbox[:, rt4]
            x0 = (p * u4 + pa4) * _SUB + _HALF - al * _HALF
            x1 = (p * (u4 + N - 1) + pa4) * _SUB + _HALF + al * _HALF
            y0 = (q * v4 + pb4) * _SUB + _HALF - be * _HALF
            y1 = (q * (v4 + N - 1) + pb4) * _SUB + _HALF + be * _HALF
            inbox = (x1 >= bb[0]) & (x0 <= bb[1]) & (y1 >= bb[2]) & (y0 <= bb[3])
        else:
            inbox = True
        if i < n:
            # Largest value of each edge over the window rectangle (sample span plus aperture).
            mx = E4 + (np.maximum(Ap4, 0) + np.maximum(Bp4, 0)) * (N - 1) + ext_all[:, rt4]
            ok = (mx >= thr).all(axis=0) & inbox
        else:
            ok_ap = ((E4 + ext_all[:, rt4]) >= thr).all(axis=0) & inbox
            ap_n = int(np.count_nonzero(ok_ap))
            ok = (E4 >= thr).all(axis=0)
        if trace:
            tr.append((proc, rt, ok.reshape(R, 4)))
        keep = np.flatnonzero(ok)
        rt, proc = rt4[keep], proc4[keep]
        E, Ap, Bp = E4[:, keep], Ap4[:, keep], Bp4[:, keep]
        u0, v0 = u4[keep], v4[keep]
        windows[i] = rt.size
        wpp[:, i] = np.bincount(proc, minlength=P)
        if per_record:
            wrec[:, :, i] = np.bincount(rt * P + proc, minlength=T * P).reshape(T, P).T
        if i < n:
            check_signed("window corner value", mx, EDGE_BITS)

    # Pixel processors: fragments (kept-triangle rt, processor, sparse pixel u0, v0, edges E).
    F = rt.size
    tri = es.tri[rt]
    pa, pb = proc % p, proc // p
    x = p * u0 + pa
    y = q * v0 + pb
    zt = z[tri].T  # (3, F)
    if depth == "float":
        # Barycentric weights from the exact (unsigned) edge values, the reference's order.
        s = es.sign[rt]
        area = es.area[rt].astype(np.float64)
        w1 = (s * E[1]).astype(np.float64) / area
        w2 = (s * E[2]).astype(np.float64) / area
        w0 = (1.0 - w1) - w2
        zz = zt[0] * w0
        zz += zt[1] * w1
        zz += zt[2] * w2
        key = zz
    else:

        Z0, Zu, Zv = depth_plane(tris, es, p, q)  # (T, q, p), (T,), (T,)
        acc = Z0[rt, pb, pa] + Zu[rt] * u0 + Zv[rt] * v0
        zmax = (1 << tris.z_bits) - 1
        zqv = np.clip(acc >> Z_FRAC_BITS, 0, zmax)
        key = zqv.astype(np.float64)
        zz = key / float(1 << tris.z_bits)
    # Local memory address of each fragment in its processor (the pixel processor's write).
    laddr = (proc * Ns + v0) * Ns + u0
    # Z test per local address in submission order (z_new < z_stored): the final owner is the
    # first fragment with the smallest depth; a fragment is written if it is below the running
    # minimum of the earlier ones.
    order = np.lexsort((tri, laddr))
    la_s, key_s, tri_s = laddr[order], key[order], tri[order]
    written = 0
    writes_pp = np.zeros(P, dtype=np.int64)
    nloc = P * Ns * Ns
    depth_loc = np.full(nloc, np.inf)
    tri_loc = np.full(nloc, -1, dtype=np.int64)
    col_loc = np.empty((nloc, 3))
    col_loc[:] = bg
    if F:
        newg = np.ones(F, dtype=bool)
        newg[1:] = la_s[1:] != la_s[:-1]
        gid = np.cumsum(newg) - 1
        G = int(gid[-1]) + 1
        rank = np.empty(F, dtype=np.int64)
        rank[np.lexsort((tri_s, key_s))] = np.arange(F)  # order of depth, ties by submission
        c = (G - gid) * F + rank
        run = np.minimum.accumulate(c)
        wr = newg.copy()
        wr[1:] |= c[1:] < run[:-1]
        written = int(np.count_nonzero(wr))
        writes_pp = np.bincount(proc[order][wr], minlength=P)
        # Winner of each address: the fragment of smallest rank in its group.
        first = np.flatnonzero(newg)
        best = np.minimum.reduceat(rank, first)
        inv = np.empty(F, dtype=np.int64)
        inv[rank] = np.arange(F)
        wfrag = order[inv[best]]
        wl = laddr[wfrag]
        depth_loc[wl] = zz[wfrag]
        tri_loc[wl] = tri[wfrag]
        # Colour of the winners (float barycentric in both layers: only depth is fixed-point).
        s = es.sign[rt[wfrag]]
        area = es.area[rt[wfrag]].astype(np.float64)
        a1 = (s * E[1, wfrag]).astype(np.float64) / area
        a2 = (s * E[2, wfrag]).astype(np.float64) / area
        a0 = (1.0 - a1) - a2
        cw = vcol[tri[wfrag]]  # (Fw, 3 vertices, 3 channels)
        for ch in range(3):
            v = a0 * cw[:, 0, ch]
            v += a1 * cw[:, 1, ch]
            col_loc[wl, ch] = v + a2 * cw[:, 2, ch]
    shape = (q, p, Ns, Ns)
    local_tri = tri_loc.reshape(shape)
    written_by = np.where(local_tri >= 0, np.arange(P).reshape(q, p, 1, 1), -1)
    return SparseFrame(
        p=p, q=q, n=n, colour=interleave(col_loc.reshape(*shape, 3)),
        depth=interleave(depth_loc.reshape(shape)), tri_id=interleave(local_tri),
        writer=interleave(written_by), local_tri=local_tri,
        windows=windows, tests=tests, windows_aperture_n=ap_n, windows_per_proc=wpp,
        tests_per_proc=tpp, fragments=int(F), pixels_written=written, triangles=int(T),
        stats={"alpha": al, "beta": be, "test": test, "depth": depth, "frag_x": x, "frag_y": y, "frag_proc": proc,
               "frag_tri": tri, "writes_per_proc": writes_pp, **({"windows_per_record": wrec} if per_record else {}),
               **({"trace": tr} if trace else {})})
