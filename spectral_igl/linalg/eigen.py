"""Generalized eigenpairs L x = λ B x: the truncated-spectrum baseline and dense ground truth."""
from __future__ import annotations

import numbers
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from .._validate import as_flag, as_int, as_positive, as_tol, check_dense_size, describe
from ..accuracy import rounding_gamma as _gamma, weakest
from ..laplacian import Laplacian, as_laplacian, lambda_max, lambda_max_kind, mass_ratio
from ..laplacian.units import dimension
from ..progress import progress_bar
from . import ldlt
from .eigensolvers import coarse_mesh, krylov_schur, prolongation, subspace_refine
from .factor import check_backend, factorize
from .solves import ldlt_factor
from .threads import serial_blas

__all__ = ["eigs", "EIG_METHODS", "dense_eigs", "cached_eigs", "lambda_min_positive", "lambda_min_positive_kind",
           "negative_inertia", "eigenvalue_bracket", "gap_lower_bound"]


#: at most this many Lanczos runs per call of :func:`eigs`: the first, then searches of the
#: B-orthogonal complement of the pairs already found for the ones the count says are missing
MAX_SEARCHES = 5

#: the inner eigensolvers of :func:`eigs` (each certified the same way)
EIG_METHODS = ("lanczos", "krylov_schur", "multires")

#: ``method="multires"``: the coarse mesh has about this fraction of the faces (at least
#: :data:`MULTIRES_MIN_FACES` per wanted pair); below that the direct Lanczos path is taken
MULTIRES_FRACTION = 0.125
MULTIRES_MIN_FACES = 12

#: ``method="multires"``: most subspace iterations on the fine mesh after the prolongation
MULTIRES_ITERATIONS = 30

#: the inertia count is taken only at a shift at least this fraction of ``lambda_max(lap)`` away
#: from every computed eigenvalue's enclosure (see :func:`eigs`, "Certificate")
COUNT_MARGIN = 1e-10


def eigs(lap: Laplacian, k: int, tol: float = 0.0, backend: str = "auto", progress=None,
         return_info: bool = False, method: str = "lanczos"):
    r"""The ``k`` smallest generalized eigenpairs :math:`L x = \lambda B x`, certified.

    Shift-invert Lanczos (ARPACK; or the Krylov--Schur method, or a prolongation from a
    coarse mesh, see ``method``) in the B-inner product, with ker L deflated exactly:
    the first ``lap.n_components`` pairs are :math:`\lambda = 0` with the B-normalised
    indicator of each connected component, and Lanczos runs on the B-orthogonal
    complement, so shapes with many components (or isolated vertices) lose no
    multiplicity. A few pairs beyond ``k`` are computed, the pairs are refined by a
    Rayleigh–Ritz step, and the result is certified by counting (below).

    Certificate. Lanczos can skip a copy of a multiple eigenvalue (which copy depends on
    the rounding, so on the CPU). Every call therefore counts, by Sylvester's law of
    inertia, the eigenvalues below a shift σ placed in a gap of the computed values just
    after the k-th (after the whole cluster the k-th belongs to): the number of negative
    pivots of an :math:`LDL^\top` factorization of :math:`L - \sigma B`
    (:func:`negative_inertia`). When it exceeds the number of computed values below σ,
    the missing pairs are searched for in the B-orthogonal complement of the ones found,
    and the count is taken again (at most :data:`MAX_SEARCHES` Lanczos runs); when it
    cannot be made to agree, a ``RuntimeWarning`` says so and ``info`` says
    ``"estimate"``. What is proved when ``info["bound_kind"] == "proof"``:

    1. residuals: :math:`\eta_i \ge \|L x_i - \tilde\lambda_i B x_i\|_{B^{-1}}`, including
       the rounding of their evaluation (:math:`\|r\|_{B^{-1}} \le \|r\|_{D^{-1}}/\sqrt c`
       with D the row sums of B and :math:`B \ge cD`, :func:`~spectral_igl.laplacian.mass_ratio`);
    2. enclosures: the values are grouped into clusters whose intervals
       :math:`[\min\tilde\lambda_S - \rho_S, \max\tilde\lambda_S + \rho_S]` are disjoint,
       :math:`\rho_S = \|(\eta_i)_{i\in S}\|_2/\sqrt{1-f} + (\max\tilde\lambda_S -
       \min\tilde\lambda_S)\, f\sqrt{1+f}/(1-f)`, f a bound of
       :math:`\|X^\top B X - I\|_2`. By Kahan's theorem each interval holds at least
       :math:`|S|` eigenvalues (counting multiplicity);
    3. the count: exactly ``info["count"]`` eigenvalues lie below σ, and σ is at least
       ``info["count_margin"]`` above the last interval and below the next one. So each
       interval holds exactly :math:`|S|` eigenvalues, the first ``count`` eigenvalues are
       enclosed, and :math:`|\tilde\lambda_i - \lambda_i| \le` ``info["abs_error"][i]``
       (:math:`=\rho_S` of i's cluster) for the i-th smallest eigenvalue
       :math:`\lambda_i`, i < k. The returned values are the k smallest with their
       multiplicities.

    The count is exact for the matrix the factorization actually factored,
    :math:`L - \sigma B + E` with E its backward error, whose pencil's eigenvalues are
    within :math:`\delta = \|B^{-1/2} E B^{-1/2}\|_2` of those of :math:`(L, B)`. A count
    j so says that at most j eigenvalues of :math:`(L, B)` lie below :math:`\sigma - \delta`;
    the enclosures hold at least j, all below :math:`\sigma -` ``info["count_margin"]``,
    so 3. holds as long as :math:`\delta <` ``info["count_margin"]``. σ is placed in the
    middle of a gap (30% or 70% across it where the factorization meets a zero pivot) at
    least :data:`COUNT_MARGIN` ``* lambda_max(lap)`` wide on either side (about
    :math:`10^6` rounding units of the largest eigenvalue), and δ is measured a posteriori
    by a solve with the factorization (``info["count_backward_error"]``, in the scaling of
    D): a count whose δ exceeds a hundredth of the margin is not accepted. This measured δ
    (a lower estimate of the backward error, not a bound) is the one ingredient not proved.

    Parameters
    ----------
    lap : Laplacian
    k : int
        Number of eigenpairs, ``1 <= k < n``.
    tol : float
        ARPACK relative tolerance (0 = machine precision).
    backend : str
        Sparse factorization of the shift, see :func:`spectral_igl.linalg.shifted_factor`.
    progress : bool, optional
        A progress counter on stderr: the shift's factorization, then one step per
        solve of the Lanczos iteration, whose number is not known in advance (see
        :mod:`spectral_igl.progress`; default off).
    return_info : bool
        Also return the certificate.
    method : {"lanczos", "krylov_schur", "multires"}
        The first search: ``"lanczos"`` (ARPACK's implicitly restarted Lanczos, default);
        ``"krylov_schur"`` (thick restart, Stewart 2001, the survey's Table 2:
        :func:`~spectral_igl.linalg.eigensolvers.krylov_schur`); ``"multires"`` (Vaxman et
        al. 2010, triangle meshes: the pairs of a mesh decimated to
        :data:`MULTIRES_FRACTION` of its faces, prolongated by barycentric interpolation at
        the closest coarse point, then refined by subspace iteration with the fine
        factorization and Rayleigh--Ritz until their residuals are small, at most
        :data:`MULTIRES_ITERATIONS` steps; other domains and small meshes take the Lanczos
        path). Every method's pairs go through the same Rayleigh--Ritz step and certificate,
        and any pair the count says is missing is searched for by Lanczos.

    Returns
    -------
    evals : (k,) float, ascending, ``evals[:c] == 0``
    evecs : (n, k) float, :math:`X^\top B X = I`
    info : dict, only with ``return_info=True``
        ``"bound_kind"`` (``"proof"`` or ``"estimate"``), ``"count_certified"`` (bool),
        ``"shift"`` (σ, None when no count was taken), ``"count"`` (eigenvalues below σ by
        inertia), ``"count_margin"``, ``"count_backward_error"``, ``"residuals"`` ((k,)
        :math:`\eta_i`), ``"abs_error"`` ((k,) :math:`\rho_S`, an estimate unless proved),
        ``"searches"`` (Lanczos runs), ``"method"``, ``"first_search"`` (the solver of the
        first search: ``"lanczos"`` where ``"multires"`` does not apply).

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ev, X, info = sig.eigs(lap, 9, return_info=True)
    >>> info["bound_kind"], info["count"], bool(info["abs_error"].max() < 1e-9)
    ('proof', 9, True)
    """
    lap = as_laplacian(lap)
    n, c = lap.n, lap.n_components
    if isinstance(k, bool) or not isinstance(k, numbers.Integral):
        raise TypeError(f"k must be an integer, got {describe(k)}")
    k = int(k)
    if not 1 <= k < n:
        raise ValueError(f"k must be in [1, {n - 1}] for n = {n}, got {k}")
    tol = as_tol(tol, "tol", allow_zero=True)
    if not isinstance(return_info, (bool, np.bool_)):
        raise TypeError(f"return_info must be True or False, got {describe(return_info)}")
    if not isinstance(method, str) or method not in EIG_METHODS:
        raise ValueError(f"method must be one of {EIG_METHODS}, got {describe(method)}")
    backend = check_backend(backend)
    if progress is not None:
        as_flag(progress, "progress")
    # the (n, k) eigenvectors and ARPACK's (n, ncv) Lanczos basis, ncv about 2k
    check_dense_size(8.0 * n * (3 * k + 32), f"{k} eigenvectors of length {n} (with the Lanczos basis)",
                     "ask for fewer pairs, or use the spectrum-free engine (apply_filter, "
                     "kernel_diagonal) that needs no eigenvectors")
    Z = lap.component_basis()  # sparse (n, c), B-orthonormal basis of ker L
    if k <= c and not return_info:   # exact: the component indicators
        return np.zeros(k), Z[:, :k].toarray()
    vals, X, info = _certified_pairs(lap, k, tol, backend, progress, method)
    if not info["count_certified"]:
        warnings.warn(f"eigs: the {k} smallest eigenvalues could not be certified by an inertia count "
                      f"({info['searches']} Lanczos searches, count {info['count']} below the shift "
                      f"{info['shift']}): eigenvalues may be missing; use dense_eigs on small meshes",
                      RuntimeWarning, stacklevel=2)
    vals, X = vals[:k], X[:, :k]
    return (vals, X, info) if return_info else (vals, X)


def _certified_pairs(lap, k, tol, backend, progress, method="lanczos"):
    """Pairs (at least k of them) and their certificate: Lanczos searches until the count agrees."""
    n, c = lap.n, lap.n_components
    Zd = lap.component_basis().toarray()
    extra = max(4, (k - c) // 20)         # pairs beyond k, to find a gap after the k-th value
    want = max(k - c, 1) + extra
    bar = progress_bar(None, f"eigs k={k}", progress, unit="solve")
    fac, kept = None, np.zeros((n, 0))    # kept: non-kernel pairs trusted by the last count
    first = method
    for search in range(1, MAX_SEARCHES + 1):
        if want >= n - c - kept.shape[1] - 1 or n - c - kept.shape[1] <= 3:
            # too few modes left for ARPACK (ncv < dimension of the complement): all of them
            vals, X = dense_eigs(lap)
            info = _certificate(lap, vals, X, k)
            break
        if fac is None:
            # shift: any s > 0 keeps L + sB positive definite; kernel directions are projected out
            s = 1e-3 * float(lap.L.diagonal().sum() / lap.B.diagonal().sum()) / max(n, 1) ** 0.5
            bar.set_postfix_str("factorization")
            fac = factorize(lap.L + s * lap.B, backend=backend)
            bar.set_postfix_str("Lanczos")
        new = None
        if method == "multires" and search == 1:
            new = _multires(lap, fac, s, want, tol, backend, bar)
            first = "multires" if new is not None else "lanczos"
        if new is None:
            solver = krylov_schur if method == "krylov_schur" else _lanczos
            new = solver(lap, fac, s, lap.component_basis(), kept, want, tol, search, bar)
        theta, Xn = _rayleigh_ritz(lap, np.hstack([kept, new]))
        vals, X = np.concatenate([np.zeros(c), theta]), np.hstack([Zd, Xn])
        info = _certificate(lap, vals, X, k)
        if info["count_certified"] or info["status"] == "failed":
            break
        if info["status"] == "missed":   # search the complement of the pairs below the shift
            below = info["count_below"]
            kept = Xn[:, :below - c]
            want = info["count"] - below + extra
        else:                            # no usable gap among the pairs: search further up
            kept, want, extra = Xn, 2 * extra, 2 * extra
    bar.close()
    info["searches"], info["method"], info["first_search"] = search, method, first
    del info["status"], info["count_below"]
    return vals, X, info


@serial_blas
def _lanczos(lap, fac, s, Z, W, m, tol, seed, bar):
    r"""(n, m) the m pairs nearest -s of the pencil on the B-orthogonal complement of [Z, W]
    (Z sparse, W dense, both B-orthonormal), by shift-invert Lanczos with the factor of L + sB."""
    n, B = lap.n, lap.B

    def project(y):
        By = B @ y
        return y - Z @ (Z.T @ By) - W @ (W.T @ By)

    def op(x):  # (L + sB)^{-1} x restricted to the complement; x = B v in mode 3
        x = x - B @ (Z @ (Z.T @ x)) - B @ (W @ (W.T @ x))
        bar.update()
        return project(fac.solve(x))

    Op = spla.LinearOperator((n, n), matvec=op, dtype=np.float64)
    v0 = project(np.random.default_rng(seed - 1).standard_normal(n))
    free = n - Z.shape[1] - W.shape[1]
    ncv = min(free - 1, max(2 * m + 1, m + 32))
    _, vecs = spla.eigsh(lap.L, k=m, M=B, sigma=-s, which="LM", OPinv=Op, v0=v0, tol=tol, ncv=ncv)
    return vecs


def _multires(lap, fac, s, m, tol, backend, bar):
    r"""(n, m) pairs nearest -s from a coarse mesh (see :func:`eigs`, ``method="multires"``), or
    None where the method does not apply (not a triangle mesh, or too small to coarsen)."""
    V, F = lap.data.get("V"), lap.data.get("F")
    c = lap.n_components
    if lap.domain != "triangle" or V is None or F is None or np.shape(F)[1] != 3:
        return None
    faces = max(int(MULTIRES_FRACTION * len(F)), MULTIRES_MIN_FACES * (m + c))
    if faces > 0.5 * len(F):
        return None
    from ..laplacian import laplacian

    Vc, Fc = coarse_mesh(V, F, faces)
    coarse = laplacian(Vc, Fc, mass="lumped" if lap.lumped else "full")
    p = m + max(8, m // 2)                     # the block, with room for convergence
    kc = min(coarse.n - 2, coarse.n_components + p)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Xc = eigs(coarse, kc, backend=backend)[1][:, coarse.n_components:]
    Z = lap.component_basis()

    def project(y):
        return y - Z @ (Z.T @ (lap.B @ y))

    X = subspace_refine(lap, fac, project(prolongation(V, F, Vc, Fc) @ Xc), project, 1, bar)
    want = max(tol, 1e-10)
    for _ in range(MULTIRES_ITERATIONS - 1):
        theta = np.einsum("ij,ij->j", X, lap.L @ X)
        R = lap.L @ X[:, :m] - (lap.B @ X[:, :m]) * theta[:m]
        res = np.sqrt(np.sum(R * R / lap.mass[:, None], axis=0))
        if np.all(res <= want * np.maximum(theta[:m], theta[min(m, X.shape[1] - 1)])):
            break
        X = subspace_refine(lap, fac, X, project, 1, bar)
    return X[:, :m]


@serial_blas
def _rayleigh_ritz(lap, X):
    """Ritz values (ascending, clipped at 0) and B-orthonormal Ritz vectors of span(X)."""
    H, G = X.T @ (lap.L @ X), X.T @ (lap.B @ X)
    theta, Q = sla.eigh((H + H.T) / 2, (G + G.T) / 2)
    return np.maximum(theta, 0.0), X @ Q


def _residual_bounds(lap, vals, LX, BX, X):
    r"""(k,) :math:`\eta_i \ge \|L x_i - \lambda_i B x_i\|_{B^{-1}}`, the rounding of the evaluation included.

    LX and BX are the computed products (``width`` terms per entry); with the subtraction,
    the computed residual is off by at most
    :math:`\gamma (|L||x| + |\lambda||B||x|)`, whose :math:`D^{-1}` norm is at most
    :math:`\gamma (g_L + |\lambda| g_B)\|x\|_D` with :math:`g_M = \max_i \sum_j |M_{ij}|/d_i
    \ge \|D^{-1/2}|M|D^{-1/2}\|_2` (symmetric M).
    """
    L, B, n = lap.L, lap.B, lap.n
    d = lap.mass
    width = int(max(np.diff(L.indptr).max(initial=0), np.diff(B.indptr).max(initial=0)))
    gL, gB = (float(np.max(np.asarray(abs(M).sum(axis=1)).ravel() / d)) for M in (L, B))
    R = LX - BX * vals
    computed = np.sqrt(np.sum(R * R / d[:, None], axis=0)) * (1 + _gamma(n + 2))
    rounding = _gamma(width + 2) * (gL + np.abs(vals) * gB) * np.sqrt(np.sum(X * X * d[:, None], axis=0))
    return (computed + rounding) / np.sqrt(mass_ratio(lap))


def _orthonormality_defect(lap, X, BX):
    r"""A bound of :math:`\|X^\top B X - I\|_2`, the rounding of its evaluation included."""
    B, n, k = lap.B, lap.n, X.shape[1]
    width = int(np.diff(B.indptr).max(initial=0))
    G = X.T @ BX - np.eye(k)
    normB = float(np.max(np.asarray(abs(B).sum(axis=1)).ravel()))   # ≥ ‖|B|‖₂ (symmetric)
    return float(np.linalg.norm(G, 2)) + _gamma(n + width) * normB * float(np.sum(X * X))


def _clusters(vals, eta, f):
    """Clusters of the sorted ``vals`` with disjoint enclosures: (start, stop, radius) triples."""
    groups = [[i, i + 1] for i in range(vals.size)]
    while True:
        rad = [np.linalg.norm(eta[a:b]) / np.sqrt(1 - f) + (vals[b - 1] - vals[a]) * f * np.sqrt(1 + f) / (1 - f)
               for a, b in groups]
        merged = [groups[0] + [rad[0]]]
        for (a, b), r in zip(groups[1:], rad[1:]):
            if vals[a] - r <= vals[merged[-1][1] - 1] + merged[-1][2]:
                merged[-1][1] = b
            else:
                merged.append([a, b, r])
        if len(merged) == len(groups):
            return [tuple(g) for g in merged]
        groups = [g[:2] for g in merged]


def _certificate(lap, vals, X, k):
    """The certificate of :func:`eigs` for the sorted pairs (vals, X), at least k of them.

    ``status``: "certified", "missed" (the count exceeds ``count_below``, the number of pairs
    below the shift), "no_gap" (no usable gap after the k-th value) or "failed".
    """
    LX, BX = lap.L @ X, lap.B @ X
    eta = _residual_bounds(lap, vals, LX, BX, X)
    f = _orthonormality_defect(lap, X, BX)
    info = {"bound_kind": "estimate", "count_certified": False, "shift": None, "count": None,
            "count_margin": None, "count_backward_error": None, "residuals": eta[:k],
            "abs_error": eta[:k].copy(), "status": "failed", "count_below": None}
    if not f < 0.5:
        return info
    groups = _clusters(vals, eta, f)
    radius = np.concatenate([np.full(b - a, r) for a, b, r in groups])
    info["abs_error"] = radius[:k]
    need = COUNT_MARGIN * lambda_max(lap)
    info["status"] = "no_gap"
    for (_, j, r), (_, _, r_next) in zip(groups[:-1], groups[1:]):
        lo, hi = vals[j - 1] + r, vals[j] - r_next
        if j < k or (hi - lo) / 2 < need:
            continue
        for sigma in (lo + (hi - lo) / 2, lo + 0.3 * (hi - lo), lo + 0.7 * (hi - lo)):
            count, backward = _inertia(lap, sigma)
            if count is not None:
                break
        margin = min(sigma - lo, hi - sigma)
        info.update(shift=float(sigma), count=count, count_margin=float(margin), count_below=j,
                    count_backward_error=backward)
        if count is None or backward is None or backward > margin / 100 or count < j:
            info["status"] = "failed"    # fewer than the j proved below σ: the count is wrong
        elif count > j:
            info["status"] = "missed"
        else:
            info["status"], info["count_certified"] = "certified", True
            if lambda_max_kind(lap) == "proof":   # the mass ratio in the residual bounds is proved
                info["bound_kind"] = "proof"
        return info
    return info


def _inertia(lap, mu):
    """(negative pivots of an LDLᵀ of L - μB, an estimate of how far its backward error E moves
    the eigenvalues of the pencil), or (None, None) when no such factorization succeeds."""
    A = (lap.L - mu * lap.B).tocsr()
    if ldlt.available():
        try:
            fac = ldlt_factor(lap, A)
        except ValueError:
            return None, None
        d, solve = fac.pivots(), fac.solve
    else:
        try:
            lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
        except RuntimeError:
            return None, None
        if not np.array_equal(lu.perm_r, lu.perm_c):
            return None, None
        d, solve = lu.U.diagonal(), lu.solve
    if not np.all(np.isfinite(d)) or np.any(d == 0):
        return None, None
    # E y = b - A y for a solve y: in the scaling of D (row sums of B), which the pencil's
    # eigenvalues see, the residual over the solution estimates ‖D^-1/2 E D^-1/2‖₂ from below
    # (Rigal–Gaches); B ≥ cD turns it into a displacement of the eigenvalues
    h = np.sqrt(lap.mass)[:, None]
    b = h * np.random.default_rng(1).standard_normal((lap.n, 2))
    y = solve(b)
    backward = float(np.max(np.linalg.norm((A @ y - b) / h, axis=0) / np.linalg.norm(h * y, axis=0)))
    backward /= mass_ratio(lap)
    return int(np.sum(d < 0)), backward if np.isfinite(backward) else None


@serial_blas
def dense_eigs(lap: Laplacian, k: int | None = None, max_n: int = 8000):
    r"""All (or the first ``k``) generalized eigenpairs by a dense solver: the ground truth.

    Parameters
    ----------
    lap : Laplacian or mesh
    k : int, optional
        Number of pairs, the smallest first (default: all n).
    max_n : int
        Largest n accepted (default 8000): memory and time grow as n² and n³.

    Returns
    -------
    evals : (k,) float
        Ascending, :math:`0 = \lambda_1 \le \lambda_2 \le \dots`, the c zeros of ker L exact.
    evecs : (n, k) float
        :math:`L x = \lambda B x` with :math:`X^\top B X = I`.

    Notes
    -----
    ``scipy.linalg.eigh(L, B)``; the kernel is replaced by the exact B-normalised component
    indicators, and the other eigenvectors are projected B-orthogonally to them. Any spectral
    operator is then :math:`\varphi(\tilde L) = X \varphi(\Lambda) X^\top B`.

    Examples
    --------
    The unit sphere's eigenvalues :math:`l(l+1)`, multiplicity :math:`2l+1`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> lam, X = sig.dense_eigs(lap, k=9)
    >>> np.round(lam, 1).tolist(), bool(np.allclose(X.T @ lap.B @ X, np.eye(9)))
    ([0.0, 2.0, 2.0, 2.0, 6.0, 6.0, 6.0, 6.0, 6.0], True)
    """
    lap = as_laplacian(lap)
    n, c = lap.n, lap.n_components
    max_n = as_int(max_n, "max_n", lo=1)
    if n > max_n:
        raise ValueError(f"dense_eigs is for small meshes: n = {n} > max_n = {max_n}; use eigs(lap, k)")
    k = n if k is None else as_int(k, "k", lo=1, hi=n)
    check_dense_size(6 * 8.0 * n * n, f"a dense ({n}, {n}) generalized eigenproblem",
                     "use eigs(lap, k) for the k smallest pairs")
    Z = lap.component_basis().toarray()
    # eigenproblem on the complement of ker L, then prepend the exact kernel
    Lf, Bf = lap.L.toarray(), lap.B.toarray()
    evals, X = sla.eigh(Lf, Bf, driver="gvd")
    X = X[:, c:]
    X = X - Z @ (Z.T @ (Bf @ X))
    # re-orthonormalise in B after the projection (Cholesky of the Gram matrix)
    G = X.T @ Bf @ X
    R = np.linalg.cholesky((G + G.T) / 2)
    X = np.linalg.solve(R, X.T).T
    vals = np.concatenate([np.zeros(c), np.maximum(evals[c:], 0.0)])
    vecs = np.hstack([Z, X])
    return vals[:k], vecs[:, :k]


def cached_eigs(lap: Laplacian, k: int | None = None):
    """:func:`eigs` (``k`` pairs) or :func:`dense_eigs` (``k=None``: all of them), cached on ``lap``.

    ``k >= n - 1`` is answered densely too (Lanczos cannot give that many).
    """
    lap = as_laplacian(lap)
    if k is None or k >= lap.n - 1:
        return lap.cache.fetch("eigen", "dense" if k is None else k,
                               lambda: dense_eigs(lap, k if k is not None and k <= lap.n else None))
    return lap.cache.fetch("eigen", int(k), lambda: eigs(lap, int(k)))


def negative_inertia(lap: Laplacian, mu: float):
    r"""Number of eigenvalues of :math:`\tilde L` below ``mu``, by Sylvester's law of inertia.

    The number of negative pivots of an :math:`LDL^\top` factorization of :math:`L - \mu B`
    (the package's LDLᵀ where it is built, else SuperLU with diagonal pivots and a
    symmetric ordering). Returns ``None`` when no such factorization succeeds (a zero
    pivot, or off-diagonal pivoting).
    """
    return _inertia(as_laplacian(lap), mu)[0]


def lambda_min_positive(lap: Laplacian) -> float:
    r"""A lower bound of the smallest positive eigenvalue :math:`\lambda_{c+1}` of :math:`\tilde L`.

    Parameters
    ----------
    lap : Laplacian or mesh

    Returns
    -------
    float
        :math:`\mu \le \lambda_{c+1}`, with c the number of connected components; its kind is
        ``spectral_igl.linalg.lambda_min_positive_kind(lap)``.

    Notes
    -----
    An estimate :math:`\hat\lambda` comes from shift-invert Lanczos with ker L deflated
    (:func:`eigs`; dense for small n). It is then certified by spectrum slicing: for
    :math:`\mu = 0.999\hat\lambda` (lowered until it succeeds), an :math:`LDL^\top`
    factorization of :math:`L - \mu B` with exactly c negative pivots (c = number of
    connected components, the dimension of ker L) shows, by Sylvester's law of inertia,
    that exactly c eigenvalues lie below :math:`\mu`: the c zeros. Then
    :math:`\mu \le \lambda_{c+1}`. When no factorization confirms it, the Lanczos value
    lowered by 5% is returned and :func:`lambda_min_positive_kind` says ``"estimate"``.
    Cached on ``lap``. Needed by the singular filters and by every spectrum-free method,
    which approximate the filter on :math:`[\lambda_{c+1}, \lambda_{\max}]` once ker L is
    split off exactly.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ev, _ = sig.dense_eigs(lap, k=2)
    >>> lo = sig.lambda_min_positive(lap)
    >>> bool(0.99 * ev[1] < lo <= ev[1]), sig.linalg.lambda_min_positive_kind(lap)
    (True, 'proof')
    """
    return _lambda_min_positive(lap)[0]


def lambda_min_positive_kind(lap: Laplacian) -> str:
    """``"proof"`` when :func:`lambda_min_positive` was certified by inertia, else ``"estimate"``."""
    return _lambda_min_positive(lap)[1]


def _lambda_min_positive(lap):
    lap = as_laplacian(lap)

    def build():
        c = lap.n_components
        if lap.n - c <= 0:
            return lambda_max(lap), "proof"
        if lap.n <= 400:
            ev, _ = dense_eigs(lap, k=min(lap.n, c + 1))
        else:
            ev, _ = eigs(lap, c + 1)
        est = float(ev[c])
        if not est > 0:
            return 1e-300, "estimate"
        mu = 0.999 * est
        for _ in range(6):
            if negative_inertia(lap, mu) == c:
                return mu, "proof"
            mu *= 0.8
        return max(0.95 * est, 1e-300), "estimate"

    return lap.cache.fetch("bound", "lambda_min_positive", build)


#: inertia counts :func:`gap_lower_bound` takes below its first shift before it gives up
GAP_TRIALS = 3


def gap_lower_bound(lap: Laplacian, mu: float, any_bound: bool = False):
    r"""A proved lower bound of :math:`\lambda_{c+1}` of about ``mu``, from one inertia count,
    without the Lanczos run of :func:`lambda_min_positive`; or ``None``.

    When an :math:`LDL^\top` factorization of :math:`L - \mu B` has exactly c negative pivots
    (c = number of connected components), exactly c eigenvalues -- the zeros of ker L -- lie
    below :math:`\mu` (Sylvester's law of inertia), so :math:`\lambda_{c+1} \ge \mu` less the
    count's backward error. One factorization, about a sixth of a Cholesky factorization's
    cost on a 43k-vertex mesh, against several for :func:`lambda_min_positive`.

    Parameters
    ----------
    lap : Laplacian
    mu : float
        The bound wanted (> 0).
    any_bound : bool
        When the count at ``mu`` finds a positive eigenvalue below it, try shifts below a
        quarter of ``min(mu, Weyl's law for lambda_{c+1})``, 8 times lower each
        (:data:`GAP_TRIALS` of them), for any proved bound at all.

    Returns
    -------
    float or None
        The certified :func:`lambda_min_positive` when it is already cached (the best bound
        known), else the first shift the counts prove, else ``None``. Every value returned
        is a proof.
    """
    lap = as_laplacian(lap)
    mu = as_positive(mu, "mu")
    known = lap.cache.get("bound", "lambda_min_positive")
    if known is not None and known[1] == "proof":
        return known[0]
    if lap.n <= lap.n_components:
        return lambda_min_positive(lap)
    shifts = [mu]
    if any_bound:
        first = 0.25 * min(mu, _weyl(lap, 1))
        shifts += [first * 8.0 ** -i for i in range(GAP_TRIALS)]
    for sigma in shifts:
        got = lap.cache.fetch("bound", ("gap_lower_bound", sigma), lambda: _count_gap(lap, sigma))
        if got is not None:
            return got
    return None


def _count_gap(lap, sigma):
    """``sigma`` less the count's backward error when exactly c eigenvalues lie below it, else None."""
    count, backward = _inertia(lap, sigma)
    if count != lap.n_components or backward is None or not backward < sigma:
        return None
    return float(sigma - backward)


#: relative width to which :func:`eigenvalue_bracket` narrows its bracket by default
BRACKET_RTOL = 0.05

#: most inertia counts :func:`eigenvalue_bracket` takes before it reports an estimate
BRACKET_COUNTS = 16


def _weyl(lap, k: int) -> float:
    r"""Weyl's law for the k-th eigenvalue: :math:`4\pi k/A` on a surface,
    :math:`(6\pi^2 k/V)^{2/3}` on a solid."""
    if dimension(lap) == 3:
        return (6.0 * np.pi ** 2 * k / lap.area()) ** (2.0 / 3.0)
    return 4.0 * np.pi * k / lap.area()


def eigenvalue_bracket(lap: Laplacian, k: int, rtol: float = BRACKET_RTOL):
    r"""An interval :math:`[lo, hi]` holding :math:`\lambda_k`, the k-th smallest eigenvalue of
    :math:`\tilde L` (counted from 1, the zeros of ker L included), spectrum-free.

    Parameters
    ----------
    lap : Laplacian or mesh
    k : int
        Which eigenvalue, from 1 (the zeros of ker L included).
    rtol : float
        Relative width of the bracket (default :data:`BRACKET_RTOL`).

    Returns
    -------
    lo, hi : float
        :math:`lo \le \lambda_k \le hi`; for ``k >= n``, ``hi`` is the proved
        :func:`spectral_igl.lambda_max`.
    kind : str
        ``"proof"`` when every count that set an end succeeded, else ``"estimate"`` (the
        bracket then comes from Lanczos eigenvalues).

    Notes
    -----
    Spectrum slicing: the number of negative pivots of an :math:`LDL^\top` factorization of
    :math:`L - \sigma B` is the number :math:`N(\sigma)` of eigenvalues below :math:`\sigma`
    (Sylvester's law of inertia), so :math:`N(\sigma) < k` gives :math:`\lambda_k \ge \sigma`
    and :math:`N(\sigma) \ge k` gives :math:`\lambda_k < \sigma`. The first shift is Weyl's law
    (:math:`4\pi k / A` on a surface of area A), the next ones interpolate the counts as
    :math:`N \propto \sigma^{d/2}` between the two ends of the bracket, until
    :math:`hi \le (1 + rtol)\, lo`: a few factorizations, no eigenvector. Each end is moved
    outwards by the count's backward error (how far rounding in the factorization moves the
    pencil's eigenvalues). Cached on ``lap``.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> lo, hi, kind = sig.linalg.eigenvalue_bracket(lap, 50)
    >>> ev = sig.dense_eigs(lap, k=50)[0]
    >>> bool(lo <= ev[49] <= hi and hi <= 1.05 * lo), kind
    (True, 'proof')
    """
    lap = as_laplacian(lap)
    k = as_int(k, "k", lo=1)
    rtol = as_tol(rtol, "rtol")
    if k > lap.n:
        raise ValueError(f"k = {k} is more than the {lap.n} eigenvalues of this Laplacian")
    if k <= lap.n_components:
        return 0.0, 0.0, "proof"
    if k == lap.n:
        return lambda_min_positive(lap), lambda_max(lap), weakest(lambda_min_positive_kind(lap),
                                                                   lambda_max_kind(lap))
    return lap.cache.fetch("bound", ("eigenvalue_bracket", k, rtol), lambda: _bracket(lap, k, rtol))


def _bracket(lap, k, rtol):
    d = dimension(lap) or 2
    lo, n_lo, kind_lo = lambda_min_positive(lap), lap.n_components, lambda_min_positive_kind(lap)
    hi, n_hi, kind_hi = lambda_max(lap), lap.n, lambda_max_kind(lap)
    sigma = min(max(_weyl(lap, k), 1.01 * lo), 0.999 * hi)
    for _ in range(BRACKET_COUNTS):
        count, backward = _inertia(lap, sigma)
        if count is None or backward is None:
            sigma *= 1.0 + 1e-3           # a zero pivot: move off it
            continue
        if count >= k:
            hi, n_hi, kind_hi = min(hi, sigma + backward), count, "proof"
        else:
            lo, n_lo, kind_lo = max(lo, sigma - backward), count, "proof"
        if hi <= (1.0 + rtol) * lo:
            return lo, hi, "proof" if kind_lo == kind_hi == "proof" else "estimate"
        sigma = _next_shift(lo, n_lo, hi, n_hi, k, d)
    # no bracket within the budget: Lanczos values, said to be an estimate
    ev = cached_eigs(lap, k)[0]
    return 0.99 * float(ev[k - 1]), 1.01 * float(ev[k - 1]), "estimate"


def _next_shift(lo, n_lo, hi, n_hi, k, d):
    r"""The next shift: the power law :math:`N \propto \sigma^{d/2}` through the bracket's
    ends aimed at k - 1/2 eigenvalues, kept a tenth of the bracket inside it."""
    p = np.log(n_hi / n_lo) / np.log(hi / lo) if n_hi > n_lo else d / 2.0
    sigma = lo * ((k - 0.5) / n_lo) ** (1.0 / max(p, 1e-3))
    w = np.log(hi / lo)
    return float(np.clip(sigma, lo * np.exp(0.1 * w), hi * np.exp(-0.1 * w)))
