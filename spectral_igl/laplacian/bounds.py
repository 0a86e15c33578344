r"""Proved bounds of the spectrum of :math:`\tilde L = B^{-1}L` from the matrices alone.

The largest eigenvalue is bounded by Gershgorin's theorem and the element mass ratio; the
smallest positive one needs a factorization and lives with the eigensolvers
(:func:`spectral_igl.linalg.lambda_min_positive`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._operator import Laplacian
from .inputs import as_laplacian

__all__ = ["mass_ratio", "lambda_max", "lambda_max_kind", "entry_error"]


def mass_ratio(lap: Laplacian) -> float:
    r"""A lower bound :math:`c \le \lambda_{\min}(D^{-1}B)`, D = diag(row sums of B).

    Parameters
    ----------
    lap : Laplacian

    Returns
    -------
    c : float
        In (0, 1]; the kind of the bound is :func:`lambda_max_kind`.

    Notes
    -----
    1 for a diagonal B. For the consistent linear-FEM mass of triangles (tets) every
    element matrix satisfies :math:`B_e \ge D_e/4` (:math:`D_e/5`), hence :math:`B \ge D/4`
    (:math:`D/5`): a proof, not an estimate. Any other B gets a Lanczos estimate of
    :math:`\lambda_{\min}(D^{-1/2} B D^{-1/2})` lowered by 10%.

    It enters :math:`\lambda_{\max}(B^{-1}L) \le \max_i (\sum_j |L_{ij}|) / (c\, D_{ii})` (Gershgorin)
    and every per-entry bound (:func:`entry_error`).

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.laplacian import mass_ratio
    >>> V, F = icosphere(1)
    >>> mass_ratio(sig.laplacian(V, F)), mass_ratio(sig.laplacian(V, F, mass="full"))
    (1.0, 0.25)
    """
    lap = as_laplacian(lap)

    def build():
        if lap.lumped:
            return 1.0
        if lap.domain in ("triangle", "tet") and lap.data.get("mass") == "full":
            return 0.25 if lap.domain == "triangle" else 0.2
        import scipy.sparse.linalg as spla

        d = 1.0 / np.sqrt(lap.mass)
        Bn = sp.diags(d) @ lap.B @ sp.diags(d)
        if lap.n <= 500:
            c = float(np.linalg.eigvalsh(Bn.toarray())[0])
        else:
            c = float(spla.eigsh(Bn, k=1, which="SA", tol=1e-6, return_eigenvectors=False)[0])
        c *= 0.9
        if not c > 0:
            raise ValueError("mass matrix B is not positive definite")
        return c

    return lap.cache.fetch("bound", "mass_ratio", build)


def lambda_max(lap: Laplacian) -> float:
    r"""Safe upper bound of the spectrum of :math:`\tilde L = B^{-1}L`, cached on ``lap``.

    :math:`\lambda_{\max}(L, B) \le \lambda_{\max}(L, D) / \lambda_{\min}(D^{-1}B)` with
    D = diag(row sums of B). The first factor is bounded by Gershgorin's theorem applied to
    :math:`D^{-1}L` (:math:`\max_i \sum_j |L_{ij}| / D_{ii}`), the second by
    :func:`mass_ratio` (exactly 1 for a lumped mass, 1/4 for the full linear-FEM mass of
    triangles, 1/5 for tets). Both are proofs for meshes built by
    :func:`spectral_igl.laplacian`; for other (L, B) pairs with a non-diagonal B the mass
    ratio is a Lanczos estimate with a 10% margin.

    Parameters
    ----------
    lap : Laplacian

    Returns
    -------
    float
        :math:`\lambda_{\max} \ge \max \operatorname{spec}(B^{-1}L)`.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ev, _ = sig.dense_eigs(lap)
    >>> bool(ev[-1] <= sig.lambda_max(lap))
    True
    """
    lap = as_laplacian(lap)

    def build():
        rowabs = np.asarray(abs(lap.L).sum(axis=1)).ravel()
        g = float(np.max(rowabs / lap.mass)) if lap.n else 0.0
        return max(g / mass_ratio(lap), 1e-300)

    return lap.cache.fetch("bound", "lambda_max", build)


def lambda_max_kind(lap: Laplacian) -> str:
    r"""Whether :func:`lambda_max` is a proof or an estimate.

    Parameters
    ----------
    lap : Laplacian

    Returns
    -------
    str
        ``"proof"`` when :func:`lambda_max` is a proved bound (a diagonal B, or the consistent
        linear-FEM mass of a triangle or tet mesh), ``"estimate"`` when its mass ratio is a
        Lanczos estimate (any other non-diagonal B).

    Notes
    -----
    :func:`lambda_max` is Gershgorin's bound over the mass ratio,
    :math:`\lambda_{\max}(B^{-1}L) \le \max_i \big(\sum_j |L_{ij}|\big) / (c\, D_{ii})`; it is a
    proof exactly when :math:`c` (:func:`mass_ratio`) is.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.laplacian import lambda_max_kind
    >>> lambda_max_kind(sig.laplacian(*icosphere(1), mass="full"))
    'proof'
    """
    lap = as_laplacian(lap)
    if lap.lumped or (lap.domain in ("triangle", "tet") and lap.data.get("mass") == "full"):
        return "proof"
    return "estimate"


def entry_error(lap: Laplacian, bnorm_error) -> np.ndarray:
    r"""Per-entry bound from a B-norm bound: :math:`|e_j| \le \|e\|_B / \sqrt{c\,D_{jj}}`.

    :math:`\|e\|_B^2 = e^\top B e \ge c\, e^\top D e \ge c\, D_{jj} e_j^2` with D the row sums
    of B and c = :func:`mass_ratio` (a proof where :func:`lambda_max_kind` says so).

    Parameters
    ----------
    lap : Laplacian
    bnorm_error : float or (m,) float
        Bounds of :math:`\|e\|_B` (one per column).

    Returns
    -------
    (n,) float for a scalar bound, (n, m) float for m bounds.

    Examples
    --------
    With a lumped mass, :math:`c = 1` and the bound is :math:`\|e\|_B / \sqrt{m_j}`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.laplacian import entry_error
    >>> lap = sig.laplacian(*icosphere(1))
    >>> bool(np.allclose(entry_error(lap, 1e-6), 1e-6 / np.sqrt(lap.mass)))
    True
    """
    lap = as_laplacian(lap)
    b = np.asarray(bnorm_error, dtype=float)
    w = 1.0 / np.sqrt(mass_ratio(lap) * lap.mass)
    # rounded up: the square root and the product are each within one unit in the last place
    w = w * (1.0 + 4.0 * np.finfo(float).eps)
    return w * b if b.ndim == 0 else w[:, None] * b[None, :]

