"""A.J. work per blended pixel, counted by running the alpha and blend steps (not typed in).

The PXP's per-pixel A.J. work is a short routine: where the edge crosses the line's centre
relative to the pixel centre (``delta``), the mixing ratio alpha by method (a), (b) or (c), a
clamp to [0, 1], and eq. (5) ``C = alpha C_L + (1 - alpha) C_R`` on R, G, B and I. Each routine
below is written once and run on :class:`V` values, which do the arithmetic on NumPy arrays (one
element per A.J. pixel) and add 1 to each element's count for every operation that element
executes; :func:`branch` runs each side of a data-dependent choice only for the elements that
take it. So the count of a pixel is the number of 16-bit operations its own path executed:
an add, subtract, multiply, shift, absolute value or compare is 1; a clamp is 2 compares.

Per-edge values come from the SLP and are not counted here: dx/dy and dy/dx (the ASB's slopes)
and, for (b), ``1 / sqrt(1 + s^2)`` (the SLP's per-edge set-up, priced in :mod:`slp`).

The alpha each routine computes is the one the image uses (:func:`pxp.anti_jagging`):
identical in the bit model for (c), and for (a), (b) and the float model within float rounding
(tested); the routines are the counted statement of that work, the image keeps its code.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Tally", "V", "branch", "clamp", "aj_pixel_ops"]


class Tally:
    """Operation counts, one per element, and the mask of elements on the current path."""

    def __init__(self, n: int):
        self.ops = np.zeros(n, np.int64)
        self.mask = np.ones(n, bool)

    def tick(self, k: int = 1) -> None:
        self.ops += self.mask * k


class V:
    """A counted value: NumPy arithmetic that ticks its :class:`Tally` once per operation."""

    __slots__ = ("v", "t")

    def __init__(self, v, t: Tally):
        self.v = np.asarray(v)
        self.t = t

    @staticmethod
    def _raw(o):
        return o.v if isinstance(o, V) else o

    def _op(self, f, o=None):
        self.t.tick()
        return V(f(self.v, self._raw(o)), self.t)

    def __add__(self, o):
        return self._op(np.add, o)

    def __radd__(self, o):
        return self._op(np.add, o)

    def __sub__(self, o):
        return self._op(np.subtract, o)

    def __rsub__(self, o):
        return self._op(lambda a, b: b - a, o)

    def __mul__(self, o):
        return self._op(np.multiply, o)

    def __rmul__(self, o):
        return self._op(np.multiply, o)

    def __truediv__(self, o):
        return self._op(np.divide, o)

    def __rshift__(self, o):
        return self._op(np.right_shift, o)

    def __lshift__(self, o):
        return self._op(np.left_shift, o)

    def __abs__(self):
        return self._op(lambda a, _: np.abs(a))

    def __le__(self, o):
        self.t.tick()
        return self.v <= self._raw(o)

    def __lt__(self, o):
        self.t.tick()
        return self.v < self._raw(o)

    def __ge__(self, o):
        self.t.tick()
        return self.v >= self._raw(o)

    def __gt__(self, o):
        self.t.tick()
        return self.v > self._raw(o)


def clamp(x: V, lo, hi) -> V:
    """Two compares."""
    x.t.tick(2)
    return V(np.clip(x.v, V._raw(lo), V._raw(hi)), x.t)


def branch(t: Tally, cond: np.ndarray, if_true, if_false) -> V:
    """Run ``if_true()`` for the elements where ``cond`` holds, ``if_false()`` for the rest."""
    saved = t.mask
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t.mask = saved & cond
        a = if_true()
        t.mask = saved & ~cond
        b = if_false()
    t.mask = saved
    return V(np.where(cond, V._raw(a), V._raw(b)), t)


def _g(u: V, t: Tally) -> V:
    """Antiderivative of clamp(u, 0, 1): two compares, then 0, u - 1/2 or u^2 / 2."""
    return branch(t, u <= 0, lambda: V(np.zeros_like(u.v, dtype=np.float64), t),
                  lambda: branch(t, u >= 1, lambda: u - 0.5, lambda: 0.5 * u * u))


def aj_pixel_ops(method: str, bit: bool, xe, xx, s, q, perp=None, fl=None, fr=None,
                 *, x_frac: int = 6, slope_frac: int = 8, alpha_bits: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run the A.J. routine for every blended pixel; returns (alpha, blended fields, ops per pixel).

    ``xe``: the edge's x at the line's centre (float px or Q10.6); ``xx``: the boundary (the
    blended pixel is ``xx - 1`` or ``xx``); ``s``: dx/dy; ``q``: dy/dx (float or sQ7.8);
    ``perp``: 1/sqrt(1 + s^2) per edge (float; method (b)); ``fl``, ``fr``: (n, 4) fields.
    """
    n = int(np.size(xe))
    t = Tally(n)
    xe, s, q = V(xe, t), V(s, t), V(q, t)
    xx = np.asarray(xx)
    if bit:
        one = 1 << alpha_bits
        px = clamp(xe >> x_frac, xx - 1, xx)                       # the pixel the edge crosses
        delta = xe - ((px << x_frac) + (1 << (x_frac - 1)))       # Q.6 from its centre
        if method == "c":
            al = branch(t, abs(s) <= (1 << slope_frac),
                        lambda: (one >> 1) + (delta << (alpha_bits - x_frac)),
                        lambda: (one >> 1) + ((delta * abs(q)) >> (x_frac + slope_frac - alpha_bits)))
        else:
            d = V(delta.v / (1 << x_frac), t)                          # reinterpretation, not an op
            a = _alpha_float(method, d, V(s.v / (1 << slope_frac), t), perp, t)
            al = V(np.rint(a.v * one).astype(np.int64), t)
            t.tick()                                                   # scale to Q0.8
        al = clamp(al, 0, one)
        blended = None
        if fl is not None:
            rest = one - al
            blended = np.stack([((al * fl[:, k] + rest * fr[:, k]) + (one >> 1) >> alpha_bits).v
                                for k in range(fl.shape[1])], axis=1)
        return al.v, blended, t.ops
    px = clamp(V(np.floor(xe.v), t), xx - 1, xx)
    t.tick()                                                           # floor
    delta = xe - (px + 0.5)
    al = clamp(_alpha_float(method, delta, s, perp, t), 0.0, 1.0)
    blended = None
    if fl is not None:
        rest = 1.0 - al
        blended = np.stack([(al * fl[:, k] + rest * fr[:, k]).v for k in range(fl.shape[1])], axis=1)
    return al.v, blended, t.ops


def _alpha_float(method: str, delta: V, s: V, perp, t: Tally) -> V:
    if method == "c":
        return branch(t, abs(s) <= 1.0, lambda: delta + 0.5, lambda: delta / abs(s) + 0.5)
    if method == "b":
        return delta * V(perp, t) + 0.5
    # (a): area left of the edge, (g(a + s/2) - g(a - s/2)) / s with a = delta + 1/2
    a = delta + 0.5
    small = abs(s) < 1e-12
    return branch(t, small, lambda: a, lambda: (_g(a + s * 0.5, t) - _g(a - s * 0.5, t)) / s)
