"""Golden model of the SNU pixel bus: frame buffer semantics and the cycle model."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.snu import pixelbus as g
from rasterhw.golden_model.snu.pixelstream import PixelStream


def ps(w, h, addr, rgb, z, pipe):
    return PixelStream(w, h, np.array(addr), np.array(rgb), np.array(z), np.array(pipe))


def naive_cycles(stream, gaps=None, mem_cycle=5, n_banks=5):
    """Clock-by-clock reference for the cycle model (slow, small streams only)."""
    n = len(stream)
    gaps = np.zeros(n, dtype=int) if gaps is None else gaps
    q = [list(np.flatnonzero(stream.pipe == p)) for p in range(2)]
    valid_from = [gaps[x[0]] if x else 0 for x in q]
    busy_until = [0] * n_banks
    acc = np.full(n, -1)
    t = 0
    while any(q):
        p = t % 2
        if q[p] and t >= valid_from[p]:
            k = q[p][0]
            b = stream.addr[k] % n_banks
            if t >= busy_until[b]:
                acc[k] = t
                busy_until[b] = t + mem_cycle
                q[p].pop(0)
                if q[p]:
                    valid_from[p] = t + 1 + gaps[q[p][0]]
        t += 1
    return acc


def test_single_pipe_scanline_runs_every_other_slot():
    n = 20
    s = ps(40, 4, np.arange(n), np.arange(n), np.full(n, 7), np.zeros(n))
    acc = g.pixelbus_accept_cycles(s)
    assert acc.tolist() == list(range(0, 2 * n, 2))  # banks rotate, only even slots
    assert g.pixelbus_cycles(s) == 2 * (n - 1) + 5


def test_vertical_line_hits_one_bank_and_loses_a_slot():
    # width 40 is a multiple of 5: a column stays in one bank; 5-clock memory cycle,
    # even slots only -> one write every 6 clocks
    n = 6
    s = ps(40, 8, np.arange(n) * 40, np.arange(n), np.full(n, 9), np.zeros(n))
    assert g.pixelbus_accept_cycles(s).tolist() == [0, 6, 12, 18, 24, 30]


def test_two_pipes_full_rate_on_different_banks():
    n = 10
    addr = np.empty(2 * n, dtype=int)
    addr[0::2] = np.arange(n) * 2  # pipe 0: even pixels
    addr[1::2] = 100 + np.arange(n) * 2 + 1  # pipe 1 elsewhere
    pipe = np.tile([0, 1], n)
    s = ps(40, 8, addr, np.zeros(2 * n), np.ones(2 * n), pipe)
    acc = g.pixelbus_accept_cycles(s)
    # pipe 0 on banks 0,2,4,1,3..., pipe 1 on banks 1,3,0,2,...: no conflicts -> 1/clock
    assert sorted(acc.tolist()) == list(range(2 * n))


def test_cycle_model_matches_clock_by_clock_reference():
    rng = np.random.default_rng(3)
    for trial in range(20):
        n = int(rng.integers(1, 80))
        w, h = 10, 6
        addr = rng.integers(0, w * h, n)
        if trial % 3 == 0:
            addr = (addr % 3) * 5  # hammer one bank
        s = ps(w, h, addr, rng.integers(0, 1 << 24, n), rng.integers(0, 4, n), rng.integers(0, 2, n))
        gaps = rng.integers(0, 4, n) * (rng.random(n) < 0.4)
        assert g.pixelbus_accept_cycles(s, gaps=gaps).tolist() == naive_cycles(s, gaps).tolist()


def test_order_kept_within_each_pipe():
    s = g.pattern_stream("random", 40, 16, 300, seed=5)
    acc = g.pixelbus_accept_cycles(s)
    for p in range(2):
        a = acc[s.pipe == p]
        assert np.all(np.diff(a) > 0)
        assert np.all(a % 2 == p)  # fixed slots
    # one bank takes at most one write per memory cycle
    for b in range(5):
        a = np.sort(acc[s.addr % 5 == b])
        assert np.all(np.diff(a) >= 5)


def test_frame_strict_greater_and_first_accepted_wins_ties():
    # pixel 3: pipe 0 writes z=5 (red) and pipe 1 z=5 (green) -> the earlier accept wins
    s = ps(5, 2, [3, 3, 7, 7, 8], [0xFF0000, 0x00FF00, 0x111111, 0x222222, 0x333333], [5, 5, 2, 9, 0], [0, 1, 0, 0, 1])
    acc = g.pixelbus_accept_cycles(s)
    rgb, z = g.pixelbus_frame(s, accept=acc)
    first = 0 if acc[0] < acc[1] else 1
    assert rgb.ravel()[3] == [0xFF0000, 0x00FF00][first] and z.ravel()[3] == 5
    assert rgb.ravel()[7] == 0x222222 and z.ravel()[7] == 9  # nearer later write lands
    assert rgb.ravel()[8] == 0 and z.ravel()[8] == 0  # z = 0 (far) never beats a clear
    # reversing the acceptance order flips the tie only
    rgb2, _ = g.pixelbus_frame(s, accept=acc[::-1].copy())
    assert rgb2.ravel()[3] == [0xFF0000, 0x00FF00][1 - first]


def test_frame_matches_sequential_reference():
    s = g.pattern_stream("random", 20, 10, 600, seed=2)
    s.z[:] = s.z % 7  # many ties and far writes
    acc = g.pixelbus_accept_cycles(s)
    rgb, z = g.pixelbus_frame(s, accept=acc)
    ref_rgb = np.zeros(200, dtype=np.int64)
    ref_z = np.zeros(200, dtype=np.int64)
    for k in np.argsort(acc, kind="stable"):
        if s.z[k] > ref_z[s.addr[k]]:
            ref_z[s.addr[k]] = s.z[k]
            ref_rgb[s.addr[k]] = s.rgb[k]
    assert np.array_equal(rgb.ravel(), ref_rgb) and np.array_equal(z.ravel(), ref_z)


def test_rates_of_patterns():
    w, h = 1280, 1024
    sl = g.pattern_stream("scanline", w, h, 20000)
    vt = g.pattern_stream("vertical", w, h, 20000)
    rnd = g.pattern_stream("random", w, h, 20000)
    r_sl = g.pixels_per_second(len(sl), g.pixelbus_cycles(sl))
    r_vt = g.pixels_per_second(len(vt), g.pixelbus_cycles(vt))
    r_rnd = g.pixels_per_second(len(rnd), g.pixelbus_cycles(rnd))
    assert 12.0e6 < r_sl <= 12.5e6  # both pipes, banks rotate: close to one write per slot
    assert r_vt == pytest.approx(2 * 12.5e6 / 6, rel=1e-3)  # each pipe: one bank, every 6th clock
    assert r_vt < r_rnd < r_sl


def test_bad_input_raises():
    s = ps(4, 4, [16], [0], [1], [0])
    with pytest.raises(RasterhwError, match="address 16"):
        g.pixelbus_cycles(s)
    s = ps(4, 4, [1], [0], [1 << 24], [0])
    with pytest.raises(RasterhwError, match="Z value"):
        g.pixelbus_frame(s)
    ok = ps(4, 4, [1], [0], [1], [0])
    with pytest.raises(RasterhwError, match="mem_cycle"):
        g.pixelbus_cycles(ok, mem_cycle=1)
    with pytest.raises(RasterhwError, match="gaps"):
        g.pixelbus_accept_cycles(ok, gaps=np.array([-1]))
    with pytest.raises(RasterhwError, match="pattern"):
        g.pattern_stream("diagonal", 4, 4, 4)
    assert g.pixelbus_cycles(ps(4, 4, [], [], [], [])) == 0


def test_rgb_image_is_the_shifted_bytes():
    """``rgb_image`` (bytes of the little-endian word) equals the shifts and masks it replaced."""
    rgb = np.random.default_rng(4).integers(0, 1 << 24, (17, 23))
    rgb[0, :4] = [0, 0xFFFFFF, 0x800001, 0x123456]
    want = np.stack([(rgb >> 16) & 0xFF, (rgb >> 8) & 0xFF, rgb & 0xFF], axis=-1).astype(np.uint8)
    got = g.rgb_image(rgb)
    assert got.dtype == np.uint8 and got.flags.c_contiguous and np.array_equal(got, want)
    assert list(g.rgb_image(np.array([[0x123456]]))[0, 0]) == [0x12, 0x34, 0x56]
