"""Mean-curvature flow of triangle meshes: implicit, and conformalized (Kazhdan et al. 2012)."""
from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp

from .._validate import as_flag, as_positive, check_dense_size, describe
from ..laplacian.elements import cotan_stiffness, element_measures, full_mass
from ..laplacian.mesh import clean_mesh

__all__ = ["mean_curvature_flow"]


def _mass(V: np.ndarray, F: np.ndarray, mass: str) -> sp.csr_matrix:
    M = full_mass(V, F)
    if mass == "full":
        return M
    return sp.diags(np.asarray(M.sum(axis=1)).ravel()).tocsr()


def _centre_and_area(V: np.ndarray, F: np.ndarray):
    a = element_measures(V, F)
    c = (a[:, None] * V[F].mean(axis=1)).sum(axis=0) / a.sum()
    return c, float(a.sum())


def mean_curvature_flow(V, F, dt: float = 1e-3, steps: int = 10, conformal: bool = True,
                        mass: str = "lumped", normalize: bool = True, history: bool = False):
    r"""Implicit mean-curvature flow of a triangle mesh.

    Each step solves the backward-Euler system

    .. math:: (M_t + \delta\, L)\, X_{t+1} = M_t X_t

    for the vertex positions :math:`X` (n, 3), with :math:`M_t` the mass matrix of the
    current surface. ``conformal=False`` is the classical implicit flow (Desbrun et al.
    1999): :math:`L = L_t`, the cotangent stiffness of the current surface, which can
    pinch thin parts into degenerate triangles. ``conformal=True`` (default) is the
    conformalized flow of Kazhdan, Solomon & Ben-Chen 2012: the stiffness stays
    :math:`L = L_0`, that of the input mesh, and only the mass follows the surface; the
    flow is then conformal in the limit and, for genus-0 surfaces, tends to a round
    sphere without pinching. The survey (§5.2) places this flow among the diffusion
    equations :math:`\partial_t X = -\tilde L X`.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        Triangles (degenerate ones are dropped, as in ``laplacian``).
    dt : float
        Time step, relative to the initial surface area: :math:`\delta = dt \cdot A_0`
        (the flow is then independent of the scale of ``V``). > 0.
    steps : int
        Number of steps, >= 0.
    conformal : bool
        Conformalized (stiffness of the input) or classical (stiffness recomputed).
    mass : {"lumped", "full"}
        ``"lumped"``: barycentric vertex areas (a third of the incident triangles);
        ``"full"``: the consistent linear-FEM mass.
    normalize : bool
        After each step, translate the area-weighted centroid back to the input's and
        scale about it so that the surface area stays :math:`A_0` (Kazhdan et al.);
        without it the flow shrinks the surface.
    history : bool
        Return every step, not only the last.

    Returns
    -------
    X : (n, 3) float, or (steps + 1, n, 3) with ``history=True`` (``X[0]`` is ``V``).

    Notes
    -----
    One sparse factorization per step (:math:`M_t + \delta L` changes with :math:`M_t`).
    Vertices that no triangle references do not move.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere, gaussian_noise
    >>> V, F = icosphere(3)
    >>> X = sig.mean_curvature_flow(gaussian_noise(V, 0.02, seed=0), F, steps=5)
    >>> r = np.linalg.norm(X - X.mean(0), axis=1)
    >>> bool(r.std() / r.mean() < 0.01)
    True
    """
    import scipy.sparse.linalg as spla

    if np.ndim(F) != 2 or np.shape(F)[1] != 3:
        raise ValueError(f"mean_curvature_flow needs triangles F of shape (m, 3), got {describe(F)}")
    V, F, _ = clean_mesh(V, F)
    if V.shape[1] != 3:
        raise ValueError(f"mean_curvature_flow needs a 3-D triangle mesh, got V {V.shape}, F {F.shape}")
    dt = as_positive(dt, "dt")
    conformal, normalize = as_flag(conformal, "conformal"), as_flag(normalize, "normalize")
    history = as_flag(history, "history")
    if dt > 1.0:
        raise ValueError(f"dt must be at most 1 (it is relative to the initial area), got {dt}")
    if isinstance(steps, bool) or not isinstance(steps, (numbers.Integral, np.integer)) or not 0 <= steps <= 10000:
        raise ValueError(f"steps must be an integer in [0, 10000], got {describe(steps)}")
    if history:
        check_dense_size(8.0 * 3 * V.shape[0] * (steps + 1), f"the history of {steps} steps",
                         "use history=False or fewer steps")
    if mass not in ("lumped", "full"):
        raise ValueError(f"mass must be 'lumped' or 'full', got {mass!r}")
    n = V.shape[0]
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    c0, A0 = _centre_and_area(V, F)
    delta = dt * A0
    L0 = cotan_stiffness(V, F)
    X = V.copy()
    out = [X.copy()] if history else None
    for _ in range(int(steps)):
        M = _mass(X, F, mass)
        L = L0 if conformal else cotan_stiffness(X, F)
        A = (M + delta * L).tocsc()
        # unreferenced vertices have empty rows: pin them
        if not used.all():
            A = (A + sp.diags(np.where(used, 0.0, 1.0))).tocsc()
        rhs = M @ X
        rhs[~used] = X[~used]
        try:
            Xn = spla.splu(A).solve(rhs)
        except RuntimeError as err:      # a pinched surface: zero-area triangles, singular system
            raise FloatingPointError(f"mean-curvature flow hit a singular system ({err}): the "
                                     "surface has pinched; use conformal=True or a smaller dt") from err
        if not np.all(np.isfinite(Xn)):
            raise FloatingPointError("mean-curvature flow produced non-finite positions; "
                                     "use a smaller dt or conformal=True")
        if normalize:
            c, a = _centre_and_area(Xn, F)
            s = np.sqrt(A0 / a)
            Xn[used] = c0 + s * (Xn[used] - c)
        X = Xn
        if history:
            out.append(X.copy())
    return np.stack(out) if history else X
