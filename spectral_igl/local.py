r"""Heat kernel columns that cost what their support costs, with a proved bound per entry.

At small t a heat kernel column :math:`K_t(:, s) = e^{-t\tilde L}B^{-1}e_s` lives on a few
rings around s. :func:`local_heat_kernel` solves the heat equation on a region R grown around
the source, with zero (Dirichlet) values outside R, and proves what it misses.

**The region's kernel is a lower bound.** On a Metzler operator (lumped mass B, non-positive
off-diagonal stiffness) write :math:`A = B^{-1}L = \alpha(I - P)` with :math:`P \ge 0`
(:mod:`spectral_igl.approx.uniformization`). The Dirichlet operator of R is
:math:`A_R = B_{RR}^{-1}L_{RR}` (the full diagonal of L kept) and
:math:`A_R = \alpha(I - P_{RR})`. Since :math:`P \ge 0`,
:math:`(P^k)_{RR} \ge (P_{RR})^k` entrywise, so

.. math:: K^R_t = e^{-tA_R}B_{RR}^{-1}e_s = e^{-t\alpha}\sum_k \frac{(t\alpha)^k}{k!}
          P_{RR}^k B_{RR}^{-1}e_s \;\le\; K_t(R, s).

(Any :math:`\alpha \ge \max_{j\in R} A_{jj}` serves, so the region's own rate is used: a poorly
shaped element elsewhere costs nothing here.)

**What lies outside is the heat that left R.** The total heat
:math:`M(t) = \sum_j B_{jj}K_t(j, s)` starts at 1 and stays in the source's component; with
the stored rows of L summing to :math:`r = L\mathbf 1` (0 up to rounding),
:math:`|M'| = |r^\top K_t(:, s)| \le \rho M` with :math:`\rho = \max_j |r_j|/B_{jj}`, so
:math:`M(t) \le e^{\rho t}`. The difference :math:`d = K_t(:, s) - K^R_t \ge 0` (zero-extended)
therefore has

.. math:: \sum_j B_{jj} d_j \le m := e^{\rho t} - \sum_{j\in R} B_{jj}K^R_t(j),
          \qquad 0 \le d_j \le m / B_{jj},
          \qquad \|d\|_B^2 \le \max_j d_j \sum_j B_{jj} d_j \le m^2/\min_j B_{jj},

the minimum over the source's component (other components get exactly 0).

**The computed region kernel.** :math:`K^R_t` is evaluated by uniformization
(:func:`~spectral_igl.approx.uniformization.uniformize`), whose per-entry bound e is a proof
and relative to each entry (no sum cancels). The lost mass m is bounded from the computed
values minus e, with the rounding of its sum and of :math:`e^{\rho t}` accounted. So every
returned entry is within ``abs_error`` = :math:`e_j + m/B_{jj}` of the exact kernel (a proof),
and below it up to :math:`e_j`: :math:`\tilde K_j - e_j \le K_t(j, s)`.

R is the set of vertices within a distance r of the source, measured along edges of L with the
length :math:`\sqrt{2(B_{ii}/L_{ii} + B_{jj}/L_{jj})}` (the edge length of an equilateral
mesh), starting from :math:`r = \sqrt{4t\log(1/m_\text{goal})}` (a Gaussian's tail) and
grown until the B-norm bound meets ``tol`` :math:`\cdot\|B^{-1}e_s\|_B` (beyond
:data:`MAX_FRACTION` of the component, to the whole component). When R would exceed
:data:`MAX_FRACTION` of all vertices or its products cost more than :data:`BUDGET` products of
the whole operator, the column is evaluated globally by :func:`~spectral_igl.heat_kernel`
(``info["method"]`` then says ``"global ..."``).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .accuracy import info as make_info
from .accuracy import warn_missed
from ._validate import as_flag, as_index, as_tol
from .approx.uniformization import rate_matrix, terms, uniformize
from .kernels import heat_kernel
from .laplacian import Laplacian, as_laplacian, shape_time

__all__ = ["local_heat_kernel", "MAX_FRACTION", "BUDGET"]

#: largest share of the source's component a region grows to before it takes the whole
#: component, and of all vertices before the global path is taken
MAX_FRACTION = 0.25
#: largest cost of a local column, in sparse products of the whole operator (one Cholesky
#: factorization of a surface mesh costs a few hundred)
BUDGET = 200.0
#: growth of the radius per attempt, at least
GROWTH = 1.3
U = 2.0 ** -53


def _gamma(k):
    return k * U / (1.0 - k * U)


def _drift(lap, mass) -> float:
    r""":math:`\rho \ge \max_j |(L\mathbf 1)_j| / B_{jj}` (proved: the computed row sums plus
    their rounding, :math:`\gamma_r \sum_k |L_{jk}|` with :math:`\sum_k|L_{jk}| \le
    2L_{jj} + |r_j|` on a Metzler L), cached on ``lap``."""
    def build():
        L = sp.csr_matrix(lap.L)
        r = np.abs(L @ np.ones(lap.n))
        width = int(np.max(np.diff(L.indptr), initial=0)) + 1
        g = _gamma(width + 2)
        bound = (r + g * (2.0 * L.diagonal() + r)) * (1.0 + 4 * U)
        return float(np.max(bound / mass, initial=0.0)) * (1.0 + 4 * U)

    return lap.cache.fetch("bound", "row_sum_drift", build)


def _neighbours(L: sp.csr_matrix, rows: np.ndarray):
    """(row of each edge, column of each edge) of the given rows of L."""
    starts, stops = L.indptr[rows], L.indptr[rows + 1]
    counts = stops - starts
    pos = np.repeat(stops - np.cumsum(counts), counts) + np.arange(int(counts.sum()))
    return np.repeat(rows, counts), L.indices[pos]


def _region(L, h2, source: int, radius: float):
    """Vertices within ``radius`` of ``source`` along edges of L (edge (i, j) of length
    sqrt((h2_i + h2_j) / 2)), found ring by ring (a vertex's distance through the ring before
    it: an over-estimate, which only makes the region smaller; no bound relies on it), and the
    smallest distance of a vertex left out (the radius that adds at least one vertex)."""
    dist = np.full(L.shape[0], np.inf)
    dist[source] = 0.0
    frontier = np.array([source])
    nearest_out = np.inf
    while frontier.size:
        i, j = _neighbours(L, frontier)
        new = np.isinf(dist[j])
        i, j = i[new], j[new]
        d = dist[i] + np.sqrt(0.5 * (h2[i] + h2[j]))
        order = np.lexsort((d, j))
        j, d = j[order], d[order]
        first = np.r_[True, j[1:] != j[:-1]] if j.size else np.zeros(0, bool)
        j, d = j[first], d[first]
        inside = d <= radius
        if not inside.all():
            nearest_out = min(nearest_out, float(np.min(d[~inside])))
        frontier = j[inside]
        dist[frontier] = d[inside]
    return np.flatnonzero(np.isfinite(dist)), nearest_out


def _spacing(lap, mass) -> np.ndarray:
    """(n,) squared spacing 4 B_jj / L_jj of each vertex (an equilateral mesh's squared edge
    length), cached on ``lap``; inf where L_jj = 0."""
    def build():
        d = lap.L.diagonal()
        with np.errstate(divide="ignore"):
            return np.where(d > 0, 4.0 * mass / np.where(d > 0, d, 1.0), np.inf)

    return lap.cache.fetch("bound", "vertex_spacing", build)


def _solve(lap, mass, R, pos, t, tail, rho):
    """The region's kernel, its per-entry bound, and the bound of the heat that left R."""
    mass = mass[R]
    # the Dirichlet operator of R: L_RR with the full diagonal, B_RR
    alpha, P = rate_matrix(lap.L[R][:, R], mass)
    g = np.zeros(R.size)
    g[pos] = 1.0 / mass[pos]
    u, e = uniformize(P, alpha, t, g, tail) if P is not None else (g, np.zeros(R.size))
    # 1 / B_ss is rounded by u relative, which moves the exact kernel by as much
    e = e + 2.0 * U * (u + e)
    # heat kept in R, from below: sum_j B_jj (u_j - e_j)^+, its rounding relative gamma_{|R|+1}
    kept = float(np.sum(mass * np.maximum(u - e, 0.0))) * (1.0 - _gamma(R.size + 2))
    top = math.exp(rho * t) * (1.0 + 8.0 * U)
    lost = max(top - kept, 0.0) * (1.0 + 4.0 * U)
    return u, e, lost, terms(t, alpha, tail) if P is not None else 0


def _global(lap, t, source, tol, why):
    K, info = heat_kernel(lap, t, source, tol=tol, return_info=True)
    info["method"] = "global " + str(info["method"])
    info["note"] = why
    info["region"] = int(np.count_nonzero(lap.components == lap.components[source]))
    info["m_lost"] = 0.0
    return K, info


def local_heat_kernel(lap: Laplacian, t: float, source, tol: float = 1e-8, return_info: bool = False,
                      time_unit: str = "absolute"):
    r"""One heat kernel column :math:`K_t(:, s) = e^{-t\tilde L}B^{-1}e_s`, evaluated on a region
    around the source with a proved bound on what lies outside it.

    The cost is that of the column's support, not of a factorization of the whole shape: at
    small t a small fraction of one Cholesky factorization. Module notes: why the region's
    Dirichlet kernel is an entrywise lower bound, and why the heat that left the region bounds
    the rest, entry by entry and in the B-norm.

    Parameters
    ----------
    lap : Laplacian
        Metzler (:attr:`~spectral_igl.Laplacian.is_metzler`: lumped mass, non-negative edge
        weights; the default of :func:`~spectral_igl.laplacian` on triangle meshes).
    t : float
        Time, in ``time_unit`` (see :func:`~spectral_igl.heat_kernel`).
    source : int
        The source vertex.
    tol : float
        The column's B-norm error is proved below ``tol`` :math:`\cdot\|B^{-1}e_s\|_B` (as for
        :func:`~spectral_igl.heat_kernel`), so that every entry j is within
        ``tol`` :math:`/\sqrt{B_{ss}B_{jj}}`.
    return_info : bool
        Also return the accuracy ``info`` (:mod:`spectral_igl.accuracy`).
    time_unit : {"absolute", "shape", "h2"}

    Returns
    -------
    K : (n,) float
        Non-negative; 0 outside the region.
    info : dict, with ``return_info``
        ``abs_error`` (n,): a proved bound of every entry (the region kernel's own bound plus
        :math:`m/B_{jj}`); ``bound_kind`` ``"proof"``; ``method`` ``"local"`` (or
        ``"global <method>"`` when the region would be too large, with the reason in
        ``note``); ``bnorm_error``, ``tol``, ``time``, ``region`` (vertices in R), ``m_lost``
        (the proved bound m of the heat outside R), ``products`` (sparse products on R),
        ``solver_error`` (n,) (the region kernel's own bound: ``K - solver_error`` is below
        the exact kernel entry by entry).

    Raises
    ------
    ValueError
        When ``lap`` is not Metzler.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(4))
    >>> k, info = sig.local_heat_kernel(lap, 1e-3, 0, return_info=True)
    >>> info["method"], info["region"] < lap.n // 4
    ('local', True)
    >>> full = sig.heat_kernel(lap, 1e-3, 0, tol=1e-12)
    >>> bool(np.all(np.abs(full - k) <= info["abs_error"] + 1e-12 * full.max()))
    True
    """
    lap = as_laplacian(lap)
    if not lap.is_metzler:
        raise ValueError("local_heat_kernel needs a Metzler Laplacian (lumped mass and non-negative "
                         f"edge weights), got {lap!r}: build it with mass='lumped' and positive=True "
                         "(the default of sig.laplacian on triangle meshes)")
    t = float(shape_time(lap, t, time_unit))
    source = as_index(source, lap.n, "source")
    tol = as_tol(tol, "tol")
    return_info = as_flag(return_info, "return_info")
    K, info = _local(lap, t, source, tol)
    info["time"] = t
    return (K, info) if return_info else K


def _local(lap, t, source, tol):
    n, mass = lap.n, lap.mass
    comp = lap.components == lap.components[source]
    size = int(np.count_nonzero(comp))
    min_mass = float(np.min(mass[comp]))
    target = tol / math.sqrt(mass[source])           # tol * ||B^-1 e_s||_B
    goal = 0.5 * target * math.sqrt(min_mass)        # heat allowed outside R
    area = float(np.sum(mass[comp]))
    # truncation of the series: at most tail / B_ss per entry, 1e-3 of the target in the B-norm
    tail = min(1e-3 * tol * math.sqrt(mass[source] / area), 1e-3)
    rho = _drift(lap, mass)
    h2 = _spacing(lap, mass)
    L = lap.L
    # a Gaussian's tail; where t is short against the source's own rate, heat moves by hops
    # (k rings away with probability about (t alpha)^k / k!): the hops a Poisson tail allows
    rate_time = 4.25 * t / h2[source]
    hops = min(terms(t, 4.25 / h2[source], min(goal, 0.5)), 6) if rate_time < 0.2 else 0
    radius = max(math.sqrt(4.0 * t * math.log(1.0 / goal)) if goal < 1 else 0.0,
                 hops * math.sqrt(h2[source]) if hops else 0.0)
    while True:
        R, nearest_out = _region(L, h2, source, radius)
        if R.size > MAX_FRACTION * size:         # no use growing further: the whole component
            R = np.flatnonzero(comp)
        whole = R.size == size
        if R.size > MAX_FRACTION * n:
            return _global(lap, t, source, tol, f"the region would cover {R.size} of the "
                           f"{n} vertices (more than {MAX_FRACTION:g})")
        row_nnz = float(np.sum(L.indptr[R + 1] - L.indptr[R]))
        cost = terms(t, 4.25 / float(np.min(h2[R])), tail) * row_nnz / L.nnz
        if not whole and cost > BUDGET:
            return _global(lap, t, source, tol, f"the region's {R.size} vertices would take "
                           f"{cost:.3g} products of the whole operator (more than {BUDGET:g})")
        u, e, lost, products = _solve(lap, mass, R, int(np.searchsorted(R, source)), t, tail, rho)
        bnorm = (lost / math.sqrt(min_mass) + math.sqrt(float(np.sum(mass[R] * e * e)))) * (1.0 + 1e-12)
        if bnorm <= target or whole:
            break
        if 0.0 < lost < 1.0 and goal < 1.0:
            grow = max(GROWTH, 1.05 * math.sqrt(math.log(1.0 / goal) / math.log(1.0 / lost)))
        else:
            grow = 2.0
        radius = max(grow * radius, nearest_out)
    warn_missed("local_heat_kernel", bnorm, target, stacklevel=4)
    K = np.zeros(n)
    K[R] = u
    err = np.zeros(n)
    err[comp] = lost / mass[comp] * (1.0 + 2.0 * U)
    err[R] += e
    solver = np.zeros(n)
    solver[R] = e
    return K, make_info(err, "proof", "local", tol=tol, bnorm_error=bnorm, region=int(R.size),
                        m_lost=lost, products=int(products), solver_error=solver)
