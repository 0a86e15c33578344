r"""Inner eigensolvers of :func:`spectral_igl.linalg.eigs` besides ARPACK: Krylov--Schur (thick
restart, Stewart 2001) and multi-resolution prolongation (Vaxman et al. 2010).

Each returns B-orthonormal vectors spanning (approximately) the m pairs of the pencil
:math:`L x = \lambda B x` nearest :math:`-s` on the B-orthogonal complement of given pairs;
none of them is trusted: :func:`~spectral_igl.linalg.eigs` refines them by Rayleigh--Ritz and
certifies them by residual bounds and an inertia count, and searches again for any pair the
count says is missing.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .threads import serial_blas

__all__ = ["krylov_schur", "coarse_mesh", "prolongation", "subspace_refine", "KS_MAX_RESTARTS"]

#: restarts :func:`krylov_schur` allows before it returns its best Ritz vectors (the
#: certificate of :func:`~spectral_igl.linalg.eigs` then judges them)
KS_MAX_RESTARTS = 100


def _complement(lap, Z, W):
    """The B-orthogonal projector onto the complement of [Z, W] (Z sparse, W dense), as a function."""
    B = lap.B

    def project(y):
        By = B @ y
        return y - Z @ (Z.T @ By) - W @ (W.T @ By)
    return project


@serial_blas
def krylov_schur(lap, fac, s, Z, W, m, tol, seed, bar):
    r"""(n, m) B-orthonormal Ritz vectors of the m pairs nearest :math:`-s` on the B-orthogonal
    complement of [Z, W], by the Krylov--Schur method on :math:`A = (L + sB)^{-1}B`.

    Parameters
    ----------
    lap : Laplacian
    fac : factorization of :math:`L + sB` (``.solve``)
    s : float
        The shift.
    Z, W : (n, c) sparse, (n, w) float
        B-orthonormal bases to deflate (ker L, pairs already found).
    m : int
        Pairs wanted.
    tol : float
        Relative residual of the Ritz values of A at which a pair counts as converged
        (0: :math:`10^{-13}`).
    seed : int
        Of the random start vector.
    bar : progress bar (``.update()`` per solve)

    Returns
    -------
    X : (n, m) float, :math:`X^\top B X = I`

    Notes
    -----
    A is self-adjoint in the B-inner product, so its Krylov--Schur decomposition
    :math:`AV_p = V_pS_p + v_{p+1}b^\top` has a symmetric :math:`S_p` (Stewart 2001; for a
    symmetric operator, thick-restart Lanczos). Each cycle expands the basis by Arnoldi steps
    with full B-orthogonalization (done twice) to ``ncv`` vectors, computes the Schur form
    :math:`S = Q\Theta Q^\top` (eigh of the symmetric part), and the residual of the Ritz pair
    :math:`(\theta_i, V q_i)` is exactly :math:`|b^\top q_i|` in the B-norm. When the m
    largest θ (the eigenvalues :math:`1/(\lambda + s)` nearest the shift) have residuals below
    ``tol`` θ the Ritz vectors are returned; else the decomposition is truncated to its
    ``keep`` leading Ritz pairs, :math:`AV_kQ_k = V_kQ_k\Theta_k + v_{p+1}(b^\top Q_k)`,
    which is again a Krylov--Schur decomposition, and expansion resumes from
    :math:`v_{p+1}`. No implicit shifts, no deflation of converged vectors inside the cycle:
    the restart keeps them exactly.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ev, X, info = sig.eigs(lap, 9, method="krylov_schur", return_info=True)
    >>> info["bound_kind"], bool(abs(ev - sig.dense_eigs(lap, 9)[0]).max() < 1e-9)
    ('proof', True)
    """
    n = lap.n
    project = _complement(lap, Z, W)
    free = n - Z.shape[1] - W.shape[1]
    ncv = min(free - 1, max(2 * m + 1, m + 32))
    keep = min(ncv - 1, m + max(2, (ncv - m) // 2))
    tol = tol if tol > 0 else 1e-13
    B = lap.B
    V = np.zeros((n, ncv + 1))
    H = np.zeros((ncv + 1, ncv))
    rng = np.random.default_rng(seed - 1)
    V[:, 0] = _normalised(lap, project(rng.standard_normal(n)))
    start = 0
    for _ in range(KS_MAX_RESTARTS):
        for j in range(start, ncv):
            w = project(fac.solve(B @ V[:, j]))
            bar.update()
            h = np.zeros(j + 1)
            for _ in range(2):            # classical Gram-Schmidt, twice
                c = V[:, :j + 1].T @ (B @ w)
                w = w - V[:, :j + 1] @ c
                h += c
            beta = float(np.sqrt(max(w @ (B @ w), 0.0)))
            H[:j + 1, j] = h
            if beta <= 1e-14 * max(abs(h[j]), 1e-300):   # invariant subspace: a fresh direction
                w = project(rng.standard_normal(n))
                w = w - V[:, :j + 1] @ (V[:, :j + 1].T @ (B @ w))
                beta, H[j + 1, j] = 0.0, 0.0
                V[:, j + 1] = _normalised(lap, w)
            else:
                H[j + 1, j] = beta
                V[:, j + 1] = w / beta
        S = H[:ncv, :ncv]
        theta, Q = np.linalg.eigh(0.5 * (S + S.T))
        theta, Q = theta[::-1], Q[:, ::-1]
        res = np.abs(H[ncv, :ncv] @ Q)
        if np.all(res[:m] <= tol * np.abs(theta[:m])):
            break
        V[:, :keep] = V[:, :ncv] @ Q[:, :keep]
        V[:, keep] = V[:, ncv]
        b = H[ncv, :ncv] @ Q[:, :keep]
        H[:] = 0.0
        H[:keep, :keep] = np.diag(theta[:keep])
        H[keep, :keep] = b
        start = keep
    return V[:, :ncv] @ Q[:, :m]


def coarse_mesh(V, F, faces: int):
    """(Vc, Fc): (V, F) decimated by edge collapses (``igl.decimate``) to about ``faces`` faces."""
    import igl

    out = igl.decimate(np.asfortranarray(V, dtype=np.float64), np.asfortranarray(F, dtype=np.int32), int(faces))
    Vc, Fc = out[-4], out[-3]
    used = np.unique(Fc)                  # decimate keeps collapsed vertices unreferenced
    remap = np.full(Vc.shape[0], -1)
    remap[used] = np.arange(used.size)
    return np.ascontiguousarray(Vc[used]), np.ascontiguousarray(remap[Fc])


def _normalised(lap, x):
    return x / np.sqrt(max(float(x @ (lap.B @ x)), 1e-300))


def prolongation(V, F, Vc, Fc):
    r"""(n, nc) sparse prolongation from a coarse triangle mesh (Vc, Fc) to the vertices V: each
    fine vertex takes the barycentric interpolation at its closest point on the coarse surface.

    Returns
    -------
    P : (n, nc) scipy.sparse.csr_matrix, rows summing to 1
    """
    import igl
    import scipy.sparse as sp

    _, face, point = igl.point_mesh_squared_distance(np.ascontiguousarray(V, dtype=np.float64),
                                                     np.ascontiguousarray(Vc, dtype=np.float64),
                                                     np.ascontiguousarray(Fc, dtype=np.int64))
    tri = Fc[face]
    bary = igl.barycentric_coordinates(np.ascontiguousarray(point), np.ascontiguousarray(Vc[tri[:, 0]]),
                                       np.ascontiguousarray(Vc[tri[:, 1]]), np.ascontiguousarray(Vc[tri[:, 2]]))
    bary = np.clip(np.nan_to_num(bary, nan=1.0 / 3.0), 0.0, 1.0)
    bary /= bary.sum(axis=1, keepdims=True)
    rows = np.repeat(np.arange(V.shape[0]), 3)
    return sp.csr_matrix((bary.ravel(), (rows, tri.ravel())), shape=(V.shape[0], Vc.shape[0]))


@serial_blas
def subspace_refine(lap, fac, X, project, iterations: int, bar):
    r"""``iterations`` steps of block Krylov refinement of the block X (p columns): Rayleigh--Ritz
    on :math:`\operatorname{span}[X, AX]`, :math:`A = (L + sB)^{-1}B`, keeping the p Ritz
    vectors of the smallest Ritz values (B-orthonormal, ascending)."""
    L, B = lap.L, lap.B
    p = X.shape[1]
    X = _orthonormal(B, X, X[:, :0])
    for _ in range(iterations):
        W = _orthonormal(B, project(fac.solve(B @ X)), X)
        bar.update(p)
        Y = np.hstack([X, W])
        H = Y.T @ (L @ Y)
        theta, Q = np.linalg.eigh(0.5 * (H + H.T))
        X = Y @ Q[:, :p]
    return X


def _orthonormal(B, W, X):
    """A B-orthonormal basis of the part of span W that is B-orthogonal to the B-orthonormal X
    (directions below 1e-10 of the largest dropped), by two passes."""
    for _ in range(2):
        W = W - X @ (X.T @ (B @ W))
        G = W.T @ (B @ W)
        d, U = np.linalg.eigh(0.5 * (G + G.T))
        keep = d > 1e-14 * d.max()
        W = W @ (U[:, keep] / np.sqrt(d[keep]))
    return W
