"""The same machine one element at a time: plain Python floats and lists, no NumPy in the loops.

This is our "scalar" run of the paper's tables (the columns スカラ): the same set-up, segment
building, algorithm 1 / 2, shadow counting and eye -> light transform as the vector model, each
written as loops over single elements, so the vectorisation gain is measured the paper's way
(scalar time / vector time of the same stage on the same data). NumPy arrays only cross the
boundary (inputs in, buffers out). The tests check the scalar results against the vector ones.
"""

from __future__ import annotations

import math
import time

import numpy as np
from rasterhw.golden_model.pipeline import frame_setup
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.vzbuf.blocks import SUB
from rasterhw.golden_model.vzbuf.segments import SegmentBlock

__all__ = ["scalar_setup", "scalar_segments", "scalar_split", "scalar_alg1", "scalar_alg2",
           "scalar_transform", "scalar_run"]

_PLANES = ((2, 0), (2, 1), (0, -1), (0, 1), (1, -1), (1, 1))  # near, far, left, right, bottom, top


def _snap(v: float) -> float:
    return math.floor(v * SUB + 0.5)


def scalar_setup(scene: Scene, width: int, height: int, ia: float, k: float, *, lit: bool = True) -> list:
    """Transform, back-face removal, intensity, clipping, divide, map, snap, plane: per polygon."""
    fs = frame_setup(scene, width, height)
    mvp = fs.mvp.tolist()
    nmat = fs.normal_matrix.tolist()
    tl = fs.lighting.to_light[0].tolist() if lit else [0.0, 0.0, 0.0]
    near = fs.near
    out = []
    pos = scene.positions.tolist()
    nrm = scene.normals.tolist()
    for p in range(scene.n_polygons):
        n = int(scene.nverts[p])
        cs = []
        for c in range(n):
            x, y, z = pos[p][c]
            cs.append([m[0] * x + m[1] * y + m[2] * z + m[3] for m in mvp])
        (x0, y0, _, w0), (x1, y1, _, w1), (x2, y2, _, w2) = cs[0], cs[1], cs[2]
        det = x0 * (y1 * w2 - w1 * y2) - y0 * (x1 * w2 - w1 * x2) + w0 * (x1 * y2 - y1 * x2)
        if not det > 0:
            continue
        verts = []
        for c in range(n):
            nx, ny, nz = nrm[p][c]
            e = [m[0] * nx + m[1] * ny + m[2] * nz for m in nmat]
            inv = 1.0 / math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            d = (e[0] * tl[0] + e[1] * tl[1] + e[2] * tl[2]) * inv
            i = min(ia + k * (d if d > 0 else 0.0), 1.0)
            verts.append(cs[c] + [i])
        for axis, side in _PLANES:
            if not verts:
                break
            def dist(v, axis=axis, side=side):
                return v[axis] if side == 0 else (v[3] - v[axis] if side > 0 else v[3] + v[axis])
            ins = [dist(v) >= 0 if side == 0 else (v[axis] <= v[3] if side > 0 else v[axis] >= -v[3])
                   for v in verts]
            if all(ins):
                continue
            new = []
            m = len(verts)
            for j in range(m):
                a, b = verts[j - 1], verts[j]
                if ins[j - 1] != ins[j]:
                    vin, vout = (a, b) if ins[j - 1] else (b, a)
                    di, do = dist(vin), dist(vout)
                    t = di / (di - do)
                    nv = [vin[q] + t * (vout[q] - vin[q]) for q in range(5)]
                    if side == 0:
                        nv[2], nv[3] = 0.0, near
                    new.append(nv)
                if ins[j]:
                    new.append(b)
            verts = new if len(new) >= 3 else []
        if not verts:
            continue
        X, Y, Z, inten = [], [], [], []
        for v in verts:
            iw = 1.0 / v[3]
            sx = min(max(v[0] * iw * (0.5 * width) + 0.5 * width, 0.0), float(width))
            sy = min(max(v[1] * iw * (-0.5 * height) + 0.5 * height, 0.0), float(height))
            X.append(_snap(sx))
            Y.append(_snap(sy))
            Z.append(min(v[2] * iw, 1.0))
            inten.append(v[4])
        out.extend(_planar(X, Y, Z, inten, p))
    return out


def _planar(X, Y, Z, inten, p) -> list:
    """Convexity in integers (else the fan triangles, each a polygon), then the plane fit."""
    n = len(X)
    area = sum(X[j] * Y[(j + 1) % n] - X[(j + 1) % n] * Y[j] for j in range(n))
    s = (area > 0) - (area < 0)
    for j in range(n):
        a, b, c = j, (j + 1) % n, (j + 2) % n
        turn = (X[b] - X[a]) * (Y[c] - Y[b]) - (Y[b] - Y[a]) * (X[c] - X[b])
        if turn * s < 0:
            out = []
            for t in range(1, n - 1):
                out.extend(_planar([X[0], X[t], X[t + 1]], [Y[0], Y[t], Y[t + 1]], [Z[0], Z[t], Z[t + 1]],
                                   [inten[0], inten[t], inten[t + 1]], p))
            return out
    xs, ys = [x / SUB for x in X], [y / SUB for y in Y]
    cx, cy, cz = sum(xs) / n, sum(ys) / n, sum(Z) / n
    sxx = sxy = syy = sxz = syz = 0.0
    for j in range(n):
        dx, dy, dz = xs[j] - cx, ys[j] - cy, Z[j] - cz
        sxx += dx * dx
        sxy += dx * dy
        syy += dy * dy
        sxz += dx * dz
        syz += dy * dz
    det = sxx * syy - sxy * sxy
    if det > 0:
        a = (sxz * syy - syz * sxy) / det
        b = (syz * sxx - sxz * sxy) / det
        c = cz - a * cx - b * cy
        Z = [a * xs[j] + b * ys[j] + c for j in range(n)]
    else:
        a = b = 0.0
    return [{"X": X, "Y": Y, "z": Z, "i": inten, "poly": p, "dzdx": a, "s": s}]


def scalar_segments(polys: list, height: int) -> list:
    """Fig. 1 per polygon: each (left edge, right edge) pair that shares lines is a segment."""
    segs = []
    half = SUB // 2
    for q, P in enumerate(polys):
        X, Y, Z, inten, s = P["X"], P["Y"], P["z"], P["i"], P["s"]
        n = len(X)
        lefts, rights = [], []
        for j in range(n):
            b = (j + 1) % n
            tdx, tdy = X[b] - X[j], Y[b] - Y[j]
            if s * tdy == 0:
                continue
            top, bot = (j, b) if Y[j] <= Y[b] else (b, j)
            r0 = max(math.ceil((Y[top] - half) / SUB), 0)
            r1 = min(math.ceil((Y[bot] - half) / SUB) - 1, height - 1)
            e = {"r0": r0, "r1": r1, "XA": X[top], "YA": Y[top], "XB": X[bot], "YB": Y[bot], "zA": Z[top],
                 "zB": Z[bot], "iA": inten[top], "iB": inten[bot], "s": s, "thr": 0.0 if s * tdy < 0 else 1.0,
                 "tdx": tdx, "tdy": tdy, "tXa": X[j], "tYa": Y[j]}
            (lefts if s * tdy < 0 else rights).append(e)
        for L in lefts:
            for R in rights:
                lo, hi = max(L["r0"], R["r0"]), min(L["r1"], R["r1"])
                if hi >= lo:
                    segs.append({"y0": lo, "yend": hi, "q": q, "L": L, "R": R, "dzdx": P["dzdx"],
                                 "part": 0, "parts": 1})
    return segs


def _edge(e: dict, row: int) -> list:
    """[x, dxdy, z, dzdy, i, didy, n, dn, ss] of edge ``e`` at line ``row``."""
    dX, dY = e["XB"] - e["XA"], e["YB"] - e["YA"]
    Yc = row * SUB + SUB // 2
    t = (Yc - e["YA"]) / dY
    k = -e["tdx"] * e["tYa"] - e["tdy"] * (SUB // 2 - e["tXa"])
    s = e["s"]
    return [(e["XA"] + t * dX) / SUB, dX / dY, e["zA"] + t * (e["zB"] - e["zA"]), (e["zB"] - e["zA"]) * SUB / dY,
            e["iA"] + t * (e["iB"] - e["iA"]), (e["iB"] - e["iA"]) * SUB / dY,
            e["thr"] - s * (e["tdx"] * Yc + k), -s * e["tdx"] * SUB, s * (-SUB * e["tdy"])]


def _span(L, R, part, parts, width):
    lo = max(math.ceil(L[6] / L[8]), 0)
    hi = min(math.floor(R[6] / R[8]), width - 1)
    if parts > 1:
        n = max(hi - lo + 1, 0)
        lo, hi = lo + (part * n) // parts, lo + ((part + 1) * n) // parts - 1
    return lo, hi


def scalar_split(segs: list, width: int) -> list:
    """Algorithm 2's split, one segment at a time (same rule as :func:`segments.split_segments`)."""
    if not segs:
        return []
    xl, yl = [], []
    for g in segs:
        best = 0
        for row in (g["y0"], g["yend"]):
            lo, hi = _span(_edge(g["L"], row), _edge(g["R"], row), 0, 1, width)
            best = max(best, hi - lo + 1)
        xl.append(best)
        yl.append(g["yend"] - g["y0"] + 1)
    mx, my = sum(xl) / len(xl), sum(yl) / len(yl)
    out = []
    for g, x, y in zip(segs, xl, yl, strict=True):
        ky = math.ceil(y / my) if y > my else 1
        kx = math.ceil(x / mx) if x > mx else 1
        for p in range(ky):
            y0 = g["y0"] + (p * y) // ky
            y1 = g["y0"] + ((p + 1) * y) // ky - 1
            for j in range(kx):
                out.append({**g, "y0": y0, "yend": y1, "part": j, "parts": kx})
    return out


def _line_work(g, L, R, width):
    lo, hi = _span(L, R, g["part"], g["parts"], width)
    xl, xr, il, ir = L[0], R[0], L[4], R[4]
    didx = (ir - il) / (xr - xl) if xr > xl else 0.0
    return lo, hi, xl, L[2], il, didx


def _buffers(segs: list, width: int, height: int):
    """Cleared frame buffers (depth, polygon id, intensity, shadow count) and the y-list: the
    segments that start on each line, in order."""
    n = width * height
    ylist = [[] for _ in range(height)]
    for si, g in enumerate(segs):
        ylist[g["y0"]].append(si)
    return [math.inf] * n, [-1] * n, [0.0] * n, [0] * n, ylist


def scalar_alg1(segs: list, width: int, height: int, *, mode: str = "real", zframe=None, sign=None,
                full_frame: bool = False):
    """Algorithm 1, one pixel at a time. Returns (depth, qid, inten, count) as flat lists."""
    inf = math.inf
    depth, qid, inten, count, ylist = _buffers(segs, width, height)
    edges = {}
    xlist = []
    zline = [inf] * width
    for y in range(height):
        xlist = [si for si in xlist if segs[si]["yend"] >= y]
        for si in ylist[y]:
            g = segs[si]
            edges[si] = (_edge(g["L"], y), _edge(g["R"], y))
            xlist.append(si)
        if not xlist:
            continue
        base = y * width
        if mode == "real" and not full_frame:
            for x in range(width):
                zline[x] = inf
        for si in xlist:
            g = segs[si]
            L, R = edges[si]
            lo, hi, xl, zl, il, didx = _line_work(g, L, R, width)
            dz = g["dzdx"]
            for col in range(lo, hi + 1):
                xc = col + 0.5 - xl
                z = zl + dz * xc
                if mode == "real":
                    if full_frame:
                        if z < depth[base + col]:
                            depth[base + col] = z
                            qid[base + col] = g["q"]
                            inten[base + col] = il + didx * xc
                    elif z < zline[col]:
                        zline[col] = z
                        qid[base + col] = g["q"]
                        inten[base + col] = il + didx * xc
                elif mode == "shadow":
                    if z < zframe[base + col]:
                        count[base + col] += sign[si]
                elif z < depth[base + col]:
                    depth[base + col] = z
        if mode == "real" and not full_frame:
            depth[base:base + width] = zline
        for si in xlist:
            for e in edges[si]:
                e[0] += e[1]
                e[2] += e[3]
                e[4] += e[5]
                e[6] += e[7]
    return depth, qid, inten, count


def scalar_alg2(segs: list, width: int, height: int, *, mode: str = "real", zframe=None, sign=None):
    """Algorithm 2, one slot and one pixel at a time. Returns flat lists as :func:`scalar_alg1`."""
    depth, qid, inten, count, ylist = _buffers(segs, width, height)
    head = [0] * height
    slist = [-1] * height
    edges = {}
    while True:
        for y in range(height):
            si = slist[y]
            if si >= 0 and segs[si]["yend"] < y:
                slist[y] = -1
            if slist[y] < 0 and head[y] < len(ylist[y]):
                si = ylist[y][head[y]]
                head[y] += 1
                g = segs[si]
                edges[si] = (_edge(g["L"], y), _edge(g["R"], y))
                slist[y] = si
        work = []
        longest = 0
        for y in range(height):
            si = slist[y]
            if si >= 0:
                g = segs[si]
                L, R = edges[si]
                w = _line_work(g, L, R, width)
                work.append((y, si, g, w))
                longest = max(longest, w[1] - w[0] + 1)
        if not work:
            break
        for k in range(longest):
            for y, si, g, (lo, hi, xl, zl, il, didx) in work:
                col = lo + k
                if col > hi:
                    continue
                pix = y * width + col
                xc = col + 0.5 - xl
                z = zl + g["dzdx"] * xc
                if mode == "real":
                    if z < depth[pix]:
                        depth[pix] = z
                        qid[pix] = g["q"]
                        inten[pix] = il + didx * xc
                elif mode == "shadow":
                    if z < zframe[pix]:
                        count[pix] += sign[si]
                elif z < depth[pix]:
                    depth[pix] = z
        for _y, si, _g, _w in work:
            for e in edges[si]:
                e[0] += e[1]
                e[2] += e[3]
                e[4] += e[5]
                e[6] += e[7]
        for y in range(height - 1, 0, -1):
            slist[y] = slist[y - 1]
        slist[0] = -1
    return depth, qid, inten, count


def scalar_transform(m: np.ndarray, depth: list, qid: list, width: int) -> list:
    """Every visible pixel through one 4x4 (eye screen -> light screen), one at a time."""
    mm = m.tolist()
    out = []
    for pix, q in enumerate(qid):
        if q < 0:
            continue
        x, y, z = pix % width + 0.5, pix // width + 0.5, depth[pix]
        r = [a[0] * x + a[1] * y + a[2] * z + a[3] for a in mm]
        iw = 1.0 / r[3]
        out.append((pix, r[0] * iw, r[1] * iw, r[2] * iw))
    return out


def segments_to_scalar(seg: SegmentBlock) -> list:
    """Vector segment blocks as the scalar model's dicts (to run both HSRs on identical input)."""
    out = []
    src = {k: v.tolist() for k, v in seg.src.items()}
    for s in range(seg.n):
        e = {}
        for side in ("L", "R"):
            e[side] = {k: src[f"{side}{k}"][s] for k in ("XA", "YA", "XB", "YB", "zA", "zB", "iA", "iB", "s",
                                                          "thr", "tdx", "tdy", "tXa", "tYa")}
        out.append({"y0": int(seg.y0[s]), "yend": int(seg.yend[s]), "q": int(seg.poly[s]), "L": e["L"],
                    "R": e["R"], "dzdx": float(seg.dzdx[s]), "part": int(seg.part[s]), "parts": int(seg.parts[s])})
    return out


def scalar_run(scene: Scene, width: int, height: int, *, alg: int, shadows: str = "none", eps: float = 5e-3,
               shadow_quads=None) -> dict:
    """The whole frame one element at a time; returns the stage CPU times (s) like render_frame."""
    from rasterhw.golden_model.vzbuf.blocks import blocks_from_scene
    from rasterhw.golden_model.vzbuf.shadows import light_space, screen_to_light_matrix

    clock = time.process_time
    t0 = clock()
    blk = blocks_from_scene(scene, width, height)
    ia, k = blk.control.ia, blk.control.k
    polys = scalar_setup(scene, width, height, ia, k)
    sq = None
    if shadows == "polygons":
        sq = scalar_shadow_quads(scene)
        front = scalar_setup(_quad_scene(scene, sq, False), width, height, 0.0, 0.0, lit=False)
        back = scalar_setup(_quad_scene(scene, sq, True), width, height, 0.0, 0.0, lit=False)
    t1 = clock()
    segs = scalar_segments(polys, height)
    if alg == 2:
        segs = scalar_split(segs, width)
    ssegs, sign = [], []
    if sq is not None:
        for lst, sg in ((front, 1), (back, -1)):
            s_ = scalar_segments(lst, height)
            ssegs.extend(s_)
            sign.extend([sg] * len(s_))
        if alg == 2 and ssegs:
            raw = ssegs
            ssegs = scalar_split(raw, width)
            # signs follow their source segment (split keeps order, pieces share L/R dicts)
            ids = {id(g["L"]): sg for g, sg in zip(raw, sign, strict=True)}
            sign = [ids[id(g["L"])] for g in ssegs]
    t2 = clock()
    run = scalar_alg1 if alg == 1 else scalar_alg2
    kw = {"full_frame": True} if (alg == 1 and shadows == "map") else {}
    depth, qid, inten, _ = run(segs, width, height, **kw)
    t3 = clock()
    t4 = t3
    if ssegs:
        _, _, _, count = run(ssegs, width, height, mode="shadow", zframe=depth, sign=sign)
        for pix in range(width * height):
            if qid[pix] >= 0 and count[pix] > 0:
                inten[pix] = ia
        t4 = clock()
    st = {}
    if shadows == "map":
        a = clock()
        ls = light_space(scene, width, height)
        lpolys = scalar_light_polys(scene, ls)
        lsegs = scalar_segments(lpolys, height)
        if alg == 2:
            lsegs = scalar_split(lsegs, width)
        b = clock()
        ldepth, _, _, _ = run(lsegs, width, height, mode="depth", **kw)
        c = clock()
        mt = screen_to_light_matrix(scene, width, height, ls)
        for pix, x1, y1, z1 in scalar_transform(mt, depth, qid, width):
            tx = min(max(math.floor(x1), 0), width - 1)
            ty = min(max(math.floor(y1), 0), height - 1)
            if z1 - ldepth[ty * width + tx] > eps:
                inten[pix] = ia
        d = clock()
        st = {"light": (b - a) + (c - b), "transform": d - c}
    t5 = clock()
    _ = [0] * (width * height)  # final image store: one element at a time below
    for pix in range(width * height):
        if qid[pix] >= 0:
            _[pix] = int(inten[pix] * 127 + 0.5)
    t6 = clock()
    setup_s, seg_s, hsr_s, sh_s, q_s = t1 - t0, t2 - t1, t3 - t2, t4 - t3, t6 - t5
    if shadows == "none":
        stages = {"1": setup_s, "2": hsr_s, "3": seg_s + q_s}
    elif shadows == "polygons" and alg == 1:
        stages = {"1": setup_s, "2": hsr_s + sh_s, "3": seg_s + q_s}
    elif shadows == "polygons":
        stages = {"1": setup_s, "2": hsr_s, "3": sh_s, "4": seg_s + q_s}
    else:
        stages = {"1": setup_s + seg_s + hsr_s, "2": st["light"], "3": st["transform"], "4": q_s}
    return {"stages": stages, "depth": depth, "qid": qid, "inten": inten, "segments": len(segs),
            "polys": polys}


def scalar_shadow_quads(scene: Scene) -> list:
    """Silhouette edges -> shadow quads (outward winding), one edge at a time."""
    from rasterhw.golden_model.vzbuf.blocks import ground_polygons
    from rasterhw.golden_model.vzbuf.shadows import face_normals

    lv = np.asarray(scene.lights[0].direction, float)
    lv = (lv / np.linalg.norm(lv)).tolist()
    ground = set(ground_polygons(scene).tolist())
    g = min(ground)
    fn = face_normals(scene).tolist()
    gn = fn[g]
    gl = math.sqrt(sum(c * c for c in gn))
    gn = [c / gl for c in gn]
    g0 = scene.positions[g, 0].tolist()
    ln = sum(a * b for a, b in zip(lv, gn, strict=True))
    pos = scene.positions.tolist()
    edges: dict = {}
    for p in range(scene.n_polygons):
        if p in ground:
            continue
        n = int(scene.nverts[p])
        for c in range(n):
            a, b = tuple(pos[p][c]), tuple(pos[p][(c + 1) % n])
            if a == b:
                continue
            key = (min(a, b), max(a, b))
            edges.setdefault(key, []).append((p, a, b))
    quads = []
    for lst in edges.values():
        if len(lst) != 2:
            continue
        (p, a, b), (q, _, _) = lst
        lp = sum(x * y for x, y in zip(fn[p], lv, strict=True)) < 0
        lq = sum(x * y for x, y in zip(fn[q], lv, strict=True)) < 0
        if lp == lq:
            continue
        ta = sum((g0[i] - a[i]) * gn[i] for i in range(3)) / ln
        tb = sum((g0[i] - b[i]) * gn[i] for i in range(3)) / ln
        if not (ta > 1e-9 or tb > 1e-9):
            continue
        ta, tb = max(ta, 0.0), max(tb, 0.0)
        a2 = [a[i] + ta * lv[i] for i in range(3)]
        b2 = [b[i] + tb * lv[i] for i in range(3)]
        quads.append((a, b, b2, a2, fn[p], fn[q]))
    return quads


def _quad_scene(scene: Scene, quads: list, reverse: bool) -> Scene:
    from dataclasses import replace

    from rasterhw.golden_model.vzbuf.shadows import _unit_rows

    lv = np.asarray(scene.lights[0].direction, float)
    lv = lv / np.linalg.norm(lv)
    if not quads:
        return scene
    q = np.array([[a, b, b2, a2] for a, b, b2, a2, _, _ in quads], float)
    fp = _unit_rows(np.array([x[4] for x in quads]))
    fq = _unit_rows(np.array([x[5] for x in quads]))
    ns = np.cross(q[:, 1] - q[:, 0], lv)
    out = np.einsum("ij,ij->i", ns, fp + fq) > 0
    ns = np.where(out[:, None], ns, -ns)
    wn = np.cross(q[:, 1] - q[:, 0], q[:, 3] - q[:, 0]) + np.cross(q[:, 2] - q[:, 1], q[:, 0] - q[:, 1])
    flip = np.einsum("ij,ij->i", wn, ns) < 0
    q = np.where(flip[:, None, None], q[:, [1, 0, 3, 2]], q)
    if reverse:
        q, ns = q[:, ::-1], -ns
    return replace(scene, positions=q, normals=np.repeat(ns[:, None], 4, 1), colours=np.ones_like(q),
                   nverts=np.full(len(q), 4, np.int64))


def scalar_light_polys(scene: Scene, ls: dict) -> list:
    """Light-facing polygons to light space, one vertex at a time."""
    from rasterhw.golden_model.vzbuf.shadows import face_normals

    m = ls["matrix"].tolist()
    lv = ls["lv"].tolist()
    fn = face_normals(scene).tolist()
    pos = scene.positions.tolist()
    out = []
    for p in range(scene.n_polygons):
        if not sum(a * b for a, b in zip(fn[p], lv, strict=True)) < 0:
            continue
        n = int(scene.nverts[p])
        X, Y, Z = [], [], []
        for c in range(n):
            x, y, z = pos[p][c]
            r = [a[0] * x + a[1] * y + a[2] * z + a[3] for a in m[:3]]
            X.append(_snap(r[0]))
            Y.append(_snap(r[1]))
            Z.append(r[2])
        out.extend(_planar(X, Y, Z, [0.0] * n, p))
    return out
