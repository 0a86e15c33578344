"""Perturbations of shapes: noise, irregular resampling, holes, point sampling, volumes."""
from __future__ import annotations

import numpy as np

__all__ = ["gaussian_noise", "normal_noise", "resample", "make_holes", "sample_points",
           "volume_from_surface", "vertex_normals", "mean_edge_length"]


def mean_edge_length(V, F) -> float:
    """Mean length of the (directed) edges of the faces."""
    V, F = np.asarray(V, float), np.asarray(F)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


def vertex_normals(V, F) -> np.ndarray:
    """(n, 3) area-weighted unit vertex normals (0 for unreferenced vertices)."""
    V, F = np.asarray(V, float), np.asarray(F)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    vn = np.zeros_like(V)
    for a in range(3):
        np.add.at(vn, F[:, a], N)
    nrm = np.linalg.norm(vn, axis=1, keepdims=True)
    return np.divide(vn, nrm, out=np.zeros_like(vn), where=nrm > 0)


def gaussian_noise(V, sigma: float, seed: int = 0) -> np.ndarray:
    """``V`` plus i.i.d. N(0, sigma²) noise in every coordinate (absolute units)."""
    V = np.asarray(V, float)
    return V + np.random.default_rng(seed).normal(0.0, sigma, V.shape)


def normal_noise(V, F, sigma: float, seed: int = 0) -> np.ndarray:
    """``V`` displaced along the vertex normals by N(0, sigma²) amounts (absolute units)."""
    V = np.asarray(V, float)
    t = np.random.default_rng(seed).normal(0.0, sigma, len(V))
    return V + t[:, None] * vertex_normals(V, F)


def resample(V, F, fraction: float = 0.5, seed: int = 0, project=None):
    """Irregular remeshing: split a random ``fraction`` of the faces at a random interior point.

    Each chosen face becomes three (1-to-3 split at random barycentric coordinates kept
    away from the edges), so valences, angles and sizes become irregular while the
    piecewise-linear surface is unchanged. ``project`` (optional) maps the new points
    onto the exact surface, e.g. ``lambda P: P / np.linalg.norm(P, axis=1, keepdims=True)``
    for the unit sphere. Returns ``(V, F)``.
    """
    V, F = np.asarray(V, float), np.asarray(F, dtype=np.int64)
    rng = np.random.default_rng(seed)
    pick = rng.random(len(F)) < fraction
    Fs = F[pick]
    w = rng.uniform(0.2, 1.0, (len(Fs), 3))
    w /= w.sum(axis=1, keepdims=True)
    C = np.einsum("mk,mki->mi", w, V[Fs])
    if project is not None:
        C = np.asarray(project(C), float)
    c = np.arange(len(V), len(V) + len(Fs))
    newF = np.vstack([F[~pick], np.c_[Fs[:, 0], Fs[:, 1], c], np.c_[Fs[:, 1], Fs[:, 2], c],
                      np.c_[Fs[:, 2], Fs[:, 0], c]])
    return np.vstack([V, C]), newF


def make_holes(V, F, n_holes: int = 3, radius: float | None = None, seed: int = 0):
    """Cut ``n_holes`` round holes: remove the faces within ``radius`` of random vertices.

    ``radius`` defaults to 4 mean edge lengths. Vertices no longer referenced are
    removed. Returns ``(V, F)`` with boundaries.
    """
    V, F = np.asarray(V, float), np.asarray(F, dtype=np.int64)
    rng = np.random.default_rng(seed)
    radius = 4 * mean_edge_length(V, F) if radius is None else float(radius)
    centres = V[rng.choice(np.unique(F), size=int(n_holes), replace=False)]
    cent = V[F].mean(axis=1)
    d = np.min(np.linalg.norm(cent[:, None, :] - centres[None], axis=2), axis=1)
    F = F[d > radius]
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def sample_points(V, F, n: int, density=None, seed: int = 0, project=None) -> np.ndarray:
    """``n`` random points on the triangle mesh ``(V, F)``.

    ``density=None`` samples uniformly by area. Otherwise ``density`` is a callable
    mapping ``(k, 3)`` points to positive relative densities (rejection sampling), or a
    number ``s > 0`` for the preset density ``1 + s (z - z_min)/(z_max - z_min)``.
    ``project`` (optional) maps the points onto the exact surface. Returns ``(n, 3)``.
    """
    V, F = np.asarray(V, float), np.asarray(F, dtype=np.int64)
    rng = np.random.default_rng(seed)
    A = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    cdf = np.cumsum(A) / A.sum()
    if density is not None and not callable(density):
        s = float(density)
        z0, z1 = V[:, 2].min(), V[:, 2].max()
        density = lambda P: 1 + s * (P[:, 2] - z0) / max(z1 - z0, 1e-300)  # noqa: E731
    out = []
    have = 0
    while have < n:
        m = 2 * n
        f = np.minimum(np.searchsorted(cdf, rng.random(m)), len(F) - 1)
        r1, r2 = rng.random(m), rng.random(m)
        s1 = np.sqrt(r1)
        P = ((1 - s1)[:, None] * V[F[f, 0]] + (s1 * (1 - r2))[:, None] * V[F[f, 1]]
             + (s1 * r2)[:, None] * V[F[f, 2]])
        if density is not None:
            d = np.asarray(density(P), float)
            P = P[rng.random(m) * d.max() < d]
        out.append(P)
        have += len(P)
    P = np.vstack(out)[:n]
    return np.asarray(project(P), float) if project is not None else P


def midpoint_subdivide(V, F, times: int = 1):
    """Split each triangle into four at its edge midpoints, ``times`` times.

    The piecewise-linear surface is unchanged (no smoothing), so linear FEM on the result
    converges to the spectrum of the surface ``(V, F)`` itself. Works on non-manifold and
    multi-component meshes. Returns ``(V, F)`` with the original vertices first.
    """
    V, F = np.asarray(V, float), np.asarray(F, dtype=np.int64)
    for _ in range(int(times)):
        E = np.sort(np.r_[F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1)
        u, inv = np.unique(E, axis=0, return_inverse=True)
        m = len(V) + inv.ravel().reshape(3, -1).T          # midpoint opposite each corner
        V = np.r_[V, 0.5 * (V[u[:, 0]] + V[u[:, 1]])]
        a, b, c = F.T
        ma, mb, mc = m.T
        F = np.r_[np.c_[a, mc, mb], np.c_[mc, b, ma], np.c_[mb, ma, c], np.c_[ma, mb, mc]]
    return V, F


def volume_from_surface(V, F, edge_length_fac: float = 0.05, **kwargs):
    """Tetrahedral mesh of the volume inside a closed surface (fTetWild). Returns ``(V, T)``."""
    from ..laplacian import tetrahedralize

    return tetrahedralize(V, F, edge_length_fac=edge_length_fac, **kwargs)
