r"""Piecewise-linear calculus on the intrinsic Delaunay triangulation of a triangle mesh.

Per-triangle hat-function gradients laid out in each triangle's own plane, and from them
the gradient operator, the stiffness :math:`G^\top \mathrm{diag}(A, A)\, G` and the lumped
mass. The heat method's geodesics and the positive heat steps both build on them.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .intrinsic import edge_lengths, element_sum, intrinsic_delaunay
from .intrinsic import mollify as mollify_lengths

__all__ = ["frame_gradients", "triangle_gradients", "gradient_matrix", "hat_stiffness", "intrinsic_operators",
           "intrinsic_parts"]


def frame_gradients(l: np.ndarray):
    """(gx, gy) (m, 3) of the three hat functions and the areas (m,), in each triangle's frame."""
    l0, l1, l2 = l[:, 0], l[:, 1], l[:, 2]
    x = (l1 ** 2 + l2 ** 2 - l0 ** 2) / (2.0 * l2)
    y = np.sqrt(np.maximum(l1 ** 2 - x ** 2, 0.0))
    A = 0.5 * l2 * y
    with np.errstate(divide="ignore", invalid="ignore"):
        inv2A = np.where(A > 0, 1.0 / (2.0 * A), 0.0)
    # corners at (0, 0), (l2, 0), (x, y); grad of hat a is the edge b -> c turned by 90°
    # and divided by 2A: (-e_y, e_x) / 2A with e = P_c - P_b
    ex = np.stack([x - l2, -x, l2], axis=1)        # a = 0: P2 - P1, a = 1: P0 - P2, a = 2: P1 - P0
    ey = np.stack([y, -y, np.zeros_like(y)], axis=1)
    return -ey * inv2A[:, None], ex * inv2A[:, None], A


def triangle_gradients(l: np.ndarray, F: np.ndarray, n: int):
    """Gradient operator (2m, n) and areas (m,) of triangles given by edge lengths.

    ``l[f, i]`` is the length of the edge opposite corner ``i``. Each triangle is laid
    out in its own plane (corner 0 at the origin, corner 1 on the x axis); the gradient
    of a piecewise-linear function is expressed in that frame, which is all the heat
    method needs (it only normalises and integrates against the same operator).
    """
    gx, gy, A = frame_gradients(l)
    return gradient_matrix(gx, gy, F, n), A


def gradient_matrix(gx, gy, F, n):
    """(2m, n) sparse gradient from the per-face hat gradients ``gx, gy`` (m, 3) of faces ``F``."""
    # rows f (x) and m + f (y) hold the three corners of face f: CSR directly, no sorting
    m = len(F)
    cols = np.ascontiguousarray(np.r_[F, F], dtype=np.int32).ravel()
    return sp.csr_matrix((np.r_[gx, gy].ravel(), cols, np.arange(0, 6 * m + 1, 3, dtype=np.int32)),
                         shape=(2 * m, n))


def hat_stiffness(gx, gy, A, F, n):
    r""":math:`G^\top \mathrm{diag}(A, A) G` assembled per triangle, every diagonal entry stored.

    The six distinct entries of each element matrix are computed once and mirrored (exactly
    symmetric; column by column, five times faster than a broadcast outer product)."""
    W = np.empty((len(A), 3, 3))
    for a in range(3):
        for b in range(a, 3):
            W[:, a, b] = W[:, b, a] = (gx[:, a] * gx[:, b] + gy[:, a] * gy[:, b]) * A
    return element_sum(W, F, n)


def intrinsic_operators(V: np.ndarray, F: np.ndarray, mollify: float = 1e-6):
    r"""Gradient, areas, stiffness and lumped mass on the intrinsic Delaunay triangulation.

    Edge lengths are first mollified (Sharp and Crane 2020): every length grows by the
    smallest :math:`\delta` that gives each triangle inequality a margin of
    ``mollify`` times the mean edge length, so that needle and degenerate triangles
    get a well-defined geometry. The lengths are then flipped to the intrinsic
    Delaunay triangulation (:func:`spectral_igl.laplacian.intrinsic.intrinsic_delaunay`,
    compiled), where all cotangent weights are non-negative.

    Returns
    -------
    G : (2m, n) sparse
        Per-triangle gradient, x rows then y rows, in each triangle's own frame.
    A : (m,) float
        Triangle areas.
    L : (n, n) sparse csr
        Stiffness :math:`G^\top \mathrm{diag}(A, A)\, G`, positive semi-definite, in
        canonical form with every diagonal entry stored (zero at unreferenced vertices).
    M : (n, n) sparse diagonal
        Lumped (barycentric) mass: a third of the incident triangle areas.
    h : float
        Mean edge length of the intrinsic triangulation.
    """
    gx, gy, A, Fi, L, M, h = intrinsic_parts(V, F, mollify)
    return gradient_matrix(gx, gy, Fi, V.shape[0]), A, L, M, h


def intrinsic_parts(V, F, mollify):
    """(gx, gy, A, Fi, L, M, h): intrinsic_operators' results with the per-face hat gradients
    (gx, gy) (m, 3) and the flipped faces Fi in place of the assembled gradient."""
    n = V.shape[0]
    l, _ = mollify_lengths(edge_lengths(V, F), mollify)
    l, Fi = intrinsic_delaunay(l, F)
    gx, gy, A = frame_gradients(l)
    h = float(l.mean())
    L = hat_stiffness(gx, gy, A, Fi, n)
    mass = np.bincount(Fi.ravel(), weights=np.repeat(A / 3.0, 3), minlength=n)
    mass[mass <= 0] = float(mass[mass > 0].mean()) if np.any(mass > 0) else 1.0
    return gx, gy, A, Fi, L, sp.diags(mass).tocsr(), h
