r"""Shape correspondence by functional maps: descriptors, the map, refinement, evaluation.

A point-to-point map between two shapes :math:`M_1` (source) and :math:`M_2` (target) is
found through a *functional map* (Ovsjanikov et al. 2012): the matrix
:math:`C \in \mathbb{R}^{k_2 \times k_1}` that carries the coefficients of a function on
:math:`M_1` in its first :math:`k_1` eigenfunctions :math:`\Phi_1` (``L x = \lambda B x``,
:math:`\Phi^\top B \Phi = I`) to those of its image on :math:`M_2`. The steps:

1. descriptors that should agree at corresponding points: WKS/HKS on grids taken from each
   shape's spectrum (:func:`pair_descriptors`), heat kernels of a few matched landmarks at
   every scale (:func:`landmark_descriptors`), both spectrum-free and certified;
2. :func:`functional_map`: least squares with descriptor preservation, commutativity with
   the Laplacians and, optionally, with the descriptors' multiplication operators;
3. :func:`point_map`: the vertex of :math:`M_1` each vertex of :math:`M_2` comes from;
4. :func:`zoomout` (Melzi et al. 2019): the map refined by alternating point map and
   functional map in a growing basis;
5. :func:`map_error`: the mean geodesic error against a known map, divided by
   :math:`\sqrt{\operatorname{area}(M_1)}`.

:func:`match_shapes` runs the whole chain in one call. The eigenpairs are
:func:`spectral_igl.eigs`'s, certified; the solvers are small dense problems in the
reduced basis.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._validate import as_array, as_choice, as_int, as_nonnegative, check_dense_size, describe
from ..descriptors import hks, hks_times, wks, wks_energies
from ..kernels import heat_kernels
from ..laplacian import as_laplacian, make_laplacian
from ..laplacian.intrinsic import edge_lengths
from ..laplacian.intrinsic_fem import frame_gradients
from ..laplacian.units import dimension
from ..linalg import eigs

__all__ = ["pair_descriptors", "landmark_descriptors", "functional_map", "point_map", "zoomout",
           "map_error", "match_shapes", "orientation_operators", "Correspondence", "DESCRIPTORS", "GRIDS",
           "LAPLACIAN_MASKS"]

#: descriptor kinds :func:`pair_descriptors` computes
DESCRIPTORS = ("wks", "hks")

#: where the scales of :func:`pair_descriptors` come from: each shape's own spectrum, or one
#: grid over the union of both bands
GRIDS = ("own", "common")

#: how :func:`functional_map` penalises the entries of C that do not commute with the Laplacians
LAPLACIAN_MASKS = ("resolvent", "squared")

#: default weight of orientation preservation in :func:`functional_map` (triangle meshes)
ORIENTATION_WEIGHT = 3e-2

#: exponent gamma of the resolvent mask (Ren et al. 2019's choice)
RESOLVENT_GAMMA = 0.5


# ----------------------------------------------------------------------------- validation

def _basis(basis, n, name):
    """``(evals, evecs)`` of one shape, checked against its vertex count (any when n is None)."""
    if not isinstance(basis, (tuple, list)) or len(basis) != 2:
        raise TypeError(f"{name} must be a pair (evals, evecs) as returned by spectral_igl.eigs, "
                        f"got {describe(basis)}")
    evals, evecs = (np.asarray(a, dtype=float) for a in basis)
    n = evecs.shape[0] if n is None and evecs.ndim == 2 else n
    if evals.ndim != 1 or evecs.ndim != 2 or evecs.shape != (n, evals.size):
        raise ValueError(f"{name} must be (evals (k,), evecs ({n}, k)), got shapes "
                         f"{evals.shape} and {evecs.shape}")
    return evals, evecs


def _descriptor(D, n, name):
    D = as_array(D, name)
    if D.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be real numbers, got {describe(D)}")
    D = D.astype(float)
    if D.ndim == 1:
        D = D[:, None]
    if D.ndim != 2 or D.shape[0] != n or D.shape[1] == 0 or not np.all(np.isfinite(D)):
        raise ValueError(f"{name} must be finite, of shape ({n},) or ({n}, p) with p >= 1, "
                         f"got {describe(D)}")
    return D


def _map(p2p, n_to, n_from, name):
    """A point map: ``n_from`` indices (any number when None) into a shape of ``n_to`` vertices."""
    p = as_array(p2p, name)
    if p.dtype.kind not in "iu":
        raise TypeError(f"{name} must be integer vertex indices, got {describe(p2p)}")
    n_from = p.shape[0] if n_from is None and p.ndim == 1 else n_from
    if p.shape != (n_from,):
        raise ValueError(f"{name} must have shape ({n_from},), got {p.shape}")
    if p.size and (p.min() < 0 or p.max() >= n_to):
        raise ValueError(f"{name} must index vertices 0..{n_to - 1}, got values in "
                         f"[{p.min()}, {p.max()}]")
    return p.astype(np.int64)


# ----------------------------------------------------------------------------- descriptors

def normalize_columns(lap, D):
    r"""Each column of ``D`` divided by its root mean square :math:`\sqrt{d^\top B d / |M|}`
    (zero columns kept): unit B-norm on the shape scaled to unit area, so that a shape and its
    scaled copy get the same columns."""
    norms = np.sqrt(np.einsum("ij,ij->j", D, lap.B @ D) / lap.area())
    return D / np.where(norms > 0, norms, 1.0)


def _grids(lap1, lap2, kind, n, k, grid):
    """The scales of each shape: its own (hks_times / wks_energies), or one grid from the
    smallest to the largest of the two."""
    if kind == "hks":
        own = [(hks_times(lap, n, k), None) for lap in (lap1, lap2)]
        if grid == "common":
            t = np.geomspace(min(g[0][0] for g in own), max(g[0][-1] for g in own), n)
            own = [(t, None)] * 2
        return own
    own = [wks_energies(lap, n, k) for lap in (lap1, lap2)]
    if grid == "common":
        e = np.linspace(min(g[0][0] for g in own), max(g[0][-1] for g in own), n)
        own = [(e, max(g[1] for g in own))] * 2
    return own


def pair_descriptors(lap1, lap2, kind: str = "wks", n: int = 100, k: int = 200,
                     grid: str = "own", method: str = "auto"):
    r"""WKS or HKS of two shapes to be matched, column ``j`` of one to column ``j`` of the other.

    Parameters
    ----------
    lap1, lap2 : Laplacian or (V, F)
    kind : {"wks", "hks"}
    n : int
        Number of energies (WKS) or times (HKS).
    k : int
        The grids span the band of the first ``k`` eigenvalues (:func:`spectral_igl.spectral_band`,
        spectrum-free: a few inertia counts).
    grid : {"own", "common"}
        ``"own"``: each shape's grid from its own band (:func:`spectral_igl.wks_energies`,
        :func:`spectral_igl.hks_times`), so that column j is the same *relative* scale on both
        (the grids are scale-covariant); ``"common"``: one grid over the union of the two bands,
        the same absolute scale on both (from the smallest to the largest of the two own grids).
    method : str
        The kernel-diagonal method of :func:`spectral_igl.wks` / :func:`spectral_igl.hks`
        (``"auto"``: spectrum-free, certified).

    Returns
    -------
    D1 : (n1, n) float
    D2 : (n2, n) float
        Every column normalised to unit root mean square on its shape
        (:math:`d^\top B d = |M|`).

    Notes
    -----
    WKS at energy :math:`e` with width :math:`\sigma`:
    :math:`\mathrm{WKS}(x, e) = \sum_l e^{-(e - \log\lambda_l)^2/2\sigma^2} \phi_l(x)^2 /
    \sum_l e^{-(e - \log\lambda_l)^2/2\sigma^2}`; HKS at time t:
    :math:`K_t(x, x) = \sum_l e^{-t\lambda_l}\phi_l(x)^2`. Both are evaluated from the diagonal
    of a kernel, without eigenpairs. Measured (``benchmarks/correspondence.py``): the own grid
    gave 0.15 (WKS) and 0.25 (HKS) against 0.56 and 0.55 for the common grid on a stretched
    pair scaled by 1.5.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> D1, D2 = sig.pair_descriptors((V, F), (2 * V, F), n=8, k=30)
    >>> bool(abs(D1 - D2).max() < 1e-6)   # the own grids follow the scale
    True
    """
    lap1, lap2 = as_laplacian(lap1, "lap1"), as_laplacian(lap2, "lap2")
    kind = as_choice(kind, "kind", DESCRIPTORS)
    grid = as_choice(grid, "grid", GRIDS)
    n, k = as_int(n, "n", lo=1, hi=1000), as_int(k, "k", lo=2)
    out = []
    for lap, (scales, sigma) in zip((lap1, lap2), _grids(lap1, lap2, kind, n, k, grid)):
        D = hks(lap, scales, method=method) if kind == "hks" else wks(lap, scales, sigma, method=method)
        out.append(normalize_columns(lap, D.reshape(lap.n, -1)))
    return out[0], out[1]


def landmark_descriptors(lap, landmarks, times=None, n_times: int = 16, k: int = 200,
                         tol: float = 1e-8):
    r"""Heat kernels of a few landmarks at many times: :math:`K_t(x, l)` for every vertex x.

    Parameters
    ----------
    lap : Laplacian or (V, F)
    landmarks : (m,) int
        Vertices matched across the shapes (the same order on both).
    times : (T,) float, optional
        Absolute times; default ``hks_times(lap, n_times, k)`` (each shape its own grid,
        scale-covariant).
    n_times : int
        Number of default times.
    k : int
        Band of the default times (:func:`spectral_igl.hks_times`).
    tol : float
        Certified B-norm error of every column relative to :math:`\|B^{-1}e_l\|_B`
        (:func:`spectral_igl.heat_kernels`).

    Returns
    -------
    D : (n, m * T) float
        Column ``i * T + j`` is landmark i at time j, normalised to unit root mean square
        (:math:`d^\top B d = |M|`).

    Notes
    -----
    .. math:: K_t(:, l) = e^{-t\tilde L} B^{-1} e_l = \sum_l e^{-t\lambda_i} \phi_i(l)\,\phi_i

    All m x T columns come from one sparse factorization per pole of a rational approximation
    shared by every time (:func:`spectral_igl.heat_kernels`), with all landmarks as one block
    right-hand side: the small times, where an eigenbasis truncated at a few hundred pairs
    rings and smears the kernel over the shape, cost nothing extra and are certified.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.landmark_descriptors(lap, [0, 5], n_times=3, k=30)
    >>> D.shape, bool(np.allclose(np.einsum("ij,ij->j", D, lap.B @ D), lap.area()))
    ((162, 6), True)
    """
    lap = as_laplacian(lap)
    idx = np.atleast_1d(as_array(landmarks, "landmarks"))
    if idx.dtype.kind not in "iu" or idx.ndim != 1 or idx.size == 0:
        raise ValueError(f"landmarks must be a non-empty 1-D array of vertex indices, got {describe(landmarks)}")
    if idx.min() < 0 or idx.max() >= lap.n:
        raise ValueError(f"landmarks must index vertices 0..{lap.n - 1}, got values in [{idx.min()}, {idx.max()}]")
    if times is None:
        times = hks_times(lap, as_int(n_times, "n_times", lo=1, hi=1000), k)
    K = heat_kernels(lap, times, idx.astype(np.int64), tol=tol)           # (n, m, T)
    K = K.reshape(lap.n, idx.size, -1).reshape(lap.n, -1)
    return normalize_columns(lap, K)


# ----------------------------------------------------------------------------- the map

def unit_measure(lap):
    r"""The same shape scaled to unit area (unit volume for solids): :math:`\tilde B = B/A`,
    :math:`\tilde L = A^{2/d - 1} L` (:math:`A = \mathbf 1^\top B \mathbf 1`, d the dimension),
    so that :math:`\tilde B^{-1}\tilde L = A^{2/d} B^{-1} L`; ``lap`` itself when A is 1.

    Functional maps compare eigenvectors of two shapes row by row; B-orthonormal eigenvectors
    scale as :math:`A^{-1/2}`, so shapes of different sizes are matched at unit measure.
    """
    A = lap.area()
    if np.isclose(A, 1.0, rtol=1e-12, atol=0.0):
        return lap
    d = dimension(lap) or 2           # a graph: the mass normalised, L kept
    data = dict(lap.data)
    for key in ("V", "P"):
        if key in data and data[key] is not None:
            data[key] = np.asarray(data[key], dtype=float) / A ** (1.0 / d)
    return make_laplacian(lap.L * A ** (2.0 / d - 1.0), lap.B / A, domain=lap.domain, data=data)


def _scale(values):
    """A term's normaliser: the mean of ``values``, 1 if it is zero."""
    s = float(np.mean(values))
    return s if s > 0 else 1.0


def _laplacian_mask(ev1, ev2, kind: str = "resolvent"):
    r"""The weights :math:`M_{ij}` of the Laplacian commutativity term of a ``(k2, k1)`` map.

    Parameters
    ----------
    ev1, ev2 : (k1,), (k2,) float
        Eigenvalues of source and target at the same measure (e.g. both at unit area).
    kind : {"resolvent", "squared"}
        ``"squared"``: :math:`(\lambda^{(1)}_j - \lambda^{(2)}_i)^2`, the commutator
        :math:`\|C\Lambda_1 - \Lambda_2 C\|^2`; ``"resolvent"`` (Ren et al. 2019):
        :math:`|R(\lambda^{(1)}_j) - R(\lambda^{(2)}_i)|^2` with
        :math:`R(\lambda) = (\tilde\lambda^{\gamma} - \mathrm i)^{-1}`,
        :math:`\tilde\lambda = \lambda / \max(\lambda^{(1)}, \lambda^{(2)})`,
        :math:`\gamma = 1/2`: the commutator with the resolvent of each Laplacian, bounded by 4.

    Returns
    -------
    M : (k2, k1) float

    Notes
    -----
    Both masks vanish on equal eigenvalues. The squared difference grows as
    :math:`\lambda^2`, so that the last rows and columns of C carry nearly all of the
    term and the low-frequency block, which decides the map, is barely constrained; the
    resolvent grows as :math:`\lambda^{\gamma}` near zero and saturates, weighing the
    whole band alike.

    Examples
    --------
    >>> import numpy as np
    >>> M = _laplacian_mask(np.array([0.0, 1.0, 4.0]), np.array([0.0, 1.0, 4.0]))
    >>> bool(np.allclose(np.diag(M), 0.0)), bool(M.max() <= 4.0)
    (True, True)
    """
    kind = as_choice(kind, "laplacian_mask", LAPLACIAN_MASKS)
    ev1, ev2 = np.abs(np.asarray(ev1, dtype=float)), np.abs(np.asarray(ev2, dtype=float))
    if kind == "squared":
        return np.square(ev1[None, :] - ev2[:, None])
    top = max(float(ev1.max(initial=0.0)), float(ev2.max(initial=0.0)))
    r1, r2 = ((ev / (top if top > 0 else 1.0)) ** RESOLVENT_GAMMA for ev in (ev1, ev2))
    return np.square(np.abs(1.0 / (r1[None, :] - 1j) - 1.0 / (r2[:, None] - 1j)))


def _multiplication_operators(lap, evecs, D):
    r""":math:`\Phi^\top B\, \mathrm{diag}(d)\, \Phi` for every column d of D: (p, k, k)."""
    BX = lap.B @ evecs
    return np.einsum("ni,np,nj->pij", BX, D, evecs, optimize=True)


def orientation_operators(lap, evecs, D):
    r"""The orientation operators of the columns of ``D`` in the basis ``evecs``: (p, k, k).

    Parameters
    ----------
    lap : Laplacian
        A triangle mesh (its ``data["V"]``, ``data["F"]``); the faces' corner order is the
        orientation.
    evecs : (n, k) float
    D : (n, p) float

    Returns
    -------
    O : (p, k, k) float
        :math:`O_q[i, j] = \int \phi_i\, \langle \nabla d_q \times \nabla \phi_j, n\rangle\, dA`.

    Notes
    -----
    Ren et al. 2018: the operator :math:`g \mapsto \langle\nabla f\times\nabla g, n\rangle`
    commutes with a map that preserves orientation and anticommutes with one that reverses it.
    The hat-function gradients are laid out in each triangle's own plane (corner 0 at the
    origin, corner 1 on the x axis, corner 2 above it: :func:`frame_gradients`), where
    :math:`\langle a \times b, n\rangle = a_x b_y - a_y b_x` with n the normal of the corner
    order; the integrand is constant on each triangle, and :math:`\int_t \phi_i = |t|` times
    the mean of :math:`\phi_i` at its corners.
    """
    V, F = np.asarray(lap.data["V"], dtype=float), np.asarray(lap.data["F"], dtype=np.int64)
    gx, gy, area = frame_gradients(edge_lengths(V, F))
    Xf, Df = evecs[F], D[F]                                           # (m, 3, k), (m, 3, p)
    Gx, Gy = np.einsum("ma,mak->mk", gx, Xf), np.einsum("ma,mak->mk", gy, Xf)
    Dx, Dy = np.einsum("ma,map->mp", gx, Df), np.einsum("ma,map->mp", gy, Df)
    S = Xf.mean(axis=1) * area[:, None]                                # (m, k): int_t phi_i
    return np.stack([S.T @ (Dx[:, q, None] * Gy - Dy[:, q, None] * Gx) for q in range(D.shape[1])])


def _commutator_normal(P1, P2):
    r"""Normal matrix of :math:`\sum_q \|C P_{1,q} - P_{2,q} C\|_F^2` in row-major vec(C).

    :math:`\operatorname{vec}(CP) = (I\otimes P^\top)\operatorname{vec}(C)`,
    :math:`\operatorname{vec}(PC) = (P\otimes I)\operatorname{vec}(C)`; the operators need
    not be symmetric."""
    k1, k2 = P1.shape[1], P2.shape[1]
    N = np.kron(np.eye(k2), np.einsum("pij,pkj->ik", P1, P1))
    N += np.kron(np.einsum("pji,pjk->ik", P2, P2), np.eye(k1))
    cross = np.tensordot(P2, P1, axes=(0, 0)).transpose(1, 3, 0, 2).reshape(k1 * k2, k1 * k2)  # sum P2^T (x) P1^T
    return N - cross - cross.T


def functional_map(lap1, lap2, desc1, desc2, basis1, basis2, laplacian_weight: float = 1e-1,
                   commutativity_weight: float = 1e-2, laplacian_mask: str = "resolvent",
                   orientation_weight: float | None = None):
    r"""The functional map :math:`C` (``k2 x k1``) that best carries the descriptors of shape 1
    onto those of shape 2 and commutes with the Laplacians.

    Parameters
    ----------
    lap1, lap2 : Laplacian or (V, F)
        Source and target.
    desc1, desc2 : (n1, p), (n2, p) float
        Descriptors, column j of one corresponding to column j of the other.
    basis1, basis2 : (evals, evecs)
        B-orthonormal eigenpairs of each shape (:func:`spectral_igl.eigs`); their number sets
        the size of C.
    laplacian_weight : float
        Weight :math:`\mu_L` of the Laplacian commutativity term.
    commutativity_weight : float
        Weight :math:`\mu_D` of descriptor commutativity (0: not used; with no orientation
        term either, the problem then splits into one small solve per row of C).
    laplacian_mask : {"resolvent", "squared"}
        The weights M of the Laplacian commutativity (:func:`_laplacian_mask`).
    orientation_weight : float, optional
        Weight :math:`\mu_O` of orientation preservation (Ren et al. 2018,
        :func:`orientation_operators`); 0: not used. It needs two triangle meshes: the default
        is ``ORIENTATION_WEIGHT`` on them and 0 on other domains (point clouds, which carry no
        orientation); a positive weight given for them is ignored with a warning.

    Returns
    -------
    C : (k2, k1) float

    Notes
    -----
    With :math:`A = \Phi_1^\top B_1 D_1` and :math:`\hat B = \Phi_2^\top B_2 D_2` the
    descriptors' coefficients, :math:`M` the mask of the eigenvalues times the areas
    (invariant to scale; :func:`_laplacian_mask`, :math:`M_{ij} = (|M_1|\lambda^{(1)}_j -
    |M_2|\lambda^{(2)}_i)^2` for ``"squared"``) and
    :math:`P^{(s)}_q = \Phi_s^\top B_s \operatorname{diag}(d^{(s)}_q)\Phi_s`, C minimises

    .. math:: \frac{\|CA - \hat B\|_F^2}{\tau_D}
              + \mu_L \frac{\|M^{1/2} \circ C\|_F^2}{\tau_L}
              + \mu_D \sum_q \frac{\|C P^{(1)}_q - P^{(2)}_q C\|_F^2}{\tau_P}
              + \mu_O \sum_q \frac{\|C O^{(1)}_q - O^{(2)}_q C\|_F^2}{\tau_O}

    (:math:`O^{(s)}_q` the orientation operators of the descriptors, :func:`orientation_operators`)
    where each :math:`\tau` is the mean of the data of its term (the entries of
    :math:`\hat B^2`, of M, of the :math:`P_q^2`), times the number p of descriptors for the
    terms that sum over them, so that the weights do not depend on the shapes' size or scale. The
    energy is a convex quadratic; its normal equations are solved directly: row by row when
    :math:`\mu_D = 0` (row i: :math:`c_i (AA^\top/\tau_D + \mu_L \operatorname{diag}(M_i)/\tau_L)
    = \hat b_i A^\top/\tau_D`), as one :math:`k_1k_2 \times k_1k_2` system otherwise
    (:math:`\sum_q I \otimes P^{(1)2}_q + P^{(2)2}_q \otimes I - 2 P^{(2)}_q \otimes P^{(1)}_q`
    for the commutativity, row-major). Without the commutativity term, WKS alone leaves the
    map of a shape with a reflective symmetry undecided between the map and its mirror image
    (measured: a map no better than random on a remeshed humanoid); with it, within 2x of the
    true map's error before refinement.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> basis = sig.eigs(lap, 4)
    >>> D = sig.landmark_descriptors(lap, [0, 40, 90], n_times=4, k=30)
    >>> C = sig.functional_map(lap, lap, D, D, basis, basis)
    >>> bool(np.allclose(C, np.eye(4), atol=1e-8))   # a shape onto itself: the identity
    True
    """
    lap1, lap2 = as_laplacian(lap1, "lap1"), as_laplacian(lap2, "lap2")
    ev1, X1 = _basis(basis1, lap1.n, "basis1")
    ev2, X2 = _basis(basis2, lap2.n, "basis2")
    D1, D2 = _descriptor(desc1, lap1.n, "desc1"), _descriptor(desc2, lap2.n, "desc2")
    if D1.shape[1] != D2.shape[1]:
        raise ValueError(f"desc1 and desc2 must have the same number of columns, got "
                         f"{D1.shape[1]} and {D2.shape[1]}")
    mu_l = as_nonnegative(laplacian_weight, "laplacian_weight")
    mu_d = as_nonnegative(commutativity_weight, "commutativity_weight")
    A, Bh = X1.T @ (lap1.B @ D1), X2.T @ (lap2.B @ D2)
    # eigenvalues times the area: the commutativity does not depend on the shapes' scales
    M = _laplacian_mask(lap1.area() * ev1, lap2.area() * ev2, laplacian_mask)
    p = D1.shape[1]
    w_d, w_l = 1.0 / (p * _scale(np.square(Bh))), mu_l / _scale(M)
    G, R = w_d * (A @ A.T), w_d * (Bh @ A.T)                      # (k1, k1), (k2, k1)
    rows = [G + np.diag(w_l * M[i]) for i in range(ev2.size)]
    C = np.stack([np.linalg.solve(Gi, r) for Gi, r in zip(rows, R)])
    meshes = lap1.domain == lap2.domain == "triangle"
    if orientation_weight is None:
        orientation_weight = ORIENTATION_WEIGHT if meshes else 0.0
    mu_o = as_nonnegative(orientation_weight, "orientation_weight")
    if mu_o > 0 and not meshes:
        warnings.warn(f"orientation_weight={mu_o:g} ignored: orientation preservation needs two "
                      f"triangle meshes, got {lap1.domain} and {lap2.domain} domains", stacklevel=2)
        mu_o = 0.0
    operators = []
    if mu_d > 0:
        operators.append((mu_d, _multiplication_operators(lap1, X1, D1), _multiplication_operators(lap2, X2, D2)))
    if mu_o > 0:
        operators.append((mu_o, orientation_operators(lap1, X1, D1), orientation_operators(lap2, X2, D2)))
    if not operators:
        return C
    k2, k1 = C.shape
    check_dense_size(8.0 * (k1 * k2) ** 2, f"the normal equations of a {k2} x {k1} map with "
                     "operator commutativity", "use fewer eigenpairs (refine with zoomout)")
    N = np.kron(np.eye(k2), G)
    N[np.diag_indices_from(N)] += w_l * M.ravel()
    for mu, P1, P2 in operators:
        N += mu / (p * _scale(np.square(np.concatenate([P1.ravel(), P2.ravel()])))) * _commutator_normal(P1, P2)
    return np.linalg.solve(N, R.ravel()).reshape(k2, k1)


def point_map(C, evecs1, evecs2):
    r"""The point map of a functional map: for each vertex y of shape 2, the vertex x of shape 1
    whose spectral embedding :math:`\Phi_1(x) C^\top` is nearest to :math:`\Phi_2(y)`.

    Parameters
    ----------
    C : (k2, k1) float
    evecs1 : (n1, >= k1) float
    evecs2 : (n2, >= k2) float
        Only the first k1 (k2) columns are used.

    Returns
    -------
    p2p : (n2,) int
        ``p2p[y]`` is the vertex of shape 1 matched to vertex y of shape 2.

    Notes
    -----
    A point map :math:`T: M_2 \to M_1` pulls functions back, :math:`f \mapsto f\circ T`; in
    the bases it is :math:`C = \Phi_2^\top B_2 \Pi \Phi_1` with :math:`\Pi_{y, T(y)} = 1`,
    and :math:`\Pi\Phi_1 C^\top \approx \Phi_2 C C^\top \approx \Phi_2` for a near-isometry
    (C nearly orthogonal). The nearest neighbours are found exactly (:func:`nearest`).

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> X = np.random.default_rng(0).normal(size=(50, 4))
    >>> perm = np.random.default_rng(1).permutation(50)
    >>> bool(np.all(sig.point_map(np.eye(4), X, X[perm]) == perm))
    True
    """
    C = np.asarray(C, dtype=float)
    if C.ndim != 2:
        raise ValueError(f"C must be a (k2, k1) matrix, got shape {C.shape}")
    k2, k1 = C.shape
    X1, X2 = np.asarray(evecs1, dtype=float), np.asarray(evecs2, dtype=float)
    for X, k, name in ((X1, k1, "evecs1"), (X2, k2, "evecs2")):
        if X.ndim != 2 or X.shape[1] < k:
            raise ValueError(f"{name} must be (n, >= {k}) for C of shape {C.shape}, got shape {X.shape}")
    return nearest(X1[:, :k1] @ C.T, X2[:, :k2])


#: entries of one block of the distance matrix of :func:`nearest` (64 MiB)
NEAREST_BLOCK = 1 << 23


def nearest(points, queries):
    r"""Index of the nearest row of ``points`` to each row of ``queries`` (Euclidean), exact.

    Blocks of :math:`\|p\|^2 - 2 q\cdot p` by matrix products: in the 30 to 200 dimensions of
    a spectral embedding a k-d tree visits nearly every point, and one product is faster.
    """
    P, Q = np.asarray(points, dtype=float), np.asarray(queries, dtype=float)
    sq = np.einsum("ij,ij->i", P, P)
    out = np.empty(len(Q), dtype=np.int64)
    rows = max(1, NEAREST_BLOCK // max(len(P), 1))
    for s in range(0, len(Q), rows):
        out[s:s + rows] = np.argmin(sq[None, :] - 2.0 * (Q[s:s + rows] @ P.T), axis=1)
    return out


def _pullback(lap2, X1, X2, p2p, k1, k2):
    r""":math:`C = \Phi_2^\top B_2 \Pi \Phi_1` of the point map ``p2p`` (2 -> 1) in k1, k2 pairs."""
    return X2[:, :k2].T @ (lap2.B @ X1[p2p, :k1])


def zoomout(lap2, p2p, basis1, basis2, k_start: int | None = None, step: int = 1):
    r"""ZoomOut (Melzi et al. 2019): refine a point map by alternating its functional map and
    its point map, adding ``step`` eigenfunctions each time.

    Parameters
    ----------
    lap2 : Laplacian or (V, F)
        The target (its mass matrix is the inner product of the pull-back).
    p2p : (n2,) int
        Initial point map, target -> source (from :func:`point_map`).
    basis1, basis2 : (evals, evecs)
        Eigenpairs of source and target; their number K is the final size.
    k_start : int, optional
        Initial basis size (default ``K // 4``, at least 2).
    step : int
        Eigenfunctions added per iteration.

    Returns
    -------
    p2p : (n2,) int
        The refined point map.
    C : (K, K) float
        Its functional map.

    Notes
    -----
    From :math:`k = k_0`: :math:`C_k = \Phi_{2,k}^\top B_2 \Pi \Phi_{1,k}` (the pull-back of
    the current point map), then :math:`\Pi` = :func:`point_map` :math:`(C_k)`, and
    :math:`k \leftarrow k + \mathrm{step}` up to K. Each step is an exact projection and a
    nearest-neighbour search; the growing basis keeps the map smooth at coarse scales while
    fitting the fine ones.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> basis = sig.eigs(lap, 20)
    >>> p2p = np.arange(lap.n)
    >>> out, C = sig.zoomout(lap, p2p, basis, basis, k_start=4)
    >>> bool(np.all(out == p2p)), C.shape
    (True, (20, 20))
    """
    lap2 = as_laplacian(lap2, "lap2")
    ev2, X2 = _basis(basis2, lap2.n, "basis2")
    _, X1 = _basis(basis1, None, "basis1")
    p2p = _map(p2p, X1.shape[0], lap2.n, "p2p")
    K = min(X1.shape[1], X2.shape[1])
    k0 = max(2, K // 4) if k_start is None else as_int(k_start, "k_start", lo=1, hi=K)
    step = as_int(step, "step", lo=1)
    ks = list(range(k0, K, step)) + [K]
    for k in ks:
        C = _pullback(lap2, X1, X2, p2p, k, k)
        p2p = point_map(C, X1, X2)
    return p2p, C


# ----------------------------------------------------------------------------- evaluation

#: how :func:`map_error` measures geodesic distances
ERROR_METHODS = ("exact", "heat")


def map_error(V1, F1, p2p, truth, samples: int | None = 500, method: str = "exact", seed: int = 0):
    r"""Mean geodesic error of a point map against a known one, over :math:`\sqrt{\text{area}}`.

    Parameters
    ----------
    V1, F1 : array
        The source surface (where both maps land).
    p2p, truth : (n2,) int
        The map to evaluate and the true one, target vertex -> source vertex.
    samples : int or None
        Evaluate on this many target vertices drawn at random (seeded); None: every vertex.
    method : {"exact", "heat"}
        ``"exact"``: libigl's exact polyhedral geodesics (one propagation per distinct true
        vertex); ``"heat"``: the heat method (:class:`spectral_igl.HeatGeodesics`, one
        factorization, an estimate within a few percent at the default time).
    seed : int

    Returns
    -------
    float
        :math:`\frac{1}{|S|}\sum_{y\in S} d_1(p2p(y), truth(y)) / \sqrt{|M_1|}`.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> truth = np.arange(len(V))
    >>> sig.map_error(V, F, truth, truth, samples=None)
    0.0
    >>> far = np.argmin(V @ V.T, axis=1)   # the antipode: pi on the unit sphere
    >>> bool(abs(sig.map_error(V, F, far, truth, samples=20) - np.pi / np.sqrt(4 * np.pi)) < 0.02)
    True
    """
    from .geodesics import HeatGeodesics

    lap1 = as_laplacian((V1, F1), "V1, F1")
    if lap1.domain != "triangle":
        raise ValueError(f"map_error needs a triangle mesh (V1, F1), got a {lap1.domain} domain")
    V1, F1 = np.asarray(lap1.data["V"], float), np.asarray(lap1.data["F"], np.int64)
    p2p = _map(p2p, lap1.n, None, "p2p")
    truth = _map(truth, lap1.n, p2p.size, "truth")
    method = as_choice(method, "method", ERROR_METHODS)
    ids = np.arange(p2p.size)
    if samples is not None:
        samples = as_int(samples, "samples", lo=1)
        if samples < p2p.size:
            ids = np.sort(np.random.default_rng(seed).choice(p2p.size, samples, replace=False))
    src, dst = truth[ids], p2p[ids]
    d = np.zeros(ids.size)
    sources = np.unique(src)
    if method == "heat":
        heat = HeatGeodesics(lap1)
        for a in range(0, sources.size, 256):          # a block of sources per solve
            block = sources[a:a + 256]
            at = np.flatnonzero(np.isin(src, block))
            dist = heat.compute_each(block)              # (n1, len(block))
            d[at] = np.maximum(dist[dst[at], np.searchsorted(block, src[at])], 0.0)
        d[src == dst] = 0.0
    else:
        import igl

        for s in sources:
            at = np.flatnonzero((src == s) & (dst != s))
            if at.size:
                d[at] = igl.exact_geodesic(V1, F1, np.array([s]), VT=dst[at])
    return float(d.mean() / np.sqrt(lap1.area()))


# ----------------------------------------------------------------------------- the chain

@dataclass
class Correspondence:
    r"""The result of :func:`match_shapes`.

    The point map :math:`T: M_2 \to M_1` and the functional maps, which carry the
    coefficients of a function on the source in its eigenbasis to those of
    :math:`f \circ T` in the target's: :math:`C \approx \Phi_2^\top B_2 \Pi \Phi_1`.

    Parameters
    ----------
    p2p, C, C0, seconds
        As the attributes.

    Attributes
    ----------
    p2p : (n2,) int
        Target vertex -> source vertex.
    C : (K, K) float
        The refined functional map (source coefficients -> target coefficients).
    C0 : (k, k) float
        The functional map fitted on the descriptors, before refinement.
    seconds : dict
        Time of each stage: ``"eigs"``, ``"descriptors"``, ``"fit"``, ``"zoomout"``.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> res = sig.Correspondence(np.arange(3), np.eye(2), np.eye(2), {"eigs": 0.1})
    >>> res.p2p.tolist(), res.C.shape
    ([0, 1, 2], (2, 2))
    """

    p2p: np.ndarray
    C: np.ndarray
    C0: np.ndarray
    seconds: dict = field(default_factory=dict)


def match_shapes(lap1, lap2, k: int = 30, k_final: int = 100, descriptors: str = "wks",
                 n_descriptors: int = 100, grid: str = "own", landmarks=None,
                 laplacian_weight: float = 1e-1, commutativity_weight: float = 1e-2,
                 laplacian_mask: str = "resolvent", orientation_weight: float | None = None,
                 refine: bool = True, method: str = "auto") -> Correspondence:
    r"""A point map from ``lap2``'s vertices to ``lap1``'s, in one call.

    Eigenpairs (:func:`spectral_igl.eigs`, ``k_final`` of each shape), descriptors
    (:func:`pair_descriptors`, plus :func:`landmark_descriptors` when landmarks are given), a
    ``k x k`` functional map (:func:`functional_map`), its point map and ZoomOut up to
    ``k_final`` (:func:`zoomout`), both shapes first scaled to unit area
    (:func:`unit_measure`). The fit solves

    .. math:: \min_C \|C A_1 - A_2\|^2 + \mu_L \|M^{1/2} \circ C\|^2
              + \mu_D \sum_p \|C P_{1,p} - P_{2,p} C\|^2,

    :math:`A_i = \Phi_i^\top B_i D_i` the descriptors' coefficients, M the Laplacian
    commutativity mask of the eigenvalues (the resolvent's, or the squared differences),
    :math:`P_{i,p} = \Phi_i^\top B_i\,\mathrm{diag}(d_{i,p})\,\Phi_i` the descriptors as
    multiplication operators.

    Parameters
    ----------
    lap1, lap2 : Laplacian or (V, F)
        Source and target.
    k : int
        Size of the fitted functional map.
    k_final : int
        Size after ZoomOut (``>= k``).
    descriptors : {"wks", "hks"}
    n_descriptors : int
        Energies or times of the descriptors.
    grid : {"own", "common"}
        See :func:`pair_descriptors`.
    landmarks : (m, 2) int, optional
        Matched vertex pairs ``(source vertex, target vertex)``.
    laplacian_weight, commutativity_weight : float
        See :func:`functional_map`.
    laplacian_mask : {"resolvent", "squared"}
        See :func:`functional_map`.
    orientation_weight : float, optional
        Weight of orientation preservation (see :func:`functional_map`; by default on for
        two triangle meshes, off otherwise).
    refine : bool
        Run ZoomOut (else the point map of the fitted map, in ``k`` eigenfunctions).
    method : str
        Kernel-diagonal method of the descriptors (see :func:`pair_descriptors`).

    Returns
    -------
    Correspondence
        The point map, and the functional maps in the eigenbases of the two shapes scaled
        to unit area (:func:`unit_measure`): the result does not depend on the shapes' sizes.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> V = V * [1.0, 0.8, 0.6] + 0.3 * V[:, :1] ** 2 + 0.15 * V[:, 1:2] * V[:, 2:3]  # no symmetry
    >>> perm = np.random.default_rng(0).permutation(len(V))
    >>> inv = np.argsort(perm)
    >>> res = sig.match_shapes((V, F), (V[perm], inv[F]), k=10, k_final=30, n_descriptors=10)
    >>> bool(np.all(res.p2p == perm))                         # the permutation, recovered
    True
    """
    lap1, lap2 = as_laplacian(lap1, "lap1"), as_laplacian(lap2, "lap2")
    k = as_int(k, "k", lo=2)
    k_final = as_int(k_final, "k_final", lo=k)
    lap1, lap2 = unit_measure(lap1), unit_measure(lap2)
    seconds = {}
    t = time.perf_counter()
    basis1, basis2 = eigs(lap1, k_final), eigs(lap2, k_final)
    seconds["eigs"] = time.perf_counter() - t
    t = time.perf_counter()
    D1, D2 = pair_descriptors(lap1, lap2, descriptors, n_descriptors, grid=grid, method=method)
    if landmarks is not None:
        lm = as_array(landmarks, "landmarks")
        if lm.ndim != 2 or lm.shape[1] != 2 or lm.shape[0] == 0:
            raise ValueError(f"landmarks must be (m, 2) vertex pairs (source, target), got {describe(landmarks)}")
        D1 = np.hstack([D1, landmark_descriptors(lap1, lm[:, 0])])
        D2 = np.hstack([D2, landmark_descriptors(lap2, lm[:, 1])])
    seconds["descriptors"] = time.perf_counter() - t
    t = time.perf_counter()
    small1, small2 = (basis1[0][:k], basis1[1][:, :k]), (basis2[0][:k], basis2[1][:, :k])
    C0 = functional_map(lap1, lap2, D1, D2, small1, small2, laplacian_weight, commutativity_weight,
                        laplacian_mask, orientation_weight)
    p2p = point_map(C0, basis1[1], basis2[1])
    seconds["fit"] = time.perf_counter() - t
    t = time.perf_counter()
    C = C0
    if refine:
        p2p, C = zoomout(lap2, p2p, basis1, basis2, k_start=k)
    seconds["zoomout"] = time.perf_counter() - t
    return Correspondence(p2p, C, C0, seconds)
