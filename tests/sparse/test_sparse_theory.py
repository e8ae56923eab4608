"""Formulas (1)-(12) of seed 002 against the paper's numbers and independent closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.sparse import theory as th


def test_shape_coefficient_of_5_to_1_rectangle():
    assert th.L_RECT_5_1 == pytest.approx(1.514, abs=5e-4)
    assert th.shape_coefficient(2 * math.pi, math.pi) == pytest.approx(1.0)  # unit disc


@pytest.mark.parametrize("k,paper", list(enumerate(th.PAPER_S_K, start=1)))
def test_s_k_reproduces_the_paper(k, paper):
    s = th.s_k(k)
    if paper == 0:
        assert abs(s) <= 0.05
    else:
        assert s == pytest.approx(paper, rel=0.01)
    # bisection on formula (1) at i = n agrees with the quadratic (4)
    assert s == pytest.approx(th.s_k_quadratic(k), abs=1e-9)


def test_formula_1_at_pixel_level_is_formula_3():
    S = np.array([0.0, 1.0, 10.0, 333.0])
    for p, q, al, be in ((4, 2, 2.0, 3.0), (8, 8, 2.0, 2.0), (2, 16, 1.5, 2.5)):
        n = 6
        w = th.windows(S, n, p, q, alpha=al, beta=be, L=1.3)[n]
        w3 = (S + 1.3 * np.sqrt((al ** 2 * q / p + be ** 2 * p / q) * math.pi * S) + al * be) / (p * q)
        assert np.allclose(w, w3, rtol=1e-12)


def test_monoprocessor_limit():
    # p = q = 1: alpha_i = 1 + 2**(i-n)(alpha - 1), the single-processor count of [3]
    S, n, al, L = 50.0, 8, 2.0, 1.2
    w = th.windows(S, n, 1, alpha=al, L=L)
    for i in range(1, n + 1):
        a = 1 + 2.0 ** (i - n) * (al - 1)
        assert w[i] == pytest.approx(4.0 ** (i - n) * S + 2.0 ** (i - n) * L * math.sqrt(2 * a * a * math.pi * S) + a * a)


def test_alpha_i_from_2_to_1():
    a = th.alpha_i(np.arange(1, 7), 6, 16, 2.0)
    assert a[-1] == pytest.approx(2 / 16)
    assert np.all(np.diff(a) < 0) and a[0] < 1
    assert np.allclose(th.alpha_i(np.arange(1, 10), 9, 2, 2.0), 1.0)  # k = 1: alpha_i = 1


def test_k1_one_window_per_level_at_zero_area():
    w = th.windows(0.0, 9, 2)
    assert np.allclose(w, 1.0)


def test_load_identity_and_bounds():
    S = np.logspace(-1, 3, 50)
    for k in (1, 2, 3, 4):
        n, p = 10 - k, 1 << k
        w = th.windows(S, n, p)
        Rp = th.load_pipeline(w)
        # (10): R_p = P_p / (n P_s)
        assert np.allclose(Rp, th.perf_pipeline(w) / (n * th.perf_stack(w)))
        assert np.all((Rp > 0) & (Rp <= 1))
        # t_1 = tau (4 + w_1) >= 4 tau, so p_p <= 5/4; at small S it is the paper's P_max = 0.2/tau
        assert np.all(th.perf_pipeline(w) <= 1.25)
        if k > 1:  # k = 1 has no small-area regime (alpha_i = 1)
            assert th.perf_pipeline(th.windows(0.01, n, p)) == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize("k", [2, 3, 4])
def test_load_peak_near_s_k(k):
    S = np.logspace(-2, 3.5, 3000)
    Rp = th.load_pipeline(th.windows(S, 10 - k, 1 << k))
    i = int(Rp.argmax())
    assert Rp[i] >= 0.95
    assert th.s_k(k) / 4 <= S[i] <= th.s_k(k) * 2


def test_large_area_performance_grows_like_matrix():
    pp = [th.summary(1000.0, 10, k)["p_p"] for k in (1, 2, 3, 4)]
    ratios = np.diff(np.log(pp)) / math.log(4)
    assert np.all(ratios > 0.7)  # "практически пропорционально 4^k"
    assert th.summary(1000.0, 10, 4)["limiting_level"] == 6  # the pixel level
    assert th.summary(0.01, 10, 4)["limiting_level"] == 1  # the first level


def test_bad_parameters():
    with pytest.raises(RasterhwError):
        th.windows(1.0, 0, 4)
    with pytest.raises(RasterhwError):
        th.windows(1.0, 5, 3)
    with pytest.raises(RasterhwError):
        th.windows(-1.0, 5, 4)
    with pytest.raises(RasterhwError):
        th.windows(1.0, 5, 4, alpha=0.0)
