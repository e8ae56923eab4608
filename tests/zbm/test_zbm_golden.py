"""ZB/M golden model: formats, edge pairs, segment generator, chips, merge, composite, cycles."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model import reference as ref
from rasterhw.golden_model import zbm as zbm
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.screen import ScreenTriangles
from rasterhw.golden_model.zbm import cycles as cyc
from rasterhw.golden_model.zbm import formats as fmt


def exact_cover(tris: ScreenTriangles) -> list[np.ndarray]:
    """Independent exact top-left coverage: integer edge functions, brute force per triangle."""
    H, W, S = tris.height, tris.width, 1 << fmt.SUBPIX_BITS
    cx = np.arange(W) * S + S // 2
    cy = np.arange(H) * S + S // 2
    PX, PY = np.meshgrid(cx, cy)
    out = []
    for t in range(tris.n_triangles):
        X = np.floor(tris.xy[t, :, 0] * S + 0.5).astype(np.int64)
        Y = np.floor(tris.xy[t, :, 1] * S + 0.5).astype(np.int64)
        area = (X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0])
        m = np.zeros((H, W), bool)
        if area != 0:
            if area < 0:
                X, Y = X[[0, 2, 1]], Y[[0, 2, 1]]
            m[:] = True
            for i in range(3):
                xa, ya, xb, yb = X[i], Y[i], X[(i + 1) % 3], Y[(i + 1) % 3]
                e = (xb - xa) * (PY - ya) - (yb - ya) * (PX - xa)
                topleft = (yb < ya) or (yb == ya and xb > xa)
                m &= (e > 0) | ((e == 0) & topleft)
        out.append(m)
    return out


def tri(xy, z=(0.5, 0.5, 0.5), colour=None, w=16, h=16) -> ScreenTriangles:
    xy = np.asarray(xy, float).reshape(-1, 3, 2)
    t = xy.shape[0]
    z = np.broadcast_to(np.asarray(z, float), (t, 3)).copy()
    col = np.full((t, 3, 3), 0.5) if colour is None else np.broadcast_to(colour, (t, 3, 3)).copy()
    return ScreenTriangles(width=w, height=h, xy=xy, z=z, zq=np.rint(z * 0xFFFFFF).astype(np.int64),
                           colour=col, poly_id=np.arange(t))


# ----------------------------------------------------------------- formats
def test_formats_fit_paper_words():
    assert fmt.FLIT.width == fmt.LOOP_BITS == 112 and fmt.FLIT.used == 112
    assert fmt.PKT_HEADER.used <= 112 and fmt.SEG_HEADER.used <= 112
    assert fmt.SAMPLE.width == 64 and fmt.PIXEL2.width == 128
    # mapping mode: header + z, um, vm, ui, vi, a = 7 flits <= 8; loader: 1 + 8 words = 9 cycles
    assert 1 + len(fmt.CHANNELS[fmt.MODE_MAPPING]) <= fmt.PACKET_FLITS == 8
    assert 1 + 2 + len(fmt.CHANNELS[fmt.MODE_MAPPING]) == fmt.EP_WORDS == fmt.EP_LOAD_CYCLES == 9
    assert 1 << fmt.SUBPIX_BITS == ref.SUBPIXEL


def test_pack_unpack_round_trip():
    rng = np.random.default_rng(1)
    for layout in (fmt.EP_HEADER, fmt.EP_CHANNEL, fmt.SEG_HEADER, fmt.FLIT, fmt.PKT_HEADER, fmt.SAMPLE):
        for _ in range(50):
            vals = {}
            for f in layout.fields:
                lo, hi = (-(1 << (f.width - 1)), (1 << (f.width - 1)) - 1) if f.signed else (0, (1 << f.width) - 1)
                vals[f.name] = int(rng.choice([lo, hi, 0, int(rng.integers(lo // 2 if lo else 0, hi // 2 + 1))]))
            word = layout.pack(**vals)
            assert 0 <= word < 1 << layout.width
            assert layout.unpack(word) == vals
    with pytest.raises(RasterhwError, match="y"):
        fmt.SEG_HEADER.pack(y=512)
    with pytest.raises(RasterhwError, match="value"):
        fmt.FLIT.pack(value=1 << 55)
    z = rng.integers(0, 1 << 24, 100)
    a = rng.integers(0, 256, 100)
    c = rng.integers(0, 256, (100, 4))
    w = fmt.pack_samples(z, a, c)
    z2, a2, c2 = fmt.unpack_samples(w)
    assert (z2 == z).all() and (a2 == a).all() and (c2 == c).all()
    assert int(w[3]) == fmt.SAMPLE.pack(z=int(z[3]), a=int(a[3]), c0=int(c[3, 0]), c1=int(c[3, 1]),
                                        c2=int(c[3, 2]), c3=int(c[3, 3]))


def test_edge_pair_words_round_trip():
    tris = ref.random_triangles(32, 32, 5, mean_area=40, seed=3)
    eps = zbm.edge_pairs(tris)
    for i in range(len(eps)):
        h, ch = fmt.unpack_edge_pair(eps.words(i))
        assert (h["y"], h["h"]) == (eps.y[i], eps.h[i])
        assert ch[0]["value"] == eps.x[i] and ch[1]["ddy"] == eps.dlendy[i]
        assert [c["ddx"] for c in ch[2:]] == list(eps.ddx[i])


# ----------------------------------------------------------------- edge pairs / coverage
def test_two_edge_pairs_per_triangle_and_flat_cases():
    eps = zbm.edge_pairs(tri([[1.2, 1.3], [10.7, 5.1], [4.4, 12.9]]))
    assert len(eps) == 2 and list(eps.tag) == [0, 0]
    assert eps.y[1] == eps.y[0] + eps.h[0]          # split at the middle vertex's line
    flat_top = zbm.edge_pairs(tri([[1, 1], [9, 1], [5, 9]]))
    assert len(flat_top) == 1                        # upper pair has no line
    assert len(zbm.edge_pairs(tri([[1, 1], [5, 5], [9, 9]]))) == 0   # degenerate


@pytest.mark.parametrize("w,h,n,area,seed", [(64, 32, 30, 60, 1), (48, 48, 80, 6, 2), (40, 40, 20, 400, 4)])
def test_segments_cover_exactly_the_triangle(w, h, n, area, seed):
    tris = ref.random_triangles(w, h, n, mean_area=area, seed=seed)
    segs = zbm.segment_generator(zbm.edge_pairs(tris), h, width=w)
    cover = exact_cover(tris)
    for t in range(n):
        m = np.zeros((h, w), bool)
        for s in np.flatnonzero(segs.tag == t):
            span = m[segs.y[s], segs.x[s]:segs.x[s] + segs.len[s]]
            assert not span.any()                    # the two pairs never overlap
            span[:] = True
        assert (m == cover[t]).all(), t


def test_fill_rule_on_exact_ties():
    # shared edge: the two halves of a square cover every pixel exactly once
    sq = tri([[[2, 2], [10, 2], [2, 10]], [[10, 2], [10, 10], [2, 10]]])
    segs = zbm.segment_generator(zbm.edge_pairs(sq), 16, width=16)
    m = np.zeros((16, 16), int)
    for s in range(segs.y.size):
        m[segs.y[s], segs.x[s]:segs.x[s] + segs.len[s]] += 1
    assert m.max() == 1 and m.sum() == 64 and (m[2:10, 2:10] == 1).all()
    # centres exactly on edges: left edge x = 2.5 (in), right x = 6.5 (out), top y = 2.5 (in)
    box = tri([[[2.5, 2.5], [6.5, 2.5], [2.5, 6.5]], [[6.5, 2.5], [6.5, 6.5], [2.5, 6.5]]])
    segs = zbm.segment_generator(zbm.edge_pairs(box), 16, width=16)
    m = np.zeros((16, 16), int)
    for s in range(segs.y.size):
        m[segs.y[s], segs.x[s]:segs.x[s] + segs.len[s]] += 1
    assert m.sum() == 16 and (m[2:6, 2:6] == 1).all()      # rows 2..5, columns 2..5


# ----------------------------------------------------------------- segment generator
def test_segment_generator_errors_and_stall():
    eps = zbm.edge_pairs(ref.random_triangles(32, 32, 12, mean_area=60, seed=7))
    with pytest.raises(RasterhwError, match="outside"):
        zbm.segment_generator(eps, 8, width=32)
    bad = eps.take(np.arange(len(eps)))
    bad.len[2] = -1
    with pytest.raises(RasterhwError, match="len -1"):
        zbm.segment_generator(bad, 32, width=32)
    with pytest.raises(RasterhwError, match="FIFO order"):
        zbm.segment_generator(eps.take(np.arange(len(eps))[::-1]), 32, width=32)
    with pytest.raises(RasterhwError, match="height"):
        zbm.segment_generator(eps, 600)
    full = zbm.segment_generator(eps, 32, width=32)
    assert full.stats["aep_max"] > 2
    # no loss: a stream needing more active pairs than the memory holds is an error that names
    # the line and the count; exactly at capacity it works and gives the same segments
    need, line = zbm.max_active_edge_pairs(eps)
    assert need == full.stats["aep_max"] > 2
    act = [(eps.y <= y) & (y < eps.y + eps.h) for y in range(32)]
    assert max(a.sum() for a in act) == need and act[line].sum() == need
    with pytest.raises(RasterhwError, match=rf"line {line} needs {need} simultaneously active"):
        zbm.segment_generator(eps, 32, width=32, capacity=need - 1)
    tris = ref.random_triangles(32, 32, 12, mean_area=60, seed=7)
    with pytest.raises(RasterhwError, match="capacity 2"):
        zbm.render_zbm(tris, capacity=2)
    exact = zbm.segment_generator(eps, 32, width=32, capacity=need)
    assert np.array_equal(exact.val, full.val) and np.array_equal(exact.ep, full.ep)
    assert zbm.max_active_edge_pairs(eps.take(np.arange(0))) == (0, 0)
    # all segments of one line are emitted together, lines in order
    assert (np.diff(full.y) >= 0).all()


# ----------------------------------------------------------------- chips, double Z, merge
def _ds(z, tag):
    d = zbm.DoubleZ.empty((len(z),))
    d.z[:] = z
    d.tag[:] = tag
    d.a[:] = 255
    return d


def test_double_z_keeps_two_nearest_with_tie_rule():
    # four full-screen-ish triangles, constant depths, submitted far to near and a tie
    quad = [[-1, -1], [17, -1], [-1, 17]]
    tris = tri([quad] * 4, z=np.array([[0.6] * 3, [0.2] * 3, [0.4] * 3, [0.2] * 3]), w=8, h=8)
    r = zbm.render_zbm(tris, interleave=2)
    px = r.pixels
    z2 = round(0.2 * 0xFFFFFF)
    assert (px.tag[2, 2] == [1, 3]).all() and (px.z[2, 2] == [z2, z2]).all()   # tie: first stays in front
    r = zbm.render_zbm(tri([quad] * 3, z=np.array([[0.6] * 3, [0.2] * 3, [0.4] * 3]), w=8, h=8))
    assert (r.pixels.tag == [1, 2]).all()        # 0.2 then 0.4; 0.6 dropped
    assert (r.pixels.z[..., 1] == round(0.4 * 0xFFFFFF)).all()


def test_chip_loop_equals_whole_unit_for_every_interleave():
    tris = ref.random_triangles(40, 24, 25, mean_area=50, seed=11)
    base = zbm.render_zbm(tris, interleave=1)
    for i in (2, 4, 16):
        r = zbm.render_zbm(tris, interleave=i, per_chip=True)
        assert (r.pixels.words() == base.pixels.words()).all() and (r.pixels.tag == base.pixels.tag).all()
    segs = zbm.segment_generator(zbm.edge_pairs(tris), 24, width=40)
    y = int(segs.y[segs.y.size // 2])
    px, n, _, inc4, keep = zbm.initial_processor(segs.x, segs.len, segs.val, segs.inc, 3, 4)
    assert ((px[keep] % 4) == 3).all() and (n[~keep] == 0).all()
    assert (inc4 == fmt.wrap(segs.inc * 4)).all()
    b, st = zbm.chip_scanline(segs, y, 3, 4, 40)
    assert b.z.shape == (10, 2) and st["packets"] >= 1
    with pytest.raises(RasterhwError, match="interleave"):
        zbm.chip_scanline(segs, y, 0, 3, 40)
    with pytest.raises(RasterhwError, match="chip"):
        zbm.chip_scanline(segs, y, 4, 4, 40)


def test_merge_nearest_two_ties_and_associativity():
    rng = np.random.default_rng(5)
    def rand(n, src):
        z = np.sort(rng.integers(0, 6, (n, 2)), axis=1)
        z[rng.random(n) < 0.2, 1] = fmt.Z_EMPTY
        return _ds(z, src * 10 + np.array([0, 1]))
    n = 400
    a, b, c = rand(n, 0), rand(n, 1), rand(n, 2)
    m = zbm.merge(a, b)
    for k in range(n):
        cand = sorted([(a.z[k, 0], 0, a.tag[k, 0]), (a.z[k, 1], 1, a.tag[k, 1]),
                       (b.z[k, 0], 2, b.tag[k, 0]), (b.z[k, 1], 3, b.tag[k, 1])])
        assert [t for _, _, t in cand[:2]] == list(m.tag[k])
    left, right = zbm.merge(zbm.merge(a, b), c), zbm.merge(a, zbm.merge(b, c))
    assert (left.tag == right.tag).all() and (left.z == right.z).all()
    # units: round-robin dealing + merge chain gives the same image as one unit (no Z ties)
    tris = ref.random_triangles(48, 32, 40, mean_area=60, seed=9)
    one = zbm.render_zbm(tris, units=1)
    three = zbm.render_zbm(tris, units=3)
    assert (three.pixels.words() == one.pixels.words()).all()
    assert len(three.unit_pixels) == 3


def test_composite_formula():
    d = zbm.DoubleZ.empty((3,))
    d.z[:] = [[5, 9], [5, fmt.Z_EMPTY], [fmt.Z_EMPTY, fmt.Z_EMPTY]]
    d.a[:] = [[128, 255], [255, 0], [0, 0]]
    d.c[:, 0, :3] = [200, 100, 0]
    d.c[:, 1, :3] = [0, 50, 255]
    out = zbm.composite(d, background=(10, 20, 30)).astype(int)
    back = np.array([0, 50, 255])
    assert (out[0] == (128 * np.array([200, 100, 0]) + 127 * back + 127) // 255).all()
    assert (out[1] == [200, 100, 0]).all() and (out[2] == [10, 20, 30]).all()
    with pytest.raises(RasterhwError, match="background"):
        zbm.composite(d, background=(300, 0, 0))


def test_mapping_after_merge_counts_only_visible():
    rng = np.random.default_rng(2)
    tris = ref.random_triangles(48, 32, 30, mean_area=80, seed=2)
    tris.uv = rng.random((30, 3, 2))
    r = zbm.render_zbm(tris, mode=fmt.MODE_MAPPING)
    visible = int((r.pixels.z[..., 0] != fmt.Z_EMPTY).sum())   # opaque: only s0 is looked up
    assert r.stats["texture_lookups"] == visible
    assert r.stats["lookups_if_mapped_before_merge"] == r.stats["fragments"] > visible
    tex, il = zbm.default_maps()
    y, x = np.argwhere(r.pixels.z[..., 0] != fmt.Z_EMPTY)[0]
    um, vm, ui, vi = r.pixels.c[y, x, 0]
    assert (r.rgb8[y, x] == (tex[vm, um] * il[vi, ui] + 127) // 255).all()
    with pytest.raises(RasterhwError, match="uv"):
        zbm.render_zbm(ref.random_triangles(8, 8, 2, seed=1), mode=fmt.MODE_MAPPING)


# ----------------------------------------------------------------- full frame vs reference and float
@pytest.mark.parametrize("seed", [1, 2])
def test_frame_matches_reference_and_float_twin(seed):
    tris = ref.random_triangles(64, 32, 30, mean_area=60, seed=seed)
    r = zbm.render_zbm(tris, interleave=8)
    f = ref.rasterise(tris)
    tag = r.pixels.tag[..., 0]
    assert ((tag >= 0) == (f.tri_id >= 0)).all()                 # same coverage
    assert (tag == f.tri_id).all()                                # same nearest triangle (no Z ties)
    assert np.abs(r.rgb8.astype(int) - f.to_rgb8().astype(int)).max() <= 1
    fl = zbm.render_zbm_float(tris)
    assert (fl["tag"] == r.pixels.tag).all()
    # stated tolerance: Z within 1 + |dz/dx| * 2**-16 LSB (left-end offset truncated to Q.16)
    eps = zbm.edge_pairs(tris)
    gx = np.zeros(tris.n_triangles)
    np.maximum.at(gx, eps.tag, np.abs(eps.ddx[:, 0]) / 2**24)
    m = tag >= 0
    zf = np.clip(np.floor(fl["z"][..., 0] * zbm.Z_SCALE + 0.5), 0, fmt.Z_MAX_SAMPLE)
    assert (np.abs(r.pixels.z[..., 0] - zf)[m] <= 1 + gx[tag[m]] * 2**-16).all()
    rgb = np.clip(np.floor(fl["rgb"] * 255 + 0.5), 0, 255)
    assert np.abs(r.rgb8 - rgb).max() <= 1


def test_translucent_composite_close_to_float():
    tris = ref.random_triangles(48, 32, 30, mean_area=120, seed=3)
    alpha = np.random.default_rng(3).uniform(0.3, 1.0, 30)
    r = zbm.render_zbm(tris, alpha=alpha, units=2)
    fl = zbm.render_zbm_float(tris, alpha=alpha)
    assert (r.pixels.tag == fl["tag"]).all()
    assert np.abs(r.rgb8 - fl["rgb"] * 255).max() <= 2     # two roundings + 8-bit alpha


def test_render_bad_input():
    tris = ref.random_triangles(16, 16, 3, seed=1)
    with pytest.raises(RasterhwError, match="interleave"):
        zbm.render_zbm(tris, interleave=3)
    with pytest.raises(RasterhwError, match="units"):
        zbm.render_zbm(tris, units=0)
    with pytest.raises(RasterhwError, match="alpha"):
        zbm.render_zbm(tris, alpha=np.full(3, 2.0))
    big = ref.random_triangles(16, 16, 3, seed=1)
    big.width = 1024
    with pytest.raises(RasterhwError, match="width"):
        zbm.render_zbm(big)
    far = tri([[0, 0], [3000, 0], [0, 5]])
    with pytest.raises(RasterhwError, match="outside"):
        zbm.edge_pairs(far)
    nan = tri([[0, 0], [np.nan, 0], [0, 5]])
    with pytest.raises(RasterhwError, match="NaN"):
        zbm.edge_pairs(nan)


# ----------------------------------------------------------------- cycles
def test_paper_table1_formula():
    rows = cyc.paper_table1()
    assert [r["cycles_per_edge_pair"] for r in rows] == [74, 64, 59, 54, 54]
    assert [r["len_chip"] for r in rows] == [cyc.PAPER_LEN_CHIP[i] for i in fmt.INTERLEAVES]
    for r in rows:   # the paper rounds its intermediate (231.5 K edges) before halving
        assert abs(r["kpolys_formula"] - r["kpolys_paper"]) <= 0.1
    assert abs(64 * cyc.formula_polygons_per_s(8) / 1e6 - 7.4) < 0.05
    with pytest.raises(RasterhwError, match="interleave"):
        cyc.len_chip(5, 3)


def test_event_model_rules():
    for i, expect in zip(fmt.INTERLEAVES, [74, 64, 59, 54, 54], strict=True):
        e = cyc.event_cycles(cyc.paper_workload(60), 512, interleave=i)
        assert e["loop_cycles_per_edge_pair"] == expect      # R1 + R2 on the paper's workload
    # a 3-line x 20-pixel pair at interleave 4: 9 + 3 * (5 + 8)
    one = cyc.paper_workload(1)
    one.len[:] = 20 << fmt.X_FRAC
    one.h[:] = 3
    e = cyc.event_cycles(one, 64, width=64, interleave=4)
    assert e["loop_cycles"] == 9 + 3 * (5 + 8)
    assert e["frame_cycles"] == 9 + (5 + 8) + 2 * max(5 + 8, 16) + 16   # R4 overlap with merge
    # empty segments cost 1 cycle (R2): a pair entirely left of the frame
    off = cyc.paper_workload(1)
    off.x[:] = -50 << fmt.X_FRAC
    e = cyc.event_cycles(off, 64, width=64, interleave=8)
    assert e["loop_cycles"] == 9 + 5 and e["segments"] == 0
    # over capacity: an error, never lost segments
    tris = ref.random_triangles(32, 32, 12, mean_area=60, seed=7)
    with pytest.raises(RasterhwError, match="simultaneously active"):
        cyc.event_cycles(zbm.edge_pairs(tris), 32, width=32, interleave=8, capacity=2)


def test_hdl_cycle_model_steady_state():
    """hdl_cycles on the paper's workload: per extra edge pair 4 (len_chip + 8) + max(len_chip + 8, 18)
    (docs/zbm.md, HDL); HDL equality is tested in tests/zbm/test_zbm_unit_pysim.py."""
    for i in fmt.INTERLEAVES:
        w = max(4 * i, 8)
        a = cyc.hdl_cycles(cyc.paper_workload(4, width=w), 20, width=w, interleave=i)["cycles"]
        b = cyc.hdl_cycles(cyc.paper_workload(5, width=w), 25, width=w, interleave=i)["cycles"]
        lc = -(-5 // i)
        assert b - a == 4 * (lc + 8) + max(lc + 8, 18)
    with pytest.raises(RasterhwError, match="line 2 needs 3"):
        cyc.hdl_cycles(cyc.paper_workload(3, lines_apart=1, width=16), 8, width=16, interleave=2, capacity=2)


def test_arrival_layers_equal_one_by_one_insertion():
    """Layered double-Z insertion (the golden fast paths) equals inserting fragments one at a time."""
    from rasterhw.golden_model.zbm.chip import _insert
    from rasterhw.golden_model.zbm.doublez import DoubleZ, arrival_layers

    rng = np.random.default_rng(8)
    n, npx = 4000, 300
    pos = rng.integers(0, npx, n)
    z = rng.integers(0, 50, n)          # many ties: the earlier fragment must win them
    a = rng.integers(0, 256, n)
    c = rng.integers(0, 256, (n, 4))
    tag = np.arange(n)
    serial, layered = DoubleZ.empty((npx,)), DoubleZ.empty((npx,))
    w1 = sum(_insert(serial, pos[i:i + 1], z[i:i + 1], a[i:i + 1], c[i:i + 1], tag[i:i + 1]) for i in range(n))
    layers = arrival_layers(pos)
    assert sorted(np.concatenate(layers).tolist()) == list(range(n))
    assert all(np.unique(pos[ly]).size == ly.size for ly in layers)
    w2 = sum(_insert(layered, pos[ly], z[ly], a[ly], c[ly], tag[ly]) for ly in layers)
    assert w1 == w2
    for f in ("z", "a", "c", "tag"):
        assert np.array_equal(getattr(serial, f), getattr(layered, f))
