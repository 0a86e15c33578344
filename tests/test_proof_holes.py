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


@pytest.mark.skipif(not available(), reason="compiled LDLT missing")
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


# ----------------------------------------------------------------------------- 2. the kernel split
def exact_projection(lap, f, rhs=False):
    r""":math:`P_0f = 1_c(1_c^\top Bf)/(1_c^\top B1_c)` (:math:`P_0B^{-1}g`: :math:`1_c^\top g` on
    top) in exact rational arithmetic from the float64 B and f: the heat filter's value at a
    t where :math:`e^{-t\lambda_2}` underflows, and what the kernel split computes."""
    B = lap.B.tocsr()
    rows = [(B.indices[B.indptr[i]:B.indptr[i + 1]], B.data[B.indptr[i]:B.indptr[i + 1]]) for i in range(lap.n)]
    fx = [Fraction(float(x)) for x in f]
    Bf = fx if rhs else [sum((Fraction(float(v)) * fx[j] for j, v in zip(*r)), Fraction(0)) for r in rows]
    B1 = [sum((Fraction(float(v)) for v in r[1]), Fraction(0)) for r in rows]
    num, den = {}, {}
    for i, c in enumerate(lap.components):
        num[c] = num.get(c, 0) + Bf[i]
        den[c] = den.get(c, 0) + B1[i]
    return [num[c] / den[c] for c in lap.components]


def exact_bnorm_error(lap, u, truth):
    """||u - truth||_B with the difference taken exactly (then rounded once per entry)."""
    d = np.array([float(Fraction(float(x)) - t) for x, t in zip(u, truth)])
    return float(np.sqrt(d @ (lap.B @ d)))


def cancelling_signals(lap, seed=1):
    """A B-mean-free signal of size 1e6 (P0 f is 0 up to rounding), a large mean with mixed
    signs, and a unit delta."""
    rng = np.random.default_rng(seed)
    n, one = lap.n, np.ones(lap.n)
    g = 1e6 * rng.standard_normal(n)
    return {"mean_free": g - (g @ (lap.B @ one)) / (one @ (lap.B @ one)),
            "large_mean": 1e6 + rng.standard_normal(n) * np.where(rng.random(n) < 0.5, 1.0, 1e3),
            "delta": np.eye(n)[:, n // 3]}


@pytest.fixture(scope="module")
def split_laps():
    """A flat jittered rectangle with boundary (full mass) and a tetrahedral box (lumped), plus
    two components (full mass): the projection is per component."""
    V, Fc = graded_strip(10, 6, 0.05)
    two = (np.vstack([V, V + [2.0, 0, 0]]), np.vstack([Fc, Fc + len(V)]))
    return {"strip_full": sig.laplacian(V, Fc, mass="full"),
            "tets_lumped": sig.laplacian(*box_tets((3, 3, 2))),
            "two_full": sig.laplacian(*two, mass="full")}


@pytest.mark.parametrize("method", ["shift_invert", "krylov", "contour", "rational"])
@pytest.mark.parametrize("t", [1e7, 1e12, 6e18])
def test_heat_at_large_t_bound_covers_projection_rounding(split_laps, method, t):
    """At a t where the heat is the projection onto the constants, the allowance for the
    exact kernel part was scaled to the result: 3e14 times too small for a mean-free signal."""
    for name, lap in split_laps.items():
        op = sig.SpectralOperator(lap, F.heat(t), method=method)
        for sname, f in cancelling_signals(lap).items():
            for rhs in (False, True):
                u = op.apply_inverse_mass(f) if rhs else op.apply(f)
                err = exact_bnorm_error(lap, u, exact_projection(lap, f, rhs))
                assert op.bound_kind == "proof"
                assert err <= op.error_bound, (name, sname, rhs, err, op.error_bound)


# ----------------------------------------------------------------------------- 3. Lanczos estimates
@pytest.mark.parametrize("method", ["krylov", "shift_invert"])
def test_lanczos_estimate_sees_a_narrow_bump(method):
    r"""multiscale(t, 1, 1) = t s e^{-ts} peaks at s = 1/t; on a spectrum [0, 3e7] that bump is
    narrower than the spacing of the Chebyshev points, every coefficient came out ~0 and the
    estimate was 1e-14 for a relative error of 1 (the result 0). Times over 1000:1."""
    lap = sig.laplacian(*graded_strip(12, 5, 1e-3), mass="full")
    lam, X = sig.dense_eigs(lap)
    lam = np.where(np.arange(lap.n) < lap.n_components, 0.0, lam)
    f = np.random.default_rng(0).standard_normal(lap.n)
    fnorm = float(np.sqrt(f @ (lap.B @ f)))
    for t in np.geomspace(0.01, 10.0, 7):
        filt = F.multiscale(t, 1, 1)
        ref = X @ (filt(lam) * (X.T @ (lap.B @ f)))
        op = sig.SpectralOperator(lap, filt, method=method)
        d = op.apply(f) - ref
        err = float(np.sqrt(d @ (lap.B @ d)))
        # the dense reference carries about 1e-12 ||f||_B of its own rounding
        assert err <= op.error_bound + 1e-11 * fnorm, (t, err, op.error_bound)


# ----------------------------------------------------------------------------- the same elsewhere
def test_heat_diagonal_at_large_t_bound_is_not_zero(split_laps):
    """At a t where e^{-t lambda_2} underflows, the diagonal is 1/V_c (the projection) and its
    bound was e^{-t lambda_2} (B^-1)_ii = 0 as a proof, with the sum of the masses rounded."""
    errors = []
    for name, lap in split_laps.items():
        for delta in ("mass", "seed") if lap.lumped else ("mass",):
            d, info = sig.kernel_diagonal(lap, F.heat(1e12), delta=delta, return_info=True)
            assert info["method"] == "projection" and info["bound_kind"] == "proof"
            B = lap.B.tocsr()
            vol, rows = {}, []
            for i, c in enumerate(lap.components):
                row = sum((Fraction(float(v)) for v in B.data[B.indptr[i]:B.indptr[i + 1]]), Fraction(0))
                rows.append(row)
                vol[c] = vol.get(c, 0) + row
            exact = [(rows[i] ** 2 if delta == "seed" else 1) / vol[c] for i, c in enumerate(lap.components)]
            err = max(abs(Fraction(float(x)) - e) for x, e in zip(d, exact))
            assert err <= info["abs_error_bound"], (name, delta, float(err), info["abs_error_bound"])
            errors.append(err)
    assert max(errors) > 0          # the rounding is really there
