"""Perturbations of shapes: noise, irregular resampling, holes, point sampling, volumes."""
from __future__ import annotations

import numpy as np

__all__ = ["gaussian_noise", "normal_noise", "resample", "make_holes", "sample_points",
           "volume_from_surface", "vertex_normals", "mean_edge_length", "bend"]


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


def bend(V, angle: float = np.pi / 6, at: float = 0.6, band: float = 0.5):
    r"""A near-isometric bending: turn the part of a shape beyond a joint, blended smoothly.

    With :math:`a_1, a_2, a_3` the principal axes of the vertices (largest extent first,
    each signed so that its largest coordinate is positive) and s the coordinate along
    :math:`a_1`, the joint is at ``at`` of the range of s and
    a vertex turns by :math:`\theta\,w(s)` about the axis :math:`a_2` through the joint,

    .. math:: w(s) = \operatorname{smoothstep}\Big(\frac{s - s_j}{b\,(s_{max} - s_{min})}
              + \tfrac12\Big),\quad \theta = \text{angle},\ b = \text{band},

    the blend of two rigid motions as in linear blend skinning, in angle. Outside the
    band the map is rigid; inside, the strain along :math:`a_1` is
    :math:`\theta w'(s) z` at the distance z from the neutral plane (that of beam bending),
    so a wide band and a thin part bend with little stretch. Measure it on the edges:
    ``abs(|e'| - |e|) / |e|``.

    Parameters
    ----------
    V : (n, 3) float
    angle : float
        Radians.
    at : float
        Where along the principal axis the joint is, in (0, 1).
    band : float
        The width of the blend, as a fraction of the extent along the principal axis, > 0.

    Returns
    -------
    (n, 3) float

    Examples
    --------
    A thin cylinder (radius 0.1, length 2 along z) bent by 45 degrees: its top end swings
    by 0.6 sideways, its edges change length by 1.8 % on average (by 13 % at most, on the
    outside of the bend: :math:`\theta w' z = \tfrac{\pi}{4}\cdot 1.5 \cdot 0.1`).

    >>> import numpy as np
    >>> from spectral_igl.data_generators import cylinder
    >>> V, F = cylinder(0.1, 2.0, 16, 40)
    >>> W = bend(V, np.pi / 4)
    >>> E = np.r_[F[:, :2], F[:, 1:], F[:, ::2]]
    >>> l0, l1 = (np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1) for X in (V, W))
    >>> strain = abs(l1 - l0) / l0
    >>> round(float(strain.mean()), 3), round(float(strain.max()), 2), round(float(abs(W - V).max()), 2)
    (0.018, 0.13, 0.59)
    """
    V = np.asarray(V, float)
    c = V.mean(axis=0)
    axes = np.linalg.svd(V - c, full_matrices=False)[2]
    # each axis points to where its largest coordinate is positive (the SVD leaves the sign open)
    axes *= np.sign(axes[np.arange(3), np.argmax(np.abs(axes), axis=1)])[:, None]
    s = (V - c) @ axes[0]
    lo, hi = s.min(), s.max()
    joint = lo + float(at) * (hi - lo)
    x = np.clip((s - joint) / (float(band) * (hi - lo)) + 0.5, 0.0, 1.0)
    theta = float(angle) * x * x * (3 - 2 * x)
    p, k = c + joint * axes[0], axes[1]
    d = V - p
    cos, sin = np.cos(theta)[:, None], np.sin(theta)[:, None]
    # Rodrigues' rotation of each d about k by its own angle
    return p + d * cos + np.cross(k, d) * sin + np.outer(d @ k, k) * (1 - cos)
