r"""Kernel columns of the heat family at many times and sources: one block solve per pole.

.. math:: K_t(:, i) = e^{-t\tilde L}B^{-1}e_i, \qquad
          \|K_t(:,i) - R_t(:,i)\|_B \le \varepsilon_t \|B^{-1}e_i\|_B

Each common pole's factor (:mod:`.fits`) is solved with every source as one block
right-hand side and dropped before the next; adding a time costs a weighted sum.
"""
from __future__ import annotations

import numpy as np

from .._validate import check_dense_size
from ..approx import LARGE_T, spectral_operator
from ..filters import heat
from ..laplacian import as_laplacian, lambda_max
from ..linalg import mass_solve
from .fits import as_times, coefficients, heat_plan, pole_factorizations

__all__ = ["heat_columns", "COLUMN_BATCH_BYTES"]


#: pole solutions held before they are added to every time's columns at once (one matrix
#: product per batch instead of one pass over the output per pole and time)
COLUMN_BATCH_BYTES = 512 * 2 ** 20


def _accumulate(O, terms, chunk: int = 4096):
    """O (T, N) += sum of outer products w (T,) x (N,) over terms [(w, x)], x any (.., ..)
    array of N entries: one (T, b) by (b, N) product, by column chunks small enough for the
    cache (so that O is read and written once)."""
    if not terms:
        return
    W = np.stack([np.asarray(w, dtype=float).reshape(-1) for w, _ in terms], axis=1)
    xs = [x.reshape(-1) for _, x in terms]
    X = np.empty((len(xs), chunk))
    tmp = np.empty((O.shape[0], chunk))
    for c0 in range(0, O.shape[1], chunk):
        c1 = min(c0 + chunk, O.shape[1])
        w = c1 - c0
        for r, x in enumerate(xs):
            X[r, :w] = x[c0:c1]
        np.matmul(W, X[:, :w], out=tmp[:, :w])
        O[:, c0:c1] += tmp[:, :w]


def heat_columns(lap, times, sources, tol: float = 1e-8):
    r"""Heat-kernel columns :math:`K_t B^{-1}`-deltas at many times and sources at once.

    .. math:: K_t(:, i) = e^{-t\tilde L}B^{-1}e_i,
              \qquad \|K_t(:,i) - R_t(:,i)\|_B \le \varepsilon_t \|B^{-1}e_i\|_B

    One factorization per common pole (see :func:`heat_diagonals`), each solved with all
    sources as one block right-hand side and dropped before the next.

    Parameters
    ----------
    lap : Laplacian
    times : (T,) float
    sources : (m,) int
    tol : float
        Target of the certified sup error (the engine's meaning: the B-norm error of each
        column relative to :math:`\|B^{-1}e_i\|_B`).

    Returns
    -------
    K : (n, m, T) float
    eps : (T,) float
        Certified :math:`\max|e^{-ts} - r_t(s)|` (the bound is ``eps * ||B^-1 e_i||_B``).
    """
    lap = as_laplacian(lap)
    T = as_times(times)
    idx = np.asarray(sources, dtype=np.int64).reshape(-1)
    u, inv = np.unique(T, return_inverse=True)
    # the (T, n, m) output, the deltas, a complex solve and its real and imaginary parts
    check_dense_size(8.0 * lap.n * idx.size * (T.size + 5), f"{idx.size} heat-kernel columns of length "
                     f"{lap.n} at {T.size} time(s)", "ask for fewer sources at a time, or for distances or "
                     "diagonals (kernel_diagonal, hks), which need no columns")
    E = np.zeros((lap.n, idx.size))
    E[idx, np.arange(idx.size)] = 1.0
    # one (n, m) slab per time, updated in place: the output is the memory, not its copies
    out = np.zeros((u.size, lap.n, idx.size))
    eps = np.empty(u.size)
    # times so large that the heat has decayed to the projection onto ker L (t lambda_max
    # beyond LARGE_T): the engine's split, not a common rational fit (whose bound is inf there)
    ns = int(np.count_nonzero(u * lambda_max(lap) <= LARGE_T))      # u is sorted: a prefix
    for j in range(ns, u.size):
        out[j], eps[j] = _large_time_columns(lap, float(u[j]), E, idx, tol)
    if ns:
        _rational_columns(lap, u[:ns], E, tol, out[:ns], eps[:ns])
    if not np.array_equal(inv, np.arange(inv.size)):
        out = out[inv]
    return np.moveaxis(out, 0, -1), eps[inv]


def _large_time_columns(lap, t: float, E: np.ndarray, idx: np.ndarray, tol: float):
    r"""Heat columns at one large time through the engine, and their relative bound.

    The engine bounds each column's B-norm error absolutely (b_i); relative to
    :math:`\|B^{-1}e_i\|_B \ge 1/\sqrt{B_{ii}}` (Cauchy--Schwarz) it is at most
    :math:`b_i \sqrt{B_{ii}}`, inflated by a few rounding units for the square root.
    """
    op = spectral_operator(lap, heat(t), "auto", tol)
    K = op.apply_inverse_mass(E)
    b = np.asarray(op.error_bound if op.error_bound is not None else np.nan, dtype=float).reshape(-1)
    rel = b * np.sqrt(lap.B.diagonal()[idx]) * (1.0 + 4.0 * np.finfo(float).eps)
    return K, float(np.max(rel)) if np.all(np.isfinite(rel)) else float("nan")


def _rational_columns(lap, u: np.ndarray, E: np.ndarray, tol: float, out: np.ndarray, eps: np.ndarray):
    """Heat columns at the sorted unique times ``u`` from common rational fits, written into
    ``out`` (T, n, m), zeros on entry, and their bounds into ``eps`` (T,)."""
    O = out.reshape(u.size, -1)
    Minv = None
    for g, upper, real, fits, e in heat_plan(lap, u, tol, targets=float(tol)):
        al, C = coefficients(fits, upper, real)
        sl = slice(int(g[0]), int(g[-1]) + 1)          # a group is a run of the sorted times
        eps[g] = e
        if np.all(e + np.abs(al) <= tol):
            # alpha0 B^-1 E would cost a solve with B: dropped, and counted in the bound
            eps[g] = e + np.abs(al)
        else:
            if Minv is None:
                Minv = mass_solve(lap, E)
            _accumulate(O[sl], [(al, Minv)])
        batch, held = [], 0
        for j, (z, fac) in enumerate(pole_factorizations(lap, upper, real)):
            X = fac.solve(E)
            del fac
            if j < upper.size:             # a conjugate pair: 2 Re(c x)
                batch += [(2.0 * C[:, j].real, X.real), (-2.0 * C[:, j].imag, X.imag)]
            else:
                batch.append((C[:, j].real, X.real))
            held += X.nbytes
            if held > COLUMN_BATCH_BYTES:
                _accumulate(O[sl], batch)
                batch, held = [], 0
        _accumulate(O[sl], batch)
