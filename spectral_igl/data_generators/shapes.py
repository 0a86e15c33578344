"""Analytic shapes with known Laplacian spectra."""
from __future__ import annotations

import numpy as np

from ._check import count, real, triple

__all__ = ["icosphere", "sphere_eigenvalues", "box_tets", "box_eigenvalues"]


def _icosahedron():
    p = (1.0 + 5 ** 0.5) / 2.0
    V = np.array([[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0],
                  [0, -1, p], [0, 1, p], [0, -1, -p], [0, 1, -p],
                  [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], dtype=float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
                  [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
                  [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
                  [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)
    return V / np.linalg.norm(V, axis=1, keepdims=True), F


def icosphere(level: int = 3, radius: float = 1.0):
    """Icosphere: the icosahedron subdivided ``level`` times (1:4), projected to the sphere.

    ``n = 10 * 4**level + 2`` vertices. Returns ``(V, F)``, outward-oriented.
    """
    level = count(level, "level", 0, 9)
    radius = real(radius, "radius", positive=True)
    V, F = _icosahedron()
    for _ in range(level):
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uE, inv = np.unique(E, axis=0, return_inverse=True)
        inv = inv.ravel()
        mid = V[uE[:, 0]] + V[uE[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(F)
        e01, e12, e20 = (inv[k * m:(k + 1) * m] + len(V) for k in range(3))
        V = np.vstack([V, mid])
        F = np.vstack([np.c_[F[:, 0], e01, e20], np.c_[F[:, 1], e12, e01],
                       np.c_[F[:, 2], e20, e12], np.c_[e01, e12, e20]])
    return radius * V, F


def sphere_eigenvalues(k: int, radius: float = 1.0) -> np.ndarray:
    """First ``k`` Laplace--Beltrami eigenvalues of the sphere: l(l+1)/r², multiplicity 2l+1."""
    k = count(k, "k")
    radius = real(radius, "radius", positive=True)
    out, l = [], 0
    while len(out) < k:
        out += [l * (l + 1) / radius ** 2] * (2 * l + 1)
        l += 1
    return np.array(out[:k])


def box_tets(shape=(8, 6, 4), size=(1.0, 0.75, 0.5)):
    """Tetrahedral mesh of the box [0,a]×[0,b]×[0,c]: a grid of ``shape`` cubes, 6 tets each.

    The Kuhn subdivision is conforming across cubes. Returns ``(V, T)`` with positively
    oriented tetrahedra.
    """
    nx, ny, nz = triple(shape, "shape", "count")
    a, b, c = triple(size, "size", "length")
    x, y, z = np.meshgrid(np.linspace(0, a, nx + 1), np.linspace(0, b, ny + 1),
                          np.linspace(0, c, nz + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), z.ravel()]
    idx = np.arange(V.shape[0]).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = (g.ravel() for g in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    corner = lambda di, dj, dk: idx[i + di, j + dj, k + dk]  # noqa: E731
    v000, v111 = corner(0, 0, 0), corner(1, 1, 1)
    T = []
    # the 6 monotone lattice paths from (0,0,0) to (1,1,1)
    for p in ([0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]):
        step = np.zeros(3, dtype=int)
        verts = [v000]
        for axis in p[:2]:
            step[axis] = 1
            verts.append(corner(*step))
        verts.append(v111)
        T.append(np.stack(verts, axis=1))
    T = np.vstack(T).astype(np.int64)
    e1, e2, e3 = (V[T[:, q]] - V[T[:, 0]] for q in (1, 2, 3))
    neg = np.einsum("ij,ij->i", np.cross(e1, e2), e3) < 0
    T[neg] = T[neg][:, [0, 2, 1, 3]]
    return V, T


def box_eigenvalues(k: int, size=(1.0, 0.75, 0.5)) -> np.ndarray:
    """First ``k`` Neumann eigenvalues of the box: π²(i²/a² + j²/b² + l²/c²), i, j, l >= 0."""
    k = count(k, "k")
    a, b, c = triple(size, "size", "length")
    m = int(np.ceil(k ** (1 / 3))) + 6
    i, j, l = np.meshgrid(np.arange(m), np.arange(m), np.arange(m), indexing="ij")
    lam = np.pi ** 2 * (i ** 2 / a ** 2 + j ** 2 / b ** 2 + l ** 2 / c ** 2)
    return np.sort(lam.ravel())[:k]
