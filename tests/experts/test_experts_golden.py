"""EXPERTS golden model: float against the reference rasteriser, bit-accurate against float."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts import alpha, formats, slp
from rasterhw.golden_model.experts.model import (
    equal_bounds,
    pxp_range_ops,
    render_frame,
    slp_band_ops,
    slp_line_costs,
)
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.screen import ScreenTriangles, snap


@cache
def _tris(name: str) -> ScreenTriangles:
    return run_geometry(build_scene(name), 512, 512)


@cache
def _ref(name: str):
    return rasterise(_tris(name))


@cache
def _frame(name: str, model: str, aj: str = "none"):
    return render_frame(_tris(name), model=model, aj=aj)


FLOAT_SCENES = ["experts-1000", "experts-2000", "c300", "sp5", "zbm-5x5", "experts-tilt-1000",
                "experts-tilt-2000", "experts-uneven", "experts-solids"]


@pytest.mark.parametrize("name", FLOAT_SCENES)
def test_float_equals_reference_coverage_and_visible_triangle(name):
    ref, f = _ref(name), _frame(name, "float")
    assert np.array_equal(f.tri_id >= 0, ref.tri_id >= 0)
    assert np.array_equal(f.tri_id, ref.tri_id)
    assert f.fragments == ref.fragments
    # one hue per face and white light: hue x intensity is the reference's Gouraud colour
    if name.startswith("experts"):
        assert np.abs(f.rgb8.astype(int) - ref.to_rgb8().astype(int)).max() <= 1


#: stated tolerance of the bit model against the float one (docs/experts.md, measured there)
BIT_COVER_FRAC = 5e-4      # pixels whose covered/empty state differs, of the frame
BIT_VISIBLE_FRAC = 5e-3    # covered pixels whose visible triangle differs
BIT_I_LEVELS = 1           # intensity levels, where the visible triangle agrees


@pytest.mark.parametrize("name", ["experts-1000", "experts-tilt-1000", "experts-tilt-2000", "c300"])
def test_bit_model_within_stated_tolerance_of_float(name):
    fl, bt = _frame(name, "float"), _frame(name, "bit")
    npix = fl.width * fl.height
    assert np.count_nonzero(fl.covered != bt.covered) <= BIT_COVER_FRAC * npix
    both = fl.covered & bt.covered
    same = both & (fl.tri_id == bt.tri_id)
    assert np.count_nonzero(both & ~same) <= BIT_VISIBLE_FRAC * np.count_nonzero(both)
    imax = bt.setup.fmt.i_max
    i_f = fl.fields[same.ravel(), 3] * imax
    i_b = bt.fields[same.ravel(), 3]
    assert np.abs(i_b - i_f).max() <= BIT_I_LEVELS + 0.5
    assert np.array_equal(bt.fields[same.ravel(), :3], np.rint(fl.fields[same.ravel(), :3] * 7))


def test_eq3_gradient_against_plane_solve():
    """di/dx from eq. (3) (with the printed (y_a - y_c) corrected) equals the plane's gradient."""
    tris = _tris("experts-tilt-1000")
    st = slp.set_up(tris, bit=False)
    X, Y = snap(tris.xy[st.keep, :, 0]) / 256, snap(tris.xy[st.keep, :, 1]) / 256
    A = np.stack([X, Y, np.ones_like(X)], axis=-1)
    g = np.linalg.solve(A, tris.z[st.keep][..., None])[:, 0, 0]
    assert np.allclose(st.dzdx, g, rtol=1e-7, atol=1e-12)


def test_partition_does_not_change_the_image_and_counts_add_up():
    f = _frame("experts-tilt-1000", "bit", "c")
    one = pxp_range_ops(f, equal_bounds(512, 1))
    eight = pxp_range_ops(f, equal_bounds(512, 8))
    assert one.shape == (512, 1) and eight.shape == (512, 8)
    # every range start adds the work for the segments it cuts, never removes work
    assert (eight.sum(axis=1) >= one[:, 0]).all()
    extra = eight.sum() - one.sum()
    cuts = sum(int(f.costs["_cross"][:, a].sum()) for a in equal_bounds(512, 8)[1:-1])
    assert extra >= 6 * cuts
    # bands: the lines are counted once whichever the split
    b1 = slp_band_ops(f, equal_bounds(512, 1), 1)[0]
    b4 = slp_band_ops(f, equal_bounds(512, 4), 1)
    assert sum(d["asl_update"] for d in b4) <= b1["asl_update"]
    assert sum(d["pl_read"] for d in b4) == 4 * b1["pl_read"]


def test_depth_search_counts_by_brute_force():
    """2k - 1 per pixel covered by k segments, k from an independent per-pixel coverage count."""
    name = "experts-1000"
    f = _frame(name, "float")
    tris = _tris(name)
    # independent k: rasterise each triangle alone with the reference and count
    k = np.zeros((512, 512), np.int64)
    sub = slice(0, 40)
    for t in range(sub.stop):
        one = ScreenTriangles(512, 512, tris.xy[t:t + 1], tris.z[t:t + 1], tris.zq[t:t + 1],
                              tris.colour[t:t + 1], tris.poly_id[t:t + 1])
        k += rasterise(one).tri_id >= 0
    g = render_frame(ScreenTriangles(512, 512, tris.xy[sub], tris.z[sub], tris.zq[sub], tris.colour[sub],
                                     tris.poly_id[sub]), model="float")
    assert np.array_equal(g.costs["depth_search"], np.where(k > 0, 2 * k - 1, 0))
    assert f.costs["depth_search"].sum() > 0


def test_l_sort_counts_against_a_bubble_sort():
    tris = _tris("experts-tilt-1000")
    st = slp.set_up(tris, bit=False)
    rec = slp.asl_update(st, 512)
    lines = slp.l_sort_x_merge(rec, 512)
    key = rec.xl
    prev = None
    for y in range(100, 140):
        sel = np.flatnonzero(rec.row == y)
        cur = {int(rec.tri[r]): (float(key[r]), int(rec.tri[r])) for r in sel}
        if prev is not None:
            lst = [t for t in prev if t in cur]          # old order, survivors
            swaps = passes = 0
            while True:
                passes += 1
                done = True
                for j in range(len(lst) - 1):
                    if cur[lst[j]] > cur[lst[j + 1]]:
                        lst[j], lst[j + 1] = lst[j + 1], lst[j]
                        swaps += 1
                        done = False
                if done:
                    break
            leave = len([t for t in prev if t not in cur])
            ns = len(lst)
            expect = (passes * (ns - 1) + swaps if ns >= 2 else 0) + leave
            assert lines["lsort"][y] == expect
        prev = [t for _, t in sorted(cur.values())]


def test_alpha_methods_against_supersampling():
    rng = np.random.default_rng(7)
    delta = rng.uniform(-0.7, 0.7, 300)
    s = np.tan(rng.uniform(-1.5, 1.5, 300))
    u = (np.arange(64) + 0.5) / 64 - 0.5
    px, py = np.meshgrid(u, u)
    inside = px[None] < delta[:, None, None] + s[:, None, None] * py[None]
    mc = inside.mean(axis=(1, 2))
    assert np.allclose(alpha.alpha_area(delta, s), mc, atol=1.5 / 64)
    vert = np.zeros(5)
    d5 = np.linspace(-0.4, 0.4, 5)
    for m in "abc":  # a vertical edge: every method is the exact area
        assert np.allclose(alpha.ALPHA[m](d5, vert), d5 + 0.5)


def test_aj_blends_only_polygon_edges_and_counts():
    f0, fc = _frame("experts-solids", "float"), _frame("experts-solids", "float", "c")
    changed = np.any(f0.fields != fc.fields, axis=1).reshape(512, 512)
    assert fc.aj_pixels > 0 and changed.sum() <= fc.aj_pixels
    # no blended pixel lies inside a polygon: its neighbours show another polygon (or background)
    yy, xx = np.nonzero(changed)
    p = f0.poly_id
    left = p[yy, np.maximum(xx - 1, 0)] != p[yy, xx]
    right = p[yy, np.minimum(xx + 1, 511)] != p[yy, xx]
    assert np.all(left | right)
    assert "anti_jagging" in fc.costs and "anti_jagging" not in f0.costs


def test_rom_division_close_to_exact():
    rng = np.random.default_rng(3)
    num = rng.integers(-(1 << 16), 1 << 16, 2000)
    den = rng.integers(1, 1 << 15, 2000)
    q = formats.rom_div(num, den, 8)
    exact = num * 256 / den
    assert np.all(np.abs(q - exact) <= 1 + np.abs(exact) * 2.0 ** -15)
    r, s = formats.recip_rom(np.array([1, 2, 3, 1024, 32767]))
    assert np.all((r > 1 << 15) & (r < 1 << 16))


def test_slp_line_costs_sum_to_band_ops():
    f = _frame("experts-tilt-1000", "float")
    cont, start = slp_line_costs(f, 4)
    bands = equal_bounds(512, 4)
    ops = slp_band_ops(f, bands, 4)
    for s in range(4):
        y0, y1 = bands[s], bands[s + 1]
        tot = sum(v for k, v in ops[s].items() if k not in ("pl_read",)) - 2 * f.setup.n
        # start line carries every active triangle's set-up; later lines those entering
        assert start[y0] + cont[y0 + 1:y1].sum() == tot


def test_bad_input_is_a_one_line_error():
    tris = _tris("experts-1000")
    with pytest.raises(RasterhwError, match="model must be"):
        render_frame(tris, model="fixed")
    with pytest.raises(RasterhwError, match="aj must be"):
        render_frame(tris, aj="d")
    with pytest.raises(RasterhwError, match="intensity_bits"):
        formats.Formats(intensity_bits=8)
    big = ScreenTriangles(2048, 16, tris.xy[:1], tris.z[:1], tris.zq[:1], tris.colour[:1], tris.poly_id[:1])
    with pytest.raises(RasterhwError, match="Q10.6"):
        render_frame(big)
    with pytest.raises(RasterhwError, match="parts"):
        equal_bounds(512, 0)


def test_band_clip_keeps_only_the_bands_triangles():
    """The SLP's clip of the broadcast PL: a band holds exactly the triangles whose lines reach it,
    and every PL triangle is band-tested (the broadcast overhead)."""
    f = _frame("experts-tilt-1000", "float")
    st = f.setup
    for band in ((0, 1), (100, 164), (448, 512)):
        order, start, ops = slp.y_sort(st, band)
        rows = [(int(st.r0[t]), int(st.r1[t])) for t in order]
        assert all(r1 >= band[0] and r0 < band[1] for r0, r1 in rows)
        inside = int(np.count_nonzero((st.r1 >= band[0]) & (st.r0 < band[1])))
        assert order.size == inside and start[-1] == inside
        assert ops["y_sort"] == 2 * st.n + 9 * inside
    # bucket order: non-decreasing first line in the band
    order, start, _ = slp.y_sort(st, (100, 164))
    first = np.maximum(st.r0[order], 100)
    assert np.all(np.diff(first) >= 0)
