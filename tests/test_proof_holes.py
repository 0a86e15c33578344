"""Reported bounds that were below the true error: exact paths with a zero rounding allowance,
rounding allowances scaled to the result instead of to the terms that cancel, and zero
estimates. Each case against ground truth computed in exact or 50-digit arithmetic."""
from decimal import Decimal, localcontext
from fractions import Fraction

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import box_tets
from spectral_igl.linalg.ldlt import available

F = sig.filters


# ----------------------------------------------------------------------------- ground truth
def _dec(A):
    """float64 array -> object array of the exact Decimals."""
    return np.vectorize(Decimal, otypes=[object])(np.asarray(A, dtype=float))


def _dec_inverse(M):
    """Gauss-Jordan inverse with partial pivoting of an object array of Decimals."""
    n = M.shape[0]
    A = np.concatenate([M.copy(), np.eye(n, dtype=int).astype(object) * Decimal(1)], axis=1)
    for k in range(n):
        piv = k + int(np.argmax([abs(x) for x in A[k:, k]]))
        if piv != k:
            A[[k, piv]] = A[[piv, k]]
        A[k] = A[k] / A[k, k]
        col = A[:, k].copy()
        col[k] = Decimal(0)
        nz = np.flatnonzero(col != 0)
        if nz.size:
            A[nz] = A[nz] - np.outer(col[nz], A[k])
    return A[:, n:]


def power_diagonals(lap, powers, prec=50):
    r"""diag of :math:`(\tilde L^+)^pB^{-1}` for each p, in ``prec``-digit arithmetic from the
    float64 L and B: :math:`G_1 = (L + BZZ^\top B)^{-1} - ZZ^\top`, :math:`G_p = G_1(BG_1)^{p-1}`."""
    with localcontext() as ctx:
        ctx.prec = prec
        Z, L, B = (_dec(M.toarray()) for M in (lap.component_basis(), lap.L, lap.B))
        BZ = B.dot(Z)
        G1 = _dec_inverse(L + BZ.dot(BZ.T)) - Z.dot(Z.T)
        out, G = {}, G1
        for p in range(1, max(powers) + 1):
            if p > 1:
                G = G1.dot(B.dot(G))
            if p in powers:
                out[p] = np.array([float(G[i, i]) for i in range(lap.n)])
        return out


def graded_strip(nx=12, ny=5, hmin=1e-4):
    """A flat rectangle with boundary whose columns are geometrically graded from ``hmin``:
    lambda_max / lambda_min+ ~ 1e8, so rounding in the solves is far from negligible."""
    xs = np.r_[0.0, np.geomspace(hmin, 1.0, nx - 1)]
    x, y = np.meshgrid(xs, np.linspace(0.0, 0.5, ny), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange(nx * ny).reshape(nx, ny)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    return V, np.r_[np.c_[a, b, d], np.c_[a, d, c]]


# ----------------------------------------------------------------------------- 1. selinv diagonal
SQUARED_POWERS = {1: lambda: F.commute_time().square, 2: lambda: F.biharmonic().square,
                  3: lambda: F.polyharmonic(3).square, 4: lambda: F.polyharmonic(4).square}


@pytest.fixture(scope="module")
def ill_conditioned():
    """(name, lap, exact diagonals of s^-1..s^-4): a graded strip (full and lumped mass) and a
    thin tetrahedral slab (full mass)."""
    out = []
    for name, lap in [("strip_full", sig.laplacian(*graded_strip(), mass="full")),
                      ("strip_lumped", sig.laplacian(*graded_strip())),
                      ("slab_full", sig.laplacian(*box_tets((5, 5, 1), (1.0, 1.0, 2e-3)), mass="full"))]:
        out.append((name, lap, power_diagonals(lap, [1, 2, 3, 4])))
    return out


@pytest.mark.skipif(not available(), reason="compiled LDLT or pymetis missing")
@pytest.mark.parametrize("p", [1, 2, 3, 4])
def test_selinv_power_diagonal_bound_covers_rounding(ill_conditioned, p):
    """The exact paths (s^-1, s^-2: grounded inverse; s^-3, s^-4: circle rule) used to report a
    bound of 0 (or the circle's aliasing alone) as a proof, below their rounding error."""
    for name, lap, exact in ill_conditioned:
        kern = sig.diagonal.SelinvKernel(lap, SQUARED_POWERS[p](), 1e-8)
        diag, bound = kern.diagonal()
        err = np.abs(diag - exact[p])
        assert np.all(err <= bound), (name, float(np.max(err / bound)))
        assert np.max(err) > 0          # rounding is really there
        d, info = sig.kernel_diagonal(lap, SQUARED_POWERS[p](), method="selinv", return_info=True)
        assert info["bound_kind"] == "proof"
        assert np.max(np.abs(d - exact[p])) <= info["abs_error_bound"]
