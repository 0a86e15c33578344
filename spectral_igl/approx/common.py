"""Shared pieces of the approximation methods: spectral intervals, norms, certified sup-errors."""
from __future__ import annotations

import numpy as np
import scipy.fft

from ..laplacian import Laplacian, mass_ratio

EPS = np.finfo(float).eps


# ----------------------------------------------------------------------------- norms
def bnorm(lap: Laplacian, f: np.ndarray) -> np.ndarray:
    """B-norm of each column; (n,) -> scalar array, (n, k) -> (k,)."""
    Bf = lap.B @ f
    return np.sqrt(np.maximum(np.real(np.sum(np.conj(f) * Bf, axis=0)), 0.0))


def inv_bnorm_upper(lap: Laplacian, g: np.ndarray) -> np.ndarray:
    r"""Upper bound of :math:`\|B^{-1}g\|_B = (g^* B^{-1} g)^{1/2}` without a solve.

    :math:`g^*B^{-1}g \le g^*D^{-1}g / c` with c from :func:`mass_ratio`.
    """
    d = lap.mass if g.ndim == 1 else lap.mass[:, None]
    return np.sqrt(np.real(np.sum(np.abs(g) ** 2 / d, axis=0)) / mass_ratio(lap))


# ----------------------------------------------------------------------------- certified sup
def sample_grid(a: float, b: float, n: int = 6000) -> np.ndarray:
    """Sorted sample points of [a, b]: linear, geometric from a (or from 1e-14 b) and Chebyshev."""
    lin = np.linspace(a, b, n)
    lo = a if a > 0 else b * 1e-14
    geo = np.geomspace(lo, b, n) if b > lo else np.array([b])
    ch = a + (b - a) * 0.5 * (1 - np.cos(np.linspace(0, np.pi, n)))
    x = np.unique(np.concatenate([[a, b], lin, geo, ch]))
    return x[(x >= a) & (x <= b)]


def sup_error(err, a: float, b: float, n: int = 6000, rounds: int = 8, safety: float = 2.0,
              scale: float | None = None, max_points: int = 200_000) -> float:
    r"""Upper bound of :math:`\max_{x \in [a, b]} |e(x)|` from a refined sample.

    ``err(x)`` evaluates the error on an array. The sample (linear, geometric and
    Chebyshev points, about 3n) is bisected wherever the error changes by more than 5% of
    its maximum between neighbours (variations below the rounding level
    :math:`10^3 \varepsilon \cdot` ``scale`` are ignored), until it is resolved; then
    :math:`\max_i (\max(|e_i|, |e_{i+1}|) + |e_{i+1} - e_i|)` plus the rounding level is
    multiplied by ``safety``. The error functions met here (differences of analytic
    functions and rational or polynomial approximants) are smooth on the scale of a resolved
    grid, so the factor 2 covers what lies between samples; the tests check the result
    against dense ground truth on many shapes and filters.
    """
    x = sample_grid(a, b, n)
    floor = 0.0
    for it in range(rounds + 1):
        with np.errstate(all="ignore"):
            e = np.abs(err(x))
        if not np.all(np.isfinite(e)):
            return np.inf
        if it == 0:
            floor = 1e3 * EPS * (scale if scale is not None else 1.0)
        de = np.abs(np.diff(e))
        bound = np.maximum(e[:-1], e[1:]) + de
        top = float(np.max(e))
        bad = de > max(0.05 * top, floor)
        if not np.any(bad) or it == rounds or x.size > max_points:
            break
        x0, x1 = x[:-1][bad], x[1:][bad]
        x = np.unique(np.concatenate([x, x0 + 0.25 * (x1 - x0), x0 + 0.5 * (x1 - x0), x0 + 0.75 * (x1 - x0)]))
    return safety * (float(np.max(bound)) + floor)


# ----------------------------------------------------------------------------- Chebyshev
def cheb_coeffs(fn, a: float, b: float, degree: int) -> np.ndarray:
    """Chebyshev coefficients of the interpolant of ``fn`` on [a, b] at degree+1 extreme points."""
    m = int(degree)
    k = np.arange(m + 1)
    x = np.cos(np.pi * k / m)
    s = 0.5 * (a + b) + 0.5 * (b - a) * x
    v = np.asarray(fn(s))
    if np.iscomplexobj(v):
        return cheb_coeffs(lambda s_: np.real(fn(s_)), a, b, m) + 1j * cheb_coeffs(
            lambda s_: np.imag(fn(s_)), a, b, m)
    c = scipy.fft.dct(v, type=1) / m
    c[0] *= 0.5
    c[-1] *= 0.5
    return c


def cheb_adaptive(fn, a: float, b: float, max_degree: int = 2 ** 16, floor: float = 0.0):
    """Chebyshev coefficients resolving ``fn`` on [a, b] to about machine precision.

    Doubles the degree until the last eighth of the coefficients is below
    ``max(8 eps max|c|, floor)`` or ``max_degree`` is reached. Returns ``(c, resolved)``.
    """
    m = 64
    while True:
        c = cheb_coeffs(fn, a, b, m)
        scale = np.max(np.abs(c))
        tail = np.max(np.abs(c[-(m // 8):]))
        if tail <= max(8 * EPS * scale, floor) or m >= max_degree:
            return c, tail <= max(8 * EPS * scale, floor)
        m *= 2


def tail_sums(c: np.ndarray) -> np.ndarray:
    """t[m] = sum_{k >= m} |c_k| (error of the degree m-1 truncation), length len(c)+1."""
    a = np.abs(c)[::-1]
    return np.concatenate([np.cumsum(a)[::-1], [0.0]])
