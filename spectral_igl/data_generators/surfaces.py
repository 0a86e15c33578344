"""More analytic shapes: UV sphere, torus, open cylinder, voxel box, and their spectra."""
from __future__ import annotations

import numpy as np

from ._check import MAX_COUNT, count, real, triple

__all__ = ["uv_sphere", "torus", "cylinder", "cylinder_eigenvalues", "box_voxels",
           "box_voxel_eigenvalues", "sphere_points"]


def grid_faces(nu: int, nv: int, wrap_u: bool, wrap_v: bool) -> np.ndarray:
    """Two triangles per cell of an nu × nv vertex grid (index u * nv + v)."""
    cu = nu if wrap_u else nu - 1
    cv = nv if wrap_v else nv - 1
    i, j = np.meshgrid(np.arange(cu), np.arange(cv), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * nv + j
    b = ((i + 1) % nu) * nv + j
    c = ((i + 1) % nu) * nv + (j + 1) % nv
    d = i * nv + (j + 1) % nv
    return np.vstack([np.c_[a, b, c], np.c_[a, c, d]]).astype(np.int64)


def uv_sphere(n_lat: int = 32, n_lon: int = 64, radius: float = 1.0):
    """Latitude-longitude sphere: ``n_lat - 1`` rings of ``n_lon`` vertices plus two poles.

    Strongly anisotropic triangles near the poles (a harder test than the icosphere).
    Eigenvalues: :func:`spectral_igl.data_generators.sphere_eigenvalues`. Returns ``(V, F)``, outward.
    """
    n_lat, n_lon = count(n_lat, "n_lat", 2, 10 ** 5), count(n_lon, "n_lon", 3, 10 ** 5)
    radius = real(radius, "radius", positive=True)
    if n_lat * n_lon > MAX_COUNT:
        raise ValueError(f"n_lat * n_lon = {n_lat * n_lon} is more than {MAX_COUNT} vertices")
    if n_lat < 2 or n_lon < 3:
        raise ValueError(f"need n_lat >= 2 and n_lon >= 3, got {n_lat}, {n_lon}")
    th = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.c_[np.sin(T).ravel() * np.cos(P).ravel(), np.sin(T).ravel() * np.sin(P).ravel(),
                 np.cos(T).ravel()]
    V = np.vstack([ring, [[0, 0, 1]], [[0, 0, -1]]]) * radius
    r = n_lat - 1
    F = grid_faces(r, n_lon, wrap_u=False, wrap_v=True)
    F = F[:, [0, 2, 1]]
    north, south = r * n_lon, r * n_lon + 1
    j = np.arange(n_lon)
    top = np.c_[np.full(n_lon, north), j, (j + 1) % n_lon]
    bot = np.c_[np.full(n_lon, south), (r - 1) * n_lon + (j + 1) % n_lon, (r - 1) * n_lon + j]
    F = np.vstack([top, F, bot]).astype(np.int64)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    inward = np.einsum("ij,ij->i", N, V[F].mean(axis=1)) < 0
    F[inward] = F[inward][:, [0, 2, 1]]
    return V, F


def torus(R: float = 1.0, r: float = 0.4, n_major: int = 64, n_minor: int = 24):
    """Ring torus with major radius ``R`` and minor radius ``r`` (closed, genus 1).

    Its Laplace--Beltrami spectrum has no closed form; use it for properties (symmetry,
    PSD, genus) and refinement studies. Returns ``(V, F)``, outward.
    """
    n_major, n_minor = count(n_major, "n_major", 3, 10 ** 5), count(n_minor, "n_minor", 3, 10 ** 5)
    R, r = real(R, "R", positive=True), real(r, "r", positive=True)
    if n_major * n_minor > MAX_COUNT:
        raise ValueError(f"n_major * n_minor = {n_major * n_minor} is more than {MAX_COUNT} vertices")
    if n_major < 3 or n_minor < 3:
        raise ValueError(f"need n_major, n_minor >= 3, got {n_major}, {n_minor}")
    if not 0 < r < R:
        raise ValueError(f"need 0 < r < R, got R={R}, r={r}")
    u = np.linspace(0, 2 * np.pi, n_major, endpoint=False)
    v = np.linspace(0, 2 * np.pi, n_minor, endpoint=False)
    U, W = np.meshgrid(u, v, indexing="ij")
    rho = R + r * np.cos(W)
    V = np.c_[(rho * np.cos(U)).ravel(), (rho * np.sin(U)).ravel(), (r * np.sin(W)).ravel()]
    return V, grid_faces(n_major, n_minor, True, True)


def cylinder(radius: float = 1.0, height: float = 2.0, n_theta: int = 64, n_z: int = 32):
    """Open cylinder (no caps) of ``n_theta × (n_z + 1)`` vertices, axis along z.

    With the natural (Neumann) boundary condition at both rims its eigenvalues are
    :func:`cylinder_eigenvalues`. Returns ``(V, F)``.
    """
    n_theta, n_z = count(n_theta, "n_theta", 3, 10 ** 5), count(n_z, "n_z", 1, 10 ** 5)
    radius, height = real(radius, "radius", positive=True), real(height, "height", positive=True)
    if n_theta * (n_z + 1) > MAX_COUNT:
        raise ValueError(f"n_theta * (n_z + 1) = {n_theta * (n_z + 1)} is more than {MAX_COUNT} vertices")
    if n_theta < 3 or n_z < 1:
        raise ValueError(f"need n_theta >= 3 and n_z >= 1, got {n_theta}, {n_z}")
    th = np.linspace(0, 2 * np.pi, n_theta, endpoint=False)
    z = np.linspace(0, height, n_z + 1)
    T, Z = np.meshgrid(th, z, indexing="ij")
    V = np.c_[radius * np.cos(T).ravel(), radius * np.sin(T).ravel(), Z.ravel()]
    return V, grid_faces(n_theta, n_z + 1, wrap_u=True, wrap_v=False)


def cylinder_eigenvalues(k: int, radius: float = 1.0, height: float = 2.0) -> np.ndarray:
    """First ``k`` Neumann eigenvalues of the open cylinder: (m/r)² + (πl/h)², m ∈ ℤ, l ≥ 0."""
    k = count(k, "k", 0, 2000)     # the enumeration grid grows like k^2
    radius, height = real(radius, "radius", positive=True, limit=1e3), real(height, "height", positive=True, limit=1e3)
    M = int(np.ceil(radius * np.sqrt(k))) + 4 + k
    L = int(np.ceil(height * np.sqrt(k))) + 4 + k
    m = np.arange(-M, M + 1)
    l = np.arange(0, L + 1)
    lam = (m[:, None] / radius) ** 2 + (np.pi * l[None, :] / height) ** 2
    return np.sort(lam.ravel())[:k]


def box_voxels(shape=(16, 12, 8), size=(1.0, 0.75, 0.5)):
    """Voxel box [0,a]×[0,b]×[0,c] as a full boolean mask of ``shape`` voxels.

    Returns ``(mask, spacing)`` with ``spacing = size / shape`` (per axis).
    Eigenvalues: :func:`box_voxel_eigenvalues` (exact discrete) and
    :func:`spectral_igl.data_generators.box_eigenvalues` (continuous limit).
    """
    shape = triple(shape, "shape", "count")
    size = triple(size, "size", "length")
    spacing = np.asarray(size, dtype=float) / np.asarray(shape)
    return np.ones(shape, dtype=bool), spacing


def box_voxel_eigenvalues(k: int, shape=(16, 12, 8), size=(1.0, 0.75, 0.5)) -> np.ndarray:
    """Exact eigenvalues of the 7-point Neumann FD Laplacian on the voxel box.

    Per axis of N voxels of size h: (4/h²) sin²(π i / (2N)), i = 0..N-1; summed over axes.
    """
    k = count(k, "k")
    shape = triple(shape, "shape", "count")
    size = triple(size, "size", "length")
    h = np.asarray(size, dtype=float) / np.asarray(shape)
    axes = [4 / h[a] ** 2 * np.sin(np.pi * np.arange(shape[a]) / (2 * shape[a])) ** 2 for a in range(3)]
    lam = axes[0][:, None, None] + axes[1][None, :, None] + axes[2][None, None, :]
    return np.sort(lam.ravel())[: int(k)]


def sphere_points(n: int, seed: int = 0, nonuniform: float = 0.0, radius: float = 1.0) -> np.ndarray:
    """``n`` random points on the sphere.

    ``nonuniform = 0`` samples uniformly by area; ``nonuniform = s > 0`` samples with
    density proportional to ``1 + s (1 + z/r)`` (denser toward the north pole, max/min
    density ratio ``1 + 2s``). Returns ``(n, 3)``.
    """
    n = count(n, "n", 1)
    seed = count(seed, "seed", 0, 2 ** 63)
    nonuniform = real(nonuniform, "nonuniform", nonnegative=True, limit=1e6)
    radius = real(radius, "radius", positive=True)
    rng = np.random.default_rng(seed)
    out = np.zeros((0, 3))
    while len(out) < n:
        P = rng.standard_normal((2 * n, 3))
        P /= np.linalg.norm(P, axis=1, keepdims=True)
        if nonuniform > 0:
            dens = 1 + nonuniform * (1 + P[:, 2])
            P = P[rng.random(len(P)) * (1 + 2 * nonuniform) < dens]
        out = np.vstack([out, P])
    return radius * out[:n]


def quad_sphere(n: int = 16, radius: float = 1.0):
    """Cube-sphere quad mesh: each cube face an ``n × n`` grid, projected to the sphere.

    The grid is equi-angular (``tan`` spacing), so the quads are close to squares of
    similar size; faces are oriented outward. Returns ``V (6n² + 2, 3)`` and
    ``Q (6n², 4)`` int. Its Laplacian spectrum tends to the sphere's ``l(l + 1)/r²``.
    """
    s = np.tan(np.linspace(-np.pi / 4, np.pi / 4, n + 1))
    a, b = np.meshgrid(s, s, indexing="ij")
    one = np.ones_like(a)
    # (x, y, z) on each face with right-handed (a, b) so that a × b points outward
    faces = [(one, a, b), (-one, b, a), (b, one, a), (a, -one, b), (a, b, one), (b, a, -one)]
    pts, quads = [], []
    for f, (x, y, z) in enumerate(faces):
        P = np.stack([x, y, z], axis=-1).reshape(-1, 3)
        idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1) + f * (n + 1) ** 2
        q = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
        pts.append(P)
        quads.append(q)
    P = np.vstack(pts)
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    _, first, inv = np.unique(np.round(P, 12), axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    V = radius * P[first[order]]
    Q = rank[inv.ravel()][np.vstack(quads)]
    # orient outward: the normal of each quad's first corner against its centre
    X = V[Q]
    nrm = np.cross(X[:, 1] - X[:, 0], X[:, 3] - X[:, 0])
    flip = np.einsum("ij,ij->i", nrm, X.mean(axis=1)) < 0
    Q[flip] = Q[flip][:, ::-1]
    return V, Q
