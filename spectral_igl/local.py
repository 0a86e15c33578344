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

:func:`local_mexican_hat` is one sparse product of such a column, and
:func:`sparse_heat_kernel` the whole matrix :math:`K_t` by patches of sources sharing one
region, thresholded with proved bounds of what it drops.

R is the set of vertices within a distance r of the source, measured along edges of L with the
length :math:`\sqrt{2(B_{ii}/L_{ii} + B_{jj}/L_{jj})}` (the edge length of an equilateral
mesh), starting from :math:`r = \sqrt{4t\log(1/m_\text{goal})}` (a Gaussian's tail) and
grown until the B-norm bound meets ``tol`` :math:`\cdot\|B^{-1}e_s\|_B` (beyond
:data:`~spectral_igl.approx.region.MAX_FRACTION` of the component, to the whole component).
When R would exceed that share of all vertices or all its attempts would cost more than
:data:`~spectral_igl.approx.region.BUDGET` products of the whole operator, the column is
evaluated globally by :func:`~spectral_igl.heat_kernel` (``info["method"]`` then says
``"global ..."``). The engine is :mod:`spectral_igl.approx.region`;
:func:`~spectral_igl.heat_kernel` with ``method="auto"`` takes the same local path first above
:data:`~spectral_igl.kernels.LOCAL_MIN_VERTICES` vertices.
"""
from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import scipy.sparse as sp

from ._validate import as_flag, as_index, as_int, as_tol
from .accuracy import UNIT_ROUNDOFF as U, info as make_info, rounding_gamma as _gamma
from .accuracy import warn_missed
from .approx import choose_method
from .approx.region import (GROWTH, MAX_FRACTION, dirichlet_heat_blocks, first_radii, grow_regions, patches,
                            region_heat_column, vertex_spacing)
from .filters import heat, mexican_hat
from .kernels import heat_kernel, spectral_kernel
from .laplacian import Laplacian, as_laplacian, shape_time
from .linalg.threads import blas_threads

__all__ = ["local_heat_kernel", "local_mexican_hat", "sparse_heat_kernel", "sparse_diffusion_distance"]



def _metzler_and_time(lap, t, time_unit, name):
    """(lap, absolute t) of a local function's arguments; a Laplacian that is not Metzler refused."""
    lap = as_laplacian(lap)
    if not lap.is_metzler:
        raise ValueError(f"{name} needs a Metzler Laplacian (lumped mass and non-negative "
                         f"edge weights), got {lap!r}: build it with mass='lumped' and positive=True "
                         "(the default of sig.laplacian on triangle meshes)")
    return lap, float(shape_time(lap, t, time_unit))


def _global(lap, t, source, tol, why):
    K, info = heat_kernel(lap, t, source, method=choose_method(lap, heat(t), tol), tol=tol,
                          return_info=True)
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
    >>> full, ref = sig.heat_kernel(lap, 1e-3, 0, tol=1e-10, return_info=True)
    >>> bool(np.all(np.abs(full - k) <= info["abs_error"] + ref["abs_error"]))
    True
    """
    lap, t = _metzler_and_time(lap, t, time_unit, "local_heat_kernel")
    source = as_index(source, lap.n, "source")
    tol = as_tol(tol, "tol")
    return_info = as_flag(return_info, "return_info")
    K, info = region_heat_column(lap, t, source, tol)
    if K is None:
        K, info = _global(lap, t, source, tol, info["note"])
    else:
        warn_missed("local_heat_kernel", info["bnorm_error"], tol / np.sqrt(lap.mass[source]), stacklevel=3)
    info["time"] = t
    return (K, info) if return_info else K


def local_mexican_hat(lap: Laplacian, t: float, source, tol: float = 1e-8, return_info: bool = False,
                      time_unit: str = "absolute"):
    r"""One Mexican-hat column :math:`t\tilde L e^{-t\tilde L}B^{-1}e_s` from a local heat column,
    with a proved bound per entry.

    The Mexican hat (:func:`~spectral_igl.filters.mexican_hat`, ``form="tse"``) is one sparse
    product of a heat column: :math:`H = tB^{-1}L\,K_t(:, s)`. It decays as fast as the heat
    column does, so it costs what :func:`local_heat_kernel` costs plus one product on the
    column's support.

    Parameters
    ----------
    lap : Laplacian
        Metzler (see :func:`local_heat_kernel`).
    t : float
        Time, in ``time_unit`` (see :func:`~spectral_igl.heat_kernel`).
    source : int
    tol : float
        The column's B-norm error is proved below ``tol`` :math:`\cdot\|B^{-1}e_s\|_B` (as for
        :func:`~spectral_igl.spectral_kernel`), or the call warns
        (:class:`~spectral_igl.accuracy.AccuracyWarning`).
    return_info : bool
    time_unit : {"absolute", "shape", "h2"}

    Returns
    -------
    H : (n,) float
        Zero beyond one ring of the heat column's region.
    info : dict, with ``return_info``
        ``abs_error`` (n,), a proved bound of every entry; ``bound_kind`` ``"proof"``;
        ``method`` ``"local"`` (``"global <method>"`` with a ``note`` when the heat column's
        region would be too large); ``bnorm_error``; ``tol``; ``time``; ``heat`` (the heat
        column's ``info``).

    Notes
    -----
    With :math:`|\tilde K - K_t(:, s)| \le E` entrywise (the heat column's proved
    ``abs_error``), the computed :math:`\tilde H = \mathrm{fl}(t\,B^{-1}(L\tilde K))` satisfies

    .. math:: |\tilde H_j - H_j| \le \gamma_{w+2}\,\frac{t\,(|L||\tilde K|)_j}{B_{jj}}
              + \frac{t\,(|L|E)_j}{B_{jj}},

    w the widest row of L and :math:`\gamma_k = ku/(1-ku)`: the first term is the rounding of
    the product, the second the heat column's error carried through
    :math:`|tB^{-1}L\,d| \le tB^{-1}|L||d|`. The B-norm bound is that of these entry bounds.
    When it misses ``tol``, the heat column is recomputed once at a tolerance scaled by the
    miss and a tenth (the carried error is largest just outside the heat column's region, where
    it falls faster than the heat column's own bound).

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(4))
    >>> h, info = sig.local_mexican_hat(lap, 1e-3, 0, return_info=True)
    >>> info["method"], bool(np.count_nonzero(h) < lap.n // 2)
    ('local', True)
    >>> full = sig.spectral_kernel(lap, sig.filters.mexican_hat(1e-3), 0, tol=1e-12)
    >>> bool(np.all(np.abs(full - h) <= info["abs_error"] + 1e-12 * np.abs(full).max()))
    True
    """
    lap, t = _metzler_and_time(lap, t, time_unit, "local_mexican_hat")
    source = as_index(source, lap.n, "source")
    tol = as_tol(tol, "tol")
    return_info = as_flag(return_info, "return_info")
    target = tol / np.sqrt(lap.mass[source])
    heat_tol = tol
    for _ in range(2):
        K, hinfo = region_heat_column(lap, t, source, heat_tol)
        if K is None:
            H, info = spectral_kernel(lap, mexican_hat(t), source, method=choose_method(lap, mexican_hat(t), tol),
                                      tol=tol, return_info=True)
            info["method"] = "global " + str(info["method"])
            info["note"] = hinfo["note"]
            break
        H, err = _heat_derivative(lap, t, K, hinfo["abs_error"])
        bnorm = float(np.sqrt(np.sum(lap.mass * err * err))) * (1.0 + 1e-12)
        info = make_info(err, "proof", "local", tol=tol, bnorm_error=bnorm, heat=hinfo)
        if bnorm <= target:
            break
        heat_tol = heat_tol * max(target / bnorm, 1e-6) * 0.1
    warn_missed("local_mexican_hat", info["bnorm_error"], target, stacklevel=3)
    info["time"] = t
    return (H, info) if return_info else H


def _heat_derivative(lap, t, K, E):
    """(t B^-1 L K, its proved entry bound) from a heat column K within E of the truth (notes of
    :func:`local_mexican_hat`)."""
    L = sp.csr_matrix(lap.L)
    absL = abs(L)
    width = int(np.max(np.diff(L.indptr), initial=0))
    H = t * (L @ K) / lap.mass
    rounding = _gamma(width + 2) * t * (absL @ np.abs(K)) / lap.mass
    carried = t * (absL @ E) / lap.mass
    return H, (rounding + carried) * (1.0 + _gamma(width + 4))



def sparse_heat_kernel(lap: Laplacian, t: float, threshold: float = 1e-8, tol: float = 1e-8, block: int = 32,
                       return_info: bool = False, time_unit: str = "absolute"):
    r"""The whole heat kernel matrix :math:`K_t = e^{-t\tilde L}B^{-1}` as a certified sparse matrix.

    Every column :math:`K_t(:, s)` is solved on a region around its source, as by
    :func:`local_heat_kernel`, by blocks of ``block`` neighbouring sources that share one
    region; the Dirichlet operators of the regions of a few thousand sources are stacked into
    one block-diagonal operator, so that one series of sparse products solves them all
    (:func:`~spectral_igl.approx.region.dirichlet_heat_blocks`; a region whose worst element
    makes its rate large takes the Chebyshev series, proved in the B-norm, instead of
    uniformization). Every entry at or above
    ``threshold`` times its column's peak is kept, and what is dropped is bounded, entry by
    entry and in mass. Column i of K is the diffusion basis function :math:`K_t e_i` of vertex
    i, its diagonal the heat kernel signature (:func:`sparse_diffusion_distance` reads the
    diffusion distances off the same matrix).

    Parameters
    ----------
    lap : Laplacian
        Metzler (see :func:`local_heat_kernel`).
    t : float
        Time, in ``time_unit`` (see :func:`~spectral_igl.heat_kernel`).
    threshold : float
        In (0, 1): entries below this share of their column's computed peak are dropped.
    tol : float
        Each column before dropping is proved within ``tol`` :math:`\cdot\|B^{-1}e_s\|_B` in
        the B-norm (as :func:`~spectral_igl.heat_kernel`).
    block : int
        Sources per shared region.
    return_info : bool
    time_unit : {"absolute", "shape", "h2"}

    Returns
    -------
    K : (n, n) scipy.sparse.csr_matrix
        Symmetric, non-negative: :math:`K_{ij} \approx k_t(x_i, x_j) = (K_t)_{ij}`.
    info : dict, with ``return_info``
        ``abs_error`` (n, n) csr_matrix with K's pattern: a proved bound of each stored
        entry's error; ``dropped_max`` (n,): every entry of column j that K does not store lies
        in [0, ``dropped_max[j]``]; ``dropped_mass`` (n,): a proved bound of
        :math:`\sum_{i\ \text{not stored}} B_{ii}(K_t)_{ij}`; ``m_lost`` (n,): the heat of each
        column outside its region; ``bnorm_error`` (n,); ``region`` (n,) (vertices of each
        column's region); ``products`` (sparse products of the whole operator spent in all);
        ``bound_kind`` ``"proof"``; ``method`` ``"local"``; ``tol``; ``threshold``; ``time`` (absolute).

    Raises
    ------
    ValueError
        When ``lap`` is not Metzler, on a bad argument, or when t is so large that a column's
        column would keep more than :data:`~spectral_igl.approx.region.MAX_FRACTION` of its
        entries (the kernel is not sparse: use :func:`~spectral_igl.heat_kernel` columns).

    Notes
    -----
    With a lumped mass :math:`K_t = B^{-1/2}e^{-tB^{-1/2}LB^{-1/2}}B^{-1/2}` is symmetric, and
    :math:`(K_t)_{ij}` is the discrete kernel :math:`k_t(x_i, x_j)`. A column c of the computed
    matrix C holds :math:`u_{ic}` (the region's Dirichlet kernel, see :func:`local_heat_kernel`)
    where :math:`u_{ic} \ge` ``threshold`` :math:`\max_i u_{ic}`, with
    :math:`|u_{ic} - (K_t)_{ic}| \le \beta_{ic} = e_{ic} + m_c/B_{ii}`, where the region
    solver's bound is :math:`e_{ic} \le \rho_c u_{ic} + a_c` (a relative rounding and an
    additive part per column: the series' truncation, or for a region evaluated by its
    Chebyshev series, :math:`\varepsilon\|g\|_B/\sqrt{B_{ii}}` at its largest over the
    region). Then :math:`K = \max(C, C^\top)` entrywise (a dropped
    entry counting 0): each stored entry is the larger of the computed values available for
    :math:`(K_t)_{ij} = (K_t)_{ji}`, and since each column's bound grows with the value, both
    columns' bounds evaluated at :math:`K_{ij}` bound it:
    :math:`E_{ij} = \max(\rho_j K_{ij} + a_j + m_j/B_{ii},\ \rho_i K_{ij} + a_i + m_i/B_{jj})`,
    stored rounded up in float32. Column c drops entries of its region with
    :math:`u_{ic} + e_{ic} \le \texttt{cut}_c` and every vertex outside it, so a dropped
    :math:`(K_t)_{ic} \le \texttt{cut}_c + m_c/\min_i B_{ii}` = ``dropped_max``, and
    their B-weighted sum is at most
    :math:`\sum_{i \in R,\ \text{dropped}} B_{ii}(u_{ic} + e_{ic}) + m_c` = ``dropped_mass``
    (the symmetric fill only stores more, so both stay bounds for K). Bounds are rounded up.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> K, info = sig.sparse_heat_kernel(lap, 1e-3, return_info=True)
    >>> bool(abs(K - K.T).max() == 0), K.nnz < lap.n ** 2 // 4
    (True, True)
    >>> full, ref = sig.heat_kernel(lap, 1e-3, 5, tol=1e-10, return_info=True)
    >>> stored = K[:, [5]].toarray()[:, 0] > 0
    >>> bool(np.all(np.abs(full - K[:, [5]].toarray()[:, 0])[stored]
    ...             <= info["abs_error"][:, [5]].toarray()[stored, 0] + ref["abs_error"][stored]))
    True
    """
    lap, t = _metzler_and_time(lap, t, time_unit, "sparse_heat_kernel")
    threshold = as_tol(threshold, "threshold")
    tol = as_tol(tol, "tol")
    block = as_int(block, "block", lo=1)
    return_info = as_flag(return_info, "return_info")
    n = lap.n
    per = {k: np.zeros(n) for k in ("dropped_max", "dropped_mass", "m_lost", "bnorm_error", "region", "rel", "add")}
    ctx = _context(lap, t, threshold, tol)
    # the groups by decreasing width, a batch's groups at least half as wide as its first: its
    # series is as wide as its widest group (the retries, queued apart, likewise)
    queue = deque(sorted(_first_groups(ctx, patches(lap.L, block)), key=lambda g: -g[0].size))
    pieces = []
    with blas_threads():                         # the workers' own sections nest in this one
        products = _run_batches(ctx, queue, pieces, per)
    K = _symmetric(n, pieces)
    warn_missed("sparse_heat_kernel", per["bnorm_error"], tol / np.sqrt(lap.mass), stacklevel=3)
    if not return_info:
        return K
    E = _entry_bounds(K, lap.mass, per.pop("rel"), per.pop("add"), per["m_lost"])
    per["region"] = per["region"].astype(np.int64)
    info = make_info(0.0, "proof", "local", tol=tol, threshold=threshold, products=products, time=t, **per)
    info["abs_error"] = E                      # sparse, with K's pattern
    return K, info


#: sources whose regions one stacked series solves at once in :func:`sparse_heat_kernel`: a few
#: hundred keep the series' dense blocks in cache (2048 cost 1.6 times as much on a 43k scan)
BATCH = 256
#: batches of :func:`sparse_heat_kernel` in flight at once (:func:`_run_batches`); 1: one after
#: the other, in this thread
PIPELINE = 2
#: sources of the first batch, which calibrates the first radius of the others
FIRST_BATCH = 128
#: largest stacked series (regions' rows times sources per group) before a batch is split
STACK_LIMIT = 1 << 24
#: share of a column's B-norm target its region's Chebyshev series may take (through the heat
#: it proves kept in the region; :func:`~spectral_igl.approx.region.dirichlet_heat_blocks`),
#: and at most as much again through its entries' bounds (each within eps ||g||_B / sqrt(B_jj),
#: so sqrt(sum_R B_jj e_j^2) <= sqrt(|R| min B / sum_R B) share * target <= share * target):
#: with the lost heat's goal of half the target, 0.5 + 2 * 0.2 leaves a first attempt's column
#: within its target. No bound depends on it (each is proved at whatever eps); at 0.02, 285 of
#: the 140k bunny's regions fell below the series' rounding floor (about 1.5 times their eps)
#: and were uniformized instead (tα 50-175: 250-290 terms against 60-90)
CHEBYSHEV_SHARE = 0.2
#: stored entries of K per row block of its symmetric assembly
ASSEMBLY_CHUNK = 1 << 21


def _context(lap, t, threshold, tol):
    """What every batch of :func:`sparse_heat_kernel` reads: the mass, the components with
    their sizes, smallest masses and areas, the spacing, read once."""
    mass = lap.mass
    labels = lap.components
    count = np.bincount(labels)
    area = np.bincount(labels, weights=mass)
    smallest = np.full(count.size, np.inf)
    np.minimum.at(smallest, labels, mass)
    return {"lap": lap, "t": t, "threshold": threshold, "tol": tol, "mass": mass, "labels": labels,
            "count": count, "area": area, "smallest": smallest, "h2": vertex_spacing(lap),
            "L": sp.csr_matrix(lap.L), "scale": 1.0}


def _goal(ctx, sources):
    """(B-norm target, heat allowed outside the region) of each source's column."""
    target = ctx["tol"] / np.sqrt(ctx["mass"][sources])
    return target, 0.5 * target * np.sqrt(ctx["smallest"][ctx["labels"][sources]])


def _first_groups(ctx, groups):
    """(sources, first radius, True) of every patch: the largest first radius of its sources
    (:func:`~spectral_igl.approx.region.first_radii`), to be scaled by what the earlier
    batches needed (:func:`_solve_batch`)."""
    sources = np.concatenate(groups)
    radii = first_radii(ctx["t"], ctx["h2"][sources], _goal(ctx, sources)[1])
    starts = np.cumsum([0] + [g.size for g in groups[:-1]])
    return [(g, r, True) for g, r in zip(groups, np.maximum.reduceat(radii, starts).tolist())]


def _run_batches(ctx, queue, pieces, per):
    """Solve the queued groups by batches (:func:`_solve_batch`), :data:`PIPELINE` batches in
    flight: a batch's Python work (its regions, their operators and bounds) runs while the
    compiled series of the one before runs without the GIL. Each batch is formed, and its first
    radius scaled, from the batches collected before it, which are collected in order, so the
    result does not depend on the threads' timing: batch i sees the calibration of batches
    0..i-PIPELINE, and the first batch is collected before any other is formed. Returns the
    products spent."""
    retries, products, pending, calibrated = [], 0.0, deque(), False
    pool = ThreadPoolExecutor(PIPELINE) if PIPELINE > 1 else None
    try:
        while queue or retries or pending:
            if pending and (len(pending) >= PIPELINE or not calibrated or not queue):
                spent, again, factors = pending.popleft().result()
                products += spent
                retries.extend(again)
                for f in factors:
                    ctx["scale"] *= f
                calibrated = True
                continue
            if not queue:
                queue = deque(sorted(retries, key=lambda g: -g[0].size))
                retries = []
            batch = [queue.popleft()]
            size = batch[0][0].size
            # a small first batch calibrates the first radius (ctx["scale"]) for the others
            while queue and size < (BATCH if calibrated else FIRST_BATCH) and 2 * queue[0][0].size >= batch[0][0].size:
                batch.append(queue.popleft())
                size += batch[-1][0].size
            args = (ctx, batch, ctx["scale"], pieces, per)
            pending.append(pool.submit(_solve_batch, *args) if pool else _done(_solve_batch(*args)))
    finally:
        if pool:
            pool.shutdown(cancel_futures=True)
    return products


def _done(value):
    """A future holding a result already computed (the batches run in this thread)."""
    future = Future()
    future.set_result(value)
    return future


def _solve_batch(ctx, batch, scale, pieces, per):
    """Solve the columns of a batch of (sources, radius, first attempt) groups in one stacked
    series (each group on its own region); keep the columns that meet their target
    (:func:`_keep`) and return the others with a larger radius. A first attempt's radius is
    scaled by ``scale``, which follows what earlier batches' first attempts needed (the
    Gaussian tail's law between the heat allowed and the heat lost), so that most columns are
    solved at once. Returns (the products spent, of the whole operator; the groups to retry;
    the factors of ``scale`` this batch calls for, :func:`_calibration`)."""
    lap, t, mass, labels = ctx["lap"], ctx["t"], ctx["mass"], ctx["labels"]
    sources = np.concatenate([g for g, _, _ in batch]).astype(np.int64)
    offsets = np.cumsum([0] + [g.size for g, _, _ in batch])
    first = np.array([f for _, _, f in batch])
    radii = np.array([r for _, r, _ in batch]) * np.where(first, scale, 1.0)
    label = labels[sources[offsets[:-1]]]
    size = ctx["count"][label]
    keys, roff = grow_regions(ctx["L"], ctx["h2"], sources, offsets, radii,
                              np.maximum((MAX_FRACTION * size).astype(np.int64), 1), labels)
    if len(batch) > 1 and keys.size * max(g.size for g, _, _ in batch) > STACK_LIMIT:
        # regions as large as their components (large t): fewer groups at a time
        half = len(batch) // 2
        a, b = (_solve_batch(ctx, part, scale, pieces, per) for part in (batch[:half], batch[half:]))
        return a[0] + b[0], a[1] + b[1], a[2] + b[2]
    # the groups in decreasing order of their regions' rates (each stops at its own terms)
    rate = np.maximum.reduceat(1.0 / ctx["h2"][keys % lap.n], roff[:-1])
    order = np.argsort(-rate, kind="stable")
    if np.any(order != np.arange(order.size)):
        batch = [batch[g] for g in order]
        first = first[order]
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        keys = np.sort(rank[keys // lap.n] * lap.n + keys % lap.n)
        roff = np.r_[0, np.cumsum(np.diff(roff)[order])]
        sources = np.concatenate([g for g, _, _ in batch]).astype(np.int64)
        offsets = np.cumsum([0] + [g.size for g, _, _ in batch])
        radii, label, size = radii[order], label[order], size[order]
    tail = min(1e-3 * ctx["tol"] * float(np.sqrt(np.min(mass[sources] / ctx["area"][labels[sources]]))), 1e-3)
    # the Chebyshev series of a region may cost its columns CHEBYSHEV_SHARE of their B-norm
    # target through the heat it proves kept (lost / sqrt(smallest mass) in the B-norm)
    allowance = CHEBYSHEV_SHARE * ctx["tol"] * np.sqrt(ctx["smallest"][label])
    u, rel, add, lost, spent = dirichlet_heat_blocks(lap, t, keys, roff, sources, offsets, tail, mass,
                                                     allowance=allowance)
    # the grid (group, column) of the batch's sources
    counts = np.diff(offsets)
    group = np.repeat(np.arange(counts.size), counts)
    col = np.arange(sources.size) - offsets[group]
    rsize = np.diff(roff)
    err = np.repeat(rel, rsize)[:, None] * u + add
    sq = np.add.reduceat(mass[keys % lap.n][:, None] * err * err, roff[:-1], axis=0)[group, col]
    lost = lost[group, col]
    min_mass = ctx["smallest"][label][group]
    bnorm = (lost / np.sqrt(min_mass) + np.sqrt(sq)) * (1.0 + 1e-12)
    target, goal = _goal(ctx, sources)
    done = (bnorm <= target) | (rsize == size)[group]
    per["bnorm_error"][sources[done]] = bnorm[done]
    per["m_lost"][sources[done]] = lost[done]
    per["region"][sources[done]] = rsize[group[done]]
    per["rel"][sources[done]] = rel[group[done]]
    per["add"][sources[done]] = np.maximum.reduceat(add, roff[:-1], axis=0)[group, col][done]
    _keep(ctx, keys, roff, u, err, sources, group, col, done, lost, pieces, per)
    again = []
    for g in np.unique(group[~done]):
        miss = (group == g) & ~done
        again.append((sources[miss], radii[g] * _growth(goal[miss], lost[miss]), False))
    return spent, again, _calibration(goal, lost, group, first & (rsize < size))


def _calibration(goal, lost, group, first):
    """[The factor of the first radius of later groups] from what nine in ten of this batch's
    first attempts needed: sqrt(log(1/goal) / log(1/lost)) of their columns (a Gaussian's
    tail); [] when none tells."""
    use = first[group] & (goal < 1.0) & (lost > 0.0) & (lost < 1.0)
    if not np.any(use):
        return []
    need = np.zeros(first.size)
    np.maximum.at(need, group[use], np.sqrt(np.log(1.0 / goal[use]) / np.log(1.0 / lost[use])))
    return [max(0.8, min(2.0, 1.02 * float(np.quantile(need[np.unique(group[use])], 0.9))))]


def _growth(goal, lost):
    """Factor of the radius for the columns whose lost heat ``lost`` missed ``goal``: a
    Gaussian's tail, log(1/m) growing like the squared radius."""
    if not lost.size or not (np.all(lost < 1.0) and np.all(goal < 1.0)):
        return 2.0
    return max(GROWTH, 1.05 * float(np.max(np.sqrt(np.log(1.0 / goal) / np.log(1.0 / np.maximum(lost, 1e-300))))))


def _keep(ctx, keys, roff, u, err, sources, group, col, done, lost, pieces, per):
    """Store the entries at or above the threshold of the batch's finished columns, and bound
    what each drops (notes of :func:`sparse_heat_kernel`)."""
    mass, n, threshold = ctx["mass"], ctx["mass"].size, ctx["threshold"]
    rsize = np.diff(roff)
    verts = keys % n
    use = np.zeros((rsize.size, u.shape[1]), dtype=bool)
    use[group[done], col[done]] = True
    peak = np.maximum.reduceat(u, roff[:-1], axis=0)
    keep = (u >= np.repeat(threshold * peak, rsize, axis=0)) & np.repeat(use, rsize, axis=0) & (u > 0)
    stored = np.add.reduceat(keep, roff[:-1], axis=0)
    if stored.max(initial=0) > MAX_FRACTION * n:
        g, c = np.unravel_index(np.argmax(stored), stored.shape)
        source = sources[np.flatnonzero((group == g) & (col == c))[0]]
        raise ValueError(f"t = {ctx['t']:g}: column {source} keeps {stored[g, c]} of the {n} entries (more "
                         f"than {MAX_FRACTION:g}) at threshold {threshold:g}; the heat kernel is not sparse "
                         "there: ask sig.heat_kernel for the columns needed, or raise the threshold")
    c, q = np.nonzero(keep.T)                    # column by column, each region's rows ascending
    grid = np.zeros(use.shape, dtype=np.int64)
    grid[group, col] = sources
    runs = stored.T.ravel() > 0                  # one run per stored column, in that order
    pieces.append((grid.T.ravel()[runs], stored.T.ravel()[runs], verts[q].astype(np.int32), u[q, c]))
    del c, q
    top = np.where(keep, 0.0, u + err)           # a dropped entry of the region, from above
    cut = np.maximum.reduceat(top, roff[:-1], axis=0)[group, col]
    top *= mass[verts][:, None]
    grow = 1.0 + _gamma(rsize + 2.0)
    dropped = (np.add.reduceat(top, roff[:-1], axis=0) * grow[:, None])[group, col]
    min_mass = ctx["smallest"][ctx["labels"][sources]]
    s = sources[done]
    per["dropped_max"][s] = ((cut + lost / min_mass) * (1.0 + 4.0 * U))[done]
    per["dropped_mass"][s] = ((dropped + lost) * (1.0 + 4.0 * U))[done]


def _up32(x):
    """float32 copy of non-negative x rounded upward (a bound stays a bound in half the memory)."""
    y = x.astype(np.float32)
    return np.nextafter(y, np.float32(np.inf), out=y, where=y < x)


def _by_columns(n, pieces):
    """C^T in compressed rows: row j holds column j of the computed C, from the batches'
    (sources, their counts, rows, values) pieces, each freed as it is read."""
    counts = np.zeros(n, dtype=np.int64)
    for src, count, _, _ in pieces:
        counts[src] = count
    indptr = _indptr(counts)
    nnz = int(indptr[-1])
    rows = np.empty(nnz, dtype=np.int32)
    vals = np.empty(nnz)
    while pieces:
        src, count, r, v = pieces.pop()
        # each source is one run of its piece, rows ascending
        start = np.cumsum(count) - count
        dest = np.repeat(indptr[src].astype(np.int64) - start, count) + np.arange(r.size)
        rows[dest] = r
        vals[dest] = v
    return sp.csr_matrix((vals, rows, indptr), shape=(n, n))


def _indptr(counts):
    """Compressed-row pointers of rows holding ``counts`` entries (int32 while they fit)."""
    total = int(np.sum(counts))
    indptr = np.zeros(len(counts) + 1, dtype=np.int32 if total < 2 ** 31 else np.int64)
    np.cumsum(counts, out=indptr[1:])
    return indptr


def _row_blocks(M):
    """(start, stop, row of each entry) of consecutive row blocks of the csr matrix M holding
    about :data:`ASSEMBLY_CHUNK` entries each (entries ``start:stop`` of its arrays)."""
    n = M.shape[0]
    step = max(1, int(n * ASSEMBLY_CHUNK // max(M.nnz, 1)))
    for a in range(0, n, step):
        b = min(a + step, n)
        yield int(M.indptr[a]), int(M.indptr[b]), np.repeat(np.arange(a, b), np.diff(M.indptr[a:b + 1]))


def _release_freed_memory():
    """Hand the memory the C library's allocator holds freed back to the system (glibc's
    ``malloc_trim``; nothing elsewhere): the batches' pieces are many arrays of a few
    megabytes, which the allocator keeps on its heap once freed, so K's arrays, allocated next,
    would come on top of them (the 140k bunny's peak resident memory: 1.86 GB without, 1.67 GB
    with)."""
    import ctypes

    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError):          # pragma: no cover - not glibc
        pass


def _symmetric(n, pieces):
    """K = max(C, C^T) from the computed columns (notes of :func:`sparse_heat_kernel`), by
    blocks of rows, the columns' arrays freed before K's are joined."""
    A = _by_columns(n, pieces)                   # C^T
    _release_freed_memory()                      # the pieces' (small, heap) arrays
    step = max(1, int(n * ASSEMBLY_CHUNK // max(A.nnz, 1)))
    parts = []
    cursor = A.indptr[:-1].astype(np.int64)      # each row's first entry not yet in a block
    for a in range(0, n, step):
        b = min(a + step, n)
        lo, hi = int(A.indptr[a]), int(A.indptr[b])
        mine = sp.csr_matrix((A.data[lo:hi], A.indices[lo:hi], A.indptr[a:b + 1] - lo), shape=(b - a, n))
        part = mine.maximum(_column_block(A, a, b, cursor))
        # copies: maximum's arrays are views of buffers sized for both operands
        parts.append((np.diff(part.indptr), part.indices.astype(np.int32), part.data.copy()))
        del mine, part
    del A
    indptr = _indptr(np.concatenate([p[0] for p in parts]))
    nnz = int(indptr[-1])
    indices = np.empty(nnz, dtype=np.int32)
    data = np.empty(nnz)
    at = 0
    parts.reverse()
    while parts:
        _, idx, val = parts.pop()
        indices[at:at + idx.size] = idx
        data[at:at + idx.size] = val
        at += idx.size
    return sp.csr_matrix((data, indices, indptr), shape=(n, n))


def _column_block(A, a, b, cursor):
    """Columns a:b of the csr matrix A (column indices ascending in each row), transposed: the
    (b - a, n) csr matrix of rows a:b of A^T, the same as ``A[:, a:b].T`` in csr. ``cursor``
    holds each row's first entry of a column at least a, and is moved to its first of a column
    at least b: the blocks taken in order read each entry of A once (a slice of A's columns
    reads all of A's entries), a bisection over each row that has entries in the block."""
    n, ind, stop = A.shape[0], A.indices, A.indptr[1:]
    rows = np.flatnonzero(cursor < stop)
    rows = rows[ind[cursor[rows]] < b]
    first = cursor[rows]
    lo, hi = first + 1, stop[rows].astype(np.int64)
    while True:                                  # the first entry of a column >= b in (first, stop]
        open_ = np.flatnonzero(lo < hi)
        if not open_.size:
            break
        mid = (lo[open_] + hi[open_]) // 2
        below = ind[mid] < b
        lo[open_[below]] = mid[below] + 1
        hi[open_[~below]] = mid[~below]
    cursor[rows] = lo
    counts = lo - first
    pos = np.repeat(first - (np.cumsum(counts) - counts), counts) + np.arange(int(counts.sum()))
    indptr = np.zeros(n + 1, dtype=np.int64)
    indptr[rows + 1] = counts
    np.cumsum(indptr, out=indptr)
    # A's columns a:b by rows are their transpose by columns
    return sp.csc_matrix((A.data[pos], ind[pos] - a, indptr), shape=(b - a, n)).tocsr()


def _entry_bounds(K, mass, rel, add, lost):
    """The proved bound of every stored entry of K, float32 rounded up, with K's pattern.

    Entry (i, j) of K is the computed value of column j or of column i; column c's value at
    row r is within ``rel[c] * value + add[c] + lost[c] / B_rr`` of the truth, increasing in
    the value, so either column's expression at K_ij (at least the value it stored) bounds it."""
    out = np.empty(K.nnz, dtype=np.float32)
    for lo, hi, i in _row_blocks(K):
        j = K.indices[lo:hi]
        k = K.data[lo:hi]
        mine = rel[i] * k + add[i] + lost[i] / mass[j]
        theirs = rel[j] * k + add[j] + lost[j] / mass[i]
        out[lo:hi] = _up32(np.maximum(mine, theirs) * (1.0 + 8.0 * U))
    return sp.csr_matrix((out, K.indices, K.indptr), shape=K.shape)


def sparse_diffusion_distance(lap: Laplacian, t: float, threshold: float = 1e-8, tol: float = 1e-8, block: int = 32,
                              return_info: bool = False, time_unit: str = "absolute"):
    r"""Diffusion distances at time t between every pair that the certified sparse heat kernel
    stores, with a proved bound of each.

    :math:`d_t^2(i, j) = K_t(i,i) + K_t(j,j) - 2K_t(i,j)`, the convention of
    :func:`~spectral_igl.diffusion_distance` (:math:`|\varphi|^2(s) = e^{-ts}`; with
    :math:`e^{-2t\lambda}` instead, pass 2t), read from :func:`sparse_heat_kernel`'s matrix:
    the pairs whose kernel entry is at least ``threshold`` times its column's peak, the small-t
    neighbourhood where diffusion distances resolve the shape.

    Parameters
    ----------
    lap : Laplacian
        Metzler (see :func:`local_heat_kernel`).
    t : float
        Time, in ``time_unit`` (see :func:`~spectral_igl.heat_kernel`).
    threshold, tol, block : see :func:`sparse_heat_kernel`
    return_info : bool
    time_unit : {"absolute", "shape", "h2"}

    Returns
    -------
    D : (n, n) scipy.sparse.csr_matrix
        Symmetric: :math:`d_t(i, j)` at every stored pair (the pattern of the kernel matrix; the
        diagonal stored as explicit zeros).
    info : dict, with ``return_info``
        ``abs_error`` (n, n) csr_matrix with D's pattern, float32 rounded up: a proved bound of
        each stored distance's error; ``hks`` (n,) and ``hks_error`` (n,): :math:`K_t(i, i)`
        and its proved bound; ``dropped_max`` (n,) (of the kernel matrix: a pair (i, j) not
        stored has :math:`0 \le K_t(i,j) \le \min(\texttt{dropped\_max}_i,
        \texttt{dropped\_max}_j)`, so :math:`d_t^2(i,j) \ge K_t(i,i) + K_t(j,j) - 2\min(\dots)`);
        ``bound_kind`` ``"proof"``; ``method`` ``"local"``; ``kernel`` (the kernel matrix's
        ``info`` without its ``abs_error``).

    Notes
    -----
    With every computed entry within its bound :math:`E` of :math:`K_t`, the computed
    :math:`\tilde d^2 = \tilde K_{ii} + \tilde K_{jj} - 2\tilde K_{ij}` is within
    :math:`\varepsilon = E_{ii} + E_{jj} + 2E_{ij} + \gamma_3(\tilde K_{ii} + \tilde K_{jj} +
    2\tilde K_{ij})` of :math:`d_t^2`, so :math:`d_t \in [\sqrt{(\tilde d^2 - \varepsilon)^+},
    \sqrt{\tilde d^2 + \varepsilon}]`; the stored distance is :math:`\sqrt{(\tilde d^2)^+}` and
    its bound the larger distance to either end (rounded up). The diffusion basis
    :math:`\{K_t e_i\}` of every vertex is :func:`sparse_heat_kernel`'s matrix itself: column
    i is :math:`K_t(:, i) = e^{-t\tilde L}B^{-1}e_i` (``K[:, [i]]``, or ``K.T[i]`` as a row, the
    matrix being symmetric), with its proved bounds.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> D, info = sig.sparse_diffusion_distance(lap, 1e-3, return_info=True)
    >>> ref = sig.diffusion_distance(lap, 1e-3, 5, tol=1e-12)
    >>> stored = D[5].indices
    >>> bool(np.all(np.abs(D[5].toarray()[0, stored] - ref[stored])
    ...             <= info["abs_error"][5].toarray()[0, stored] + 1e-9 * ref.max()))
    True
    """
    K, info = sparse_heat_kernel(lap, t, threshold=threshold, tol=tol, block=block, return_info=True,
                                 time_unit=time_unit)
    E = info.pop("abs_error")
    hks, hks_error = K.diagonal(), E.diagonal().astype(float)
    for lo, hi, i in _row_blocks(K):             # in place: D and its bound take K's arrays
        j = K.indices[lo:hi]
        k = K.data[lo:hi]
        d2 = hks[i] + hks[j] - 2.0 * k
        eps = (hks_error[i] + hks_error[j] + 2.0 * E.data[lo:hi] + _gamma(3) * (hks[i] + hks[j] + 2.0 * k)) \
            * (1.0 + 8.0 * U)
        d = np.sqrt(np.maximum(d2, 0.0))
        err = np.maximum(np.sqrt(d2 + eps) - d, d - np.sqrt(np.maximum(d2 - eps, 0.0)))
        K.data[lo:hi] = d
        # the square roots within one rounding each: 4u relative of the larger end
        E.data[lo:hi] = _up32(err + 4.0 * U * np.sqrt(np.maximum(d2 + eps, 0.0)))
    if not return_info:
        return K
    out = make_info(0.0, "proof", "local", tol=tol, threshold=threshold, hks=hks, hks_error=hks_error,
                    dropped_max=info["dropped_max"], kernel=info)
    out["abs_error"] = E
    return K, out
