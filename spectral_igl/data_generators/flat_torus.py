"""The flat torus: a periodic grid with the flat metric, and its analytic spectrum."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._check import MAX_COUNT, count, real
from .surfaces import grid_faces

__all__ = ["flat_torus", "flat_torus_laplacian", "flat_torus_eigenvalues"]


def flat_torus(a: float = 1.0, b: float = 1.0, nu: int = 32, nv: int = 32):
    r"""Periodic triangulation of the rectangle :math:`[0,a]\times[0,b]` with opposite sides identified.

    The flat torus has no isometric smooth embedding in 3-D, so it is given intrinsically:
    connectivity and edge lengths of the flat metric (each grid cell split into two right
    triangles).

    Parameters
    ----------
    a, b : float
        Side lengths.
    nu, nv : int, >= 3
        Vertices along ``a`` and ``b``; vertex ``i * nv + j`` sits at ``(i a / nu, j b / nv)``.

    Returns
    -------
    F : (2 nu nv, 3) int
        Triangles (every vertex has valence 6, no boundary).
    l : (2 nu nv, 3) float
        Edge lengths, ``l[f, c]`` the edge opposite corner ``c`` (libigl's convention).
    """
    nu, nv = count(nu, "nu", 3, 10 ** 5), count(nv, "nv", 3, 10 ** 5)
    a, b = real(a, "a", positive=True), real(b, "b", positive=True)
    if nu * nv > MAX_COUNT:
        raise ValueError(f"nu * nv = {nu * nv} is more than {MAX_COUNT} vertices")
    if not (a > 0 and b > 0):
        raise ValueError(f"side lengths must be positive, got a={a}, b={b}")
    F = grid_faces(nu, nv, wrap_u=True, wrap_v=True)
    iu, iv = F // nv, F % nv

    def length(p, q):  # shortest periodic offset between corners p and q
        du = (iu[:, q] - iu[:, p] + nu // 2) % nu - nu // 2
        dv = (iv[:, q] - iv[:, p] + nv // 2) % nv - nv // 2
        return np.hypot(du * (a / nu), dv * (b / nv))

    l = np.stack([length(1, 2), length(2, 0), length(0, 1)], axis=1)
    return F, l


def flat_torus_laplacian(a: float = 1.0, b: float = 1.0, nu: int = 32, nv: int = 32):
    r"""Linear-FEM Laplacian of :func:`flat_torus`: intrinsic cotan stiffness, consistent mass.

    Returns a :class:`spectral_igl.Laplacian` with ``domain="triangle"`` and ``data``
    holding ``F`` and ``l`` (there are no vertex positions).
    """
    import igl

    from ..laplacian import make_laplacian

    F, l = flat_torus(a, b, nu, nv)
    n = int(nu) * int(nv)
    L = -igl.cotmatrix_intrinsic(l, F)
    area = np.full(len(F), a * b / (2.0 * n))
    rows = np.repeat(F.T, 3, axis=0).ravel()
    cols = np.tile(F.T, (3, 1)).ravel()
    vals = np.concatenate([area * ((2.0 if p == q else 1.0) / 12.0) for p in range(3) for q in range(3)])
    B = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    return make_laplacian(L, B, domain="triangle", data={"F": F, "l": l, "a": a, "b": b})


def flat_torus_eigenvalues(k: int, a: float = 1.0, b: float = 1.0) -> np.ndarray:
    r"""The ``k`` smallest Laplace--Beltrami eigenvalues of the flat torus, with multiplicity.

    .. math:: \lambda_{ij} = 4\pi^2\left(\frac{i^2}{a^2} + \frac{j^2}{b^2}\right),
              \qquad i, j \in \mathbb{Z}.
    """
    k = count(k, "k", 0, 10 ** 6)
    a, b = real(a, "a", positive=True, limit=1e6), real(b, "b", positive=True, limit=1e6)
    if max(a, b) / min(a, b) > 1e6:
        raise ValueError(f"the side ratio a/b = {a / b:g} is beyond 1e6")
    R = 1.0 / min(a, b)
    while True:  # all (i, j) with i²/a² + j²/b² <= R² lie in the box |i| <= R a, |j| <= R b
        i = np.arange(-int(R * a), int(R * a) + 1)[:, None]
        j = np.arange(-int(R * b), int(R * b) + 1)[None, :]
        q = (i ** 2 / a ** 2 + j ** 2 / b ** 2).ravel()
        q = np.sort(q[q <= R ** 2])
        if q.size >= k:
            return 4 * np.pi ** 2 * q[:k]
        R *= 2.0
