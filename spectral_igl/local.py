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

import numpy as np
import scipy.sparse as sp

from ._validate import as_flag, as_index, as_int, as_tol
from .accuracy import UNIT_ROUNDOFF as U, info as make_info, rounding_gamma as _gamma
from .accuracy import warn_missed
from .approx import choose_method
from .approx.region import (GROWTH, MAX_FRACTION, dirichlet_heat, first_radius, grow_region, patches,
                            region_heat_column, vertex_spacing)
from .filters import heat, mexican_hat
from .kernels import heat_kernel, spectral_kernel
from .laplacian import Laplacian, as_laplacian, shape_time

__all__ = ["local_heat_kernel", "local_mexican_hat", "sparse_heat_kernel"]



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
    >>> full = sig.heat_kernel(lap, 1e-3, 0, tol=1e-12)
    >>> bool(np.all(np.abs(full - k) <= info["abs_error"] + 1e-12 * full.max()))
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



def sparse_heat_kernel(lap: Laplacian, t: float, threshold: float = 1e-8, tol: float = 1e-8, block: int = 64,
                       return_info: bool = False, time_unit: str = "absolute"):
    r"""The whole heat kernel matrix :math:`K_t = e^{-t\tilde L}B^{-1}` as a certified sparse matrix.

    Every column :math:`K_t(:, s)` is solved on a region around its source, as by
    :func:`local_heat_kernel`, by blocks of ``block`` neighbouring sources that share one
    region and one block of sparse products; every entry at or above ``threshold`` times its
    column's peak is kept, and what is dropped is bounded, entry by entry and in mass.

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
        ``bound_kind`` ``"proof"``; ``method`` ``"local"``; ``tol``; ``threshold``; ``time``.

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
    :math:`|u_{ic} - (K_t)_{ic}| \le \beta_{ic} = e_{ic} + m_c/B_{ii}`. Then
    :math:`K = \max(C, C^\top)` entrywise (a dropped entry counting 0): each stored entry is
    the larger of the computed values available for :math:`(K_t)_{ij} = (K_t)_{ji}`, within the
    larger of their bounds (if :math:`a \ge b` both bracket the truth, :math:`|a - k| \le
    \beta_a`), stored rounded up in float32. Column c drops entries of its region with
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
    >>> full = sig.heat_kernel(lap, 1e-3, 5, tol=1e-12)
    >>> stored = K[:, [5]].toarray()[:, 0] > 0
    >>> bool(np.all(np.abs(full - K[:, [5]].toarray()[:, 0])[stored]
    ...             <= info["abs_error"][:, [5]].toarray()[stored, 0] + 1e-12 * full.max()))
    True
    """
    lap, t = _metzler_and_time(lap, t, time_unit, "sparse_heat_kernel")
    threshold = as_tol(threshold, "threshold")
    tol = as_tol(tol, "tol")
    block = as_int(block, "block", lo=1)
    return_info = as_flag(return_info, "return_info")
    n = lap.n
    parts = {k: [None] * n for k in ("rows", "vals", "errs")}
    per = {k: np.zeros(n) for k in ("dropped_max", "dropped_mass", "m_lost", "bnorm_error", "region")}
    ctx = _context(lap, t, threshold, tol)
    products = 0.0
    for sources in patches(lap.L, block):
        products += _sparse_block(ctx, sources, parts, per)
    K, E = _symmetric(n, parts)
    warn_missed("sparse_heat_kernel", per["bnorm_error"], tol / np.sqrt(lap.mass), stacklevel=3)
    if not return_info:
        return K
    per["region"] = per["region"].astype(np.int64)
    info = make_info(0.0, "proof", "local", tol=tol, threshold=threshold, products=products, **per)
    info["abs_error"] = E                      # sparse, with K's pattern
    return K, info


def _context(lap, t, threshold, tol):
    """What every block of :func:`sparse_heat_kernel` reads: the mass, the components with
    their sizes, smallest masses and areas, the spacing, read once."""
    mass = lap.mass
    labels = lap.components
    count = np.bincount(labels)
    area = np.bincount(labels, weights=mass)
    smallest = np.full(count.size, np.inf)
    np.minimum.at(smallest, labels, mass)
    return {"lap": lap, "t": t, "threshold": threshold, "tol": tol, "mass": mass, "labels": labels,
            "count": count, "area": area, "smallest": smallest, "h2": vertex_spacing(lap), "radius": 0.0}


def _sparse_block(ctx, sources, parts, per):
    """Solve the columns of ``sources`` (one patch, one component) on shared regions, grown for
    the columns that miss their target; keep their entries above the threshold. Returns the
    products spent (of the whole operator)."""
    lap, t, mass, h2 = ctx["lap"], ctx["t"], ctx["mass"], ctx["h2"]
    L = lap.L
    label = ctx["labels"][sources[0]]
    size, min_mass = int(ctx["count"][label]), float(ctx["smallest"][label])
    target = ctx["tol"] / np.sqrt(mass[sources])
    goal = 0.5 * target * np.sqrt(min_mass)
    tail = min(1e-3 * ctx["tol"] * float(np.sqrt(np.min(mass[sources]) / ctx["area"][label])), 1e-3)
    # a neighbouring patch's final radius is the likeliest start
    radius = max(max(first_radius(t, h2[s], g) for s, g in zip(sources, goal)), ctx["radius"])
    spent = 0.0
    while sources.size:
        R, _ = grow_region(L, h2, sources, radius, limit=max(int(MAX_FRACTION * size), 1))
        R = np.flatnonzero(ctx["labels"] == label) if R is None else R
        u, e, lost, k = dirichlet_heat(lap, t, R, sources, tail, mass)
        spent += k * float(np.sum(L.indptr[R + 1] - L.indptr[R])) / L.nnz
        bnorm = (lost / np.sqrt(min_mass) + np.sqrt(mass[R] @ (e * e))) * (1.0 + 1e-12)
        done = (bnorm <= target) | (R.size == size)
        for c in np.flatnonzero(done):
            _keep(ctx, R, sources[c], u[:, c], e[:, c], float(lost[c]), min_mass, parts, per)
            per["bnorm_error"][sources[c]] = bnorm[c]
            per["region"][sources[c]] = R.size
        sources, target, goal, lost = sources[~done], target[~done], goal[~done], lost[~done]
        if sources.size:
            radius *= _growth(goal, lost)
    ctx["radius"] = 0.9 * radius
    return spent


def _growth(goal, lost):
    """Factor of the radius for the columns whose lost heat ``lost`` missed ``goal``: a
    Gaussian's tail, log(1/m) growing like the squared radius."""
    if not lost.size or not (np.all(lost < 1.0) and np.all(goal < 1.0)):
        return 2.0
    return max(GROWTH, 1.05 * float(np.max(np.sqrt(np.log(1.0 / goal) / np.log(1.0 / np.maximum(lost, 1e-300))))))


def _keep(ctx, R, source, u, e, lost, min_mass, parts, per):
    """Store one column's entries at or above the threshold with their bounds, and bound what
    it drops (notes of :func:`sparse_heat_kernel`)."""
    mass, n, threshold = ctx["mass"], ctx["mass"].size, ctx["threshold"]
    keep = u >= threshold * np.max(u)
    rows = R[keep]
    if rows.size > MAX_FRACTION * n:
        raise ValueError(f"t = {ctx['t']:g}: column {source} keeps {rows.size} of the {n} entries (more "
                         f"than {MAX_FRACTION:g}) at threshold {threshold:g}; the heat kernel is not sparse "
                         "there: ask sig.heat_kernel for the columns needed, or raise the threshold")
    parts["rows"][source] = rows.astype(np.int32)
    parts["vals"][source] = u[keep]
    parts["errs"][source] = _up32((e[keep] + lost / mass[rows]) * (1.0 + 4.0 * U))
    top = u[~keep] + e[~keep]
    cut = float(np.max(top, initial=0.0))
    per["dropped_max"][source] = (cut + lost / min_mass) * (1.0 + 4.0 * U)
    per["dropped_mass"][source] = (float(mass[R[~keep]] @ top) * (1.0 + _gamma(R.size + 2)) + lost) \
        * (1.0 + 4.0 * U)
    per["m_lost"][source] = lost


def _up32(x):
    """float32 copy of non-negative x rounded upward (a bound stays a bound in half the memory)."""
    y = x.astype(np.float32)
    return np.nextafter(y, np.float32(np.inf), out=y, where=y < x)


def _symmetric(n, parts):
    """(K, E) = (max(C, C^T), max(E_C, E_C^T)) from the stored columns (notes of
    :func:`sparse_heat_kernel`).

    Column j of C is ``parts[...][j]`` with sorted rows, so C is assembled in compressed
    columns without sorting, and its transpose is the same arrays read by rows; each list is
    emptied as it is read."""
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum([r.size for r in parts["rows"]], out=indptr[1:])
    rows = np.concatenate(parts["rows"])
    parts["rows"].clear()

    def one(key):
        data = np.concatenate(parts[key])
        parts[key].clear()
        C = sp.csc_matrix((data, rows, indptr), shape=(n, n))
        return C.tocsr().maximum(sp.csr_matrix((data, rows, indptr), shape=(n, n)))

    K = one("vals")
    E = one("errs")
    return K, E
