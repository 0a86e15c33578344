r"""Spectral distances :math:`d^2(i,j) = \|\varphi(\tilde L)B^{-1}(e_i - e_j)\|_B^2`.

.. math:: d^2(i, j) = \sum_l |\varphi(\lambda_l)|^2 |x_l(i) - x_l(j)|^2 = G_{ii} + G_{jj} - 2 G_{ij},
          \qquad G = |\varphi|^2(\tilde L) B^{-1}

Distances are returned as distances (not squares) and are never negative by
construction: one-to-one and one-to-many distances are computed as the B-norm of
:math:`\varphi(\tilde L)B^{-1}(e_i - e_j)`; one-to-all distances use a column of
:math:`G` and its diagonal, and every target whose squared distance is not safely
above the diagonal's error is recomputed as such a norm.
"""
from __future__ import annotations

import warnings

import numpy as np

from .accuracy import info as bound_info, warn_missed, weakest
from ._validate import as_delta, as_flag, as_index, as_indices, as_int, check_dense_size
from .approx import spectral_operator
from .approx.region import region_heat_column
from .diagonal import (EXACT_MAX, check_diagonal_options, heat_projection_applies, kernel_diagonal, low_rank,
                       phi_values, selinv_kernel, selinv_supported)
from .diagonal.core import column_entry_error
from .diagonal.selinv import NoSelinv
from .filters import (
    biharmonic,
    check_filter,
    commute_time,
    heat,
    mexican_hat,
    polyharmonic,
    wave,
)
from .kernels import LOCAL_MIN_VERTICES, block_sources, heat_kernels, kernel_columns
from .laplacian import as_laplacian, lambda_max_kind, mass_ratio, shape_time
from .progress import progress_bar

__all__ = [
    "spectral_distance",
    "OneToAll",
    "pairwise_spectral_distance",
    "diffusion_distance",
    "commute_time_distance",
    "biharmonic_distance",
    "polyharmonic_distance",
    "wave_distance",
    "mexican_hat_distance",
    "pairwise_diffusion_distance",
    "pairwise_commute_time_distance",
    "pairwise_biharmonic_distance",
    "pairwise_polyharmonic_distance",
    "pairwise_wave_distance",
    "pairwise_mexican_hat_distance",
    "root_error",
]

BLOCK = 64
#: largest order of :func:`polyharmonic_distance`
MAX_ORDER = 16
#: one-to-many with more targets than this (on a large mesh) goes through the diagonal
MANY_TARGETS = 256


def root_error(d, d2_error):
    r"""Per-entry bound of :math:`|d - \tilde d|` from a bound :math:`e` of :math:`|d^2 - \tilde d^2|`.

    For non-negative :math:`d, \tilde d`: :math:`|d - \tilde d| = |d^2 - \tilde d^2| / (d + \tilde d)
    \le \min(\sqrt e,\ e / \tilde d)` (the first since :math:`|d - \tilde d|^2 \le
    |d - \tilde d|(d + \tilde d)`). ``nan`` stays ``nan`` (no bound).

    Parameters
    ----------
    d : float or array
        The returned :math:`\tilde d \ge 0`.
    d2_error : float or array
        Bounds :math:`e` of :math:`|d^2 - \tilde d^2|`, broadcast against ``d``.

    Examples
    --------
    >>> root_error([0.0, 2.0], 1e-4)
    array([1.e-02, 5.e-05])
    """
    d = np.abs(np.asarray(d, dtype=float))
    e = np.asarray(d2_error, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.minimum(np.sqrt(e), np.where(d > 0, e / np.where(d > 0, d, 1.0), np.inf))


def _norm_rounding(lap) -> float:
    r"""Relative rounding allowance of a B-norm computed as :math:`\sqrt{y^*(By)}`: each product
    sums at most n + (row length) terms, and :math:`|y|^\top B|y| \le y^*By/c` for a mass matrix
    with non-negative entries (c = :func:`~spectral_igl.laplacian.mass_ratio`); twice the
    unit roundoff per term, for the square and the square root."""
    row = int(np.max(np.diff(lap.B.indptr), initial=1))
    return (lap.n + row + 4) * np.finfo(float).eps / mass_ratio(lap)


def _bnorm2(lap, Y):
    """(m,) squared B-norms of the columns of Y (real or complex)."""
    BY = lap.B @ Y
    return np.real(np.einsum("ij,ij->j", np.conj(Y), BY))


def _pair_norms(lap, op, source: int, targets: np.ndarray, delta: str):
    """Exact d^2(source, t) = ||phi(L~) B^-1 (e_s - e_t)||_B^2 for each target, in blocks, and a
    bound of each |d - d~|: the engine's B-norm bound of the column (reverse triangle
    inequality) plus the rounding of the norm."""
    n = lap.n
    out = np.empty(targets.size)
    bound = np.empty(targets.size)
    for a in range(0, targets.size, BLOCK):
        t = targets[a:a + BLOCK]
        E = np.zeros((n, t.size))
        E[source, :] += 1.0
        E[t, np.arange(t.size)] -= 1.0     # a zero column when t == source
        Y = op.apply_inverse_mass(E) if delta == "mass" else op.apply(E)
        out[a:a + t.size] = _bnorm2(lap, Y)
        eb = op.error_bound
        bound[a:a + t.size] = np.nan if eb is None else np.broadcast_to(np.asarray(eb, dtype=float), (t.size,))
    out = np.maximum(out, 0.0)  # a B-norm squared: only -0.0 can occur
    bound = bound + _norm_rounding(lap) * np.sqrt(out)
    bound[targets == source] = 0.0
    return out, bound


def _coming_selinv_kernel(lap, G2, diagonal, delta, tol):
    """The selected-inverse kernel :func:`kernel_diagonal` is about to use for ``G2``, or None."""
    if diagonal not in ("auto", "selinv") or not selinv_supported(lap, G2, delta) \
            or heat_projection_applies(lap, G2):
        return None
    try:
        return selinv_kernel(lap, G2, tol)
    except NoSelinv:
        return None


def spectral_distance(lap, filt, source, targets=None, delta: str = "mass", method: str = "auto",
                      tol: float = 1e-8, diagonal: str = "auto", k: int | None = None,
                      distance: int | None = None, samples: int = 16, rtol: float = 1e-4,
                      max_colours: int | None = None, max_recompute: int | None = None,
                      return_info: bool = False, progress=None):
    r"""Spectral distance from ``source`` to ``targets`` (one, many, or all vertices).

    .. math:: d(i, j) = \|\varphi(\tilde L) B^{-1}(e_i - e_j)\|_B
              = \Big(\sum_l |\varphi(\lambda_l)|^2 |x_l(i) - x_l(j)|^2\Big)^{1/2}

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        :math:`\varphi`; the distance uses :math:`|\varphi|^2`.
    source : int
    targets : None, int or (m,) int
        ``None``: all vertices (one-to-all). Otherwise each distance is the exact B-norm
        of one filtered difference of deltas (one engine application per target).
    delta : {"mass", "seed"}
        ``"mass"`` (default): :math:`B^{-1}e_i`, converges under refinement. ``"seed"``:
        :math:`e_i` as printed in the survey's Eq. (5); mesh dependent.
    method, tol : engine approximation method and accuracy.
    diagonal : {"auto", "selinv", "exact", "probing", "eigen", "dense"}
        How :math:`G_{jj}` is obtained for one-to-all (see
        :func:`spectral_igl.kernel_diagonal`). ``"eigen"`` returns the classical
        truncated-eigenpair distance with ``k`` pairs (baseline; no error bound).
    k, distance, samples, rtol, max_colours : parameters of the diagonal estimator
        (:func:`spectral_igl.kernel_diagonal`).
    max_recompute : int, optional
        One-to-all: at most this many targets (the smallest estimates first) whose
        squared distance is within the diagonal's error of 0 are recomputed exactly
        (one engine application each); the others keep the estimate, clipped at 0, and
        are listed in ``info["unverified"]``. Default: all of them.
    return_info : bool
        Also return a dict (:mod:`spectral_igl.accuracy`): ``abs_error``, a bound of
        :math:`|d - \tilde d|` for every returned distance (shaped as ``d``; ``nan`` where there
        is none), ``bound_kind`` (``"proof"``, ``"estimate"`` or ``None``: the weakest of its
        parts), ``method`` (the diagonal's method for one-to-all, else the engine's),
        ``engine_method``. Distances computed as norms of filtered differences are within
        the engine's B-norm bound of that difference (plus the rounding of the norm); the
        others come from :math:`d^2 = G_{ss} + G_{jj} - 2G_{js}` with a bound :math:`e_j` of
        :math:`|d^2 - \tilde d^2|` (the diagonal's bound at j and s, the column's per-entry
        bound, the rounding of the cancellation) and :math:`|d - \tilde d| \le
        \min(\sqrt{e_j}, e_j/\tilde d)` (:func:`root_error`). One-to-all also gives the
        diagonal's ``info`` (its ``bound_kind`` as ``diagonal_bound_kind``), ``recomputed``
        (targets recomputed exactly as a norm), ``unverified`` and ``d2_error_bound`` (the
        largest :math:`e_j` of the entries not recomputed).
    progress : bool, optional
        One-to-all: a progress bar on stderr over the diagonal's poles or blocks (see
        :mod:`spectral_igl.progress`; default off).

    Returns
    -------
    d : float for an integer target; (m,) float for m targets; (n,) float for all.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.spectral_distance(lap, sig.filters.biharmonic(), 0)
    >>> d.shape, float(d[0])
    ((162,), 0.0)
    """
    lap, filt, delta, s, tol, opts, max_recompute, return_info = _checked_arguments(
        lap, filt, source, targets, delta, method, tol, diagonal, k, distance, samples, rtol,
        max_colours, max_recompute, return_info)
    n = lap.n
    if diagonal == "eigen":
        d = _eigen_distance(lap, filt, s, opts["k"], delta)
        info = bound_info(np.full(n, np.nan), None, "eigen", k=opts["k"],
                          note="truncated eigen-expansion: no error bound")
        return _finish(d, info, targets, n, return_info)
    if targets is not None and _targets_as_norms(lap, targets):
        local = _local_norm_distances(lap, filt, s, targets, delta, method, tol, return_info)
        if local is not None:
            return local
        return _norm_distances(lap, filt, s, targets, delta, method, tol, return_info)

    # one-to-all: column of G, diagonal of G
    G2 = filt.square
    e = np.zeros((n, 1))
    e[s] = 1.0
    diag, dinfo = _diagonal_step(lap, G2, e, delta, diagonal, method, tol, opts, progress)
    info = dict(dinfo, diagonal_bound_kind=dinfo["bound_kind"], tol=tol)
    col, err, kind, engine_method = _column_step(lap, G2, e, s, delta, dinfo, method, tol)
    if engine_method is not None:
        info["engine_method"] = engine_method
    d, abs_error, kind, redo, unverified, d2_bound = _combination_step(
        lap, filt, s, diag, col, err, kind, delta, method, tol, max_recompute)
    info["recomputed"] = redo
    info["d2_error_bound"] = d2_bound
    info["unverified"] = unverified
    info.update(bound_info(abs_error, kind, dinfo["method"]))
    return _finish(d, info, targets, n, return_info)


def _checked_arguments(lap, filt, source, targets, delta, method, tol, diagonal, k, distance, samples,
                       rtol, max_colours, max_recompute, return_info):
    """The arguments of :func:`spectral_distance`, checked and normalized: ``(lap, filt, delta,
    source index, tol, options of the diagonal estimator, max_recompute, return_info)``."""
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    delta = as_delta(delta)
    n = lap.n
    s = as_index(source, n, "source")
    k, distance, samples, rtol, max_colours, tol, _ = check_diagonal_options(
        n, diagonal, k, distance, samples, rtol, max_colours, tol, method)
    max_recompute = None if max_recompute is None else as_int(max_recompute, "max_recompute", lo=0)
    return_info = as_flag(return_info, "return_info")
    if targets is not None:
        as_indices(targets, n, "targets")
    opts = dict(k=k, distance=distance, samples=samples, rtol=rtol, max_colours=max_colours)
    return lap, filt, delta, s, tol, opts, max_recompute, return_info


def _targets_as_norms(lap, targets) -> bool:
    """Whether the distances to ``targets`` are computed one norm each (not through the
    diagonal, which pays off only for many targets on a large mesh)."""
    t = as_indices(targets, lap.n, "targets")
    return not (t.size > MANY_TARGETS and lap.n > EXACT_MAX)


def _norm_distances(lap, filt, s, targets, delta, method, tol, return_info):
    """One-to-one or one-to-many: each distance the B-norm of one filtered difference of deltas."""
    t = as_indices(targets, lap.n, "targets")
    op = spectral_operator(lap, filt, method, tol)
    d2, bound = _pair_norms(lap, op, s, t, delta)
    info = bound_info(bound, weakest(op.bound_kind, lambda_max_kind(lap)), op.method,
                      tol=tol, engine_method=op.method)
    return _finish(np.sqrt(d2), info, np.arange(t.size) if np.ndim(targets) else 0, t.size,
                   return_info)


def _local_norm_distances(lap, filt, s, targets, delta, method, tol, return_info):
    r"""Diffusion distances to a few targets as B-norms of differences of local heat columns
    (``method="auto"`` on a Metzler operator above
    :data:`~spectral_igl.kernels.LOCAL_MIN_VERTICES` vertices), or None when that is not
    the cheaper path: the filter is not the heat filter, or a column's region would cost too
    much (each column has the budget of ``heat_kernel``'s local columns,
    :data:`~spectral_igl.approx.region.BUDGET` products of the whole operator).

    With :math:`u_j = K_{t/2}(:, j)` each column is computed on a region around its source
    within :math:`\|\tilde u_j - u_j\|_B \le \beta_j \le (\mathrm{tol}/\sqrt 2)\,
    \|B^{-1}e_j\|_B` (a proof, :func:`~spectral_igl.approx.region.region_heat_column`), and
    :math:`d(s, i) = \|u_s - u_i\|_B`, so by the reverse triangle inequality
    :math:`|\tilde d - d| \le \beta_s + \beta_i` plus the rounding of the norm
    (:func:`_norm_rounding`); that is within :math:`\mathrm{tol}\,\|B^{-1}(e_s - e_i)\|_B`,
    the global path's promise.
    """
    if not (filt.kind == "heat" and method == "auto" and delta == "mass" and lap.is_metzler
            and lap.n > LOCAL_MIN_VERTICES):
        return None
    half = float(filt.params["t"])
    idx = as_indices(targets, lap.n, "targets")
    cost, columns = 0.0, {}
    for j in np.unique(np.r_[s, idx]):
        col, cinfo = region_heat_column(lap, half, int(j), tol / np.sqrt(2.0))
        if col is None:
            return None
        cost += cinfo["cost"]
        support = np.flatnonzero(col)
        columns[int(j)] = (support, col[support], float(cinfo["bnorm_error"]))
    mass = lap.mass
    src = np.zeros(lap.n)
    src_support, src_values, src_bound = columns[s]
    src[src_support] = src_values
    d2, bound = np.zeros(idx.size), np.zeros(idx.size)
    for c, j in enumerate(idx):
        if j == s:
            continue
        support, values, beta = columns[int(j)]
        union = np.union1d(src_support, support)
        diff = src[union]
        diff[np.searchsorted(union, support)] -= values
        d2[c] = float(mass[union] @ (diff * diff))
        bound[c] = src_bound + beta
    d = np.sqrt(d2)
    bound = (bound + _norm_rounding(lap) * d) * (1.0 + 1e-12)
    target = tol * np.sqrt(1.0 / mass[s] + 1.0 / mass[idx])
    warn_missed("diffusion distance", np.where(idx == s, 0.0, bound), target, stacklevel=4)
    info = bound_info(bound, "proof", "local", tol=tol, engine_method="local", cost=cost)
    return _finish(d, info, np.arange(idx.size) if np.ndim(targets) else 0, idx.size, return_info)


def _diagonal_step(lap, G2, e, delta, diagonal, method, tol, opts, progress):
    """The diagonal of :math:`G` by the method ``diagonal`` chooses, with its info; when that
    is the selected inverse, the column ``e`` is primed into the same pass over the poles
    (one factor held at a time)."""
    kern = _coming_selinv_kernel(lap, G2, diagonal, delta, tol)
    if kern is not None:
        kern.prime(e if delta == "mass" else e * lap.mass[:, None])
    diag, dinfo = kernel_diagonal(lap, G2, method=diagonal, delta=delta, tol=tol, engine_method=method,
                                  return_info=True, progress=progress, **opts)
    return np.real(diag), dinfo


def _column_step(lap, G2, e, s, delta, dinfo, method, tol):
    r"""The column :math:`G_{:,s}` and a bound ``err`` of the error its combination with the
    diagonal makes in each :math:`d^2` (before rounding); returns ``(column, err, bound kind,
    engine method or None)``."""
    if dinfo["method"] == "selinv":
        # the column from the same approximation R as the diagonal: d^2 is then R's own
        # squared distance, |d^2 - d_R^2| <= eps ||B^-1(e_i - e_s)||_B^2 <= 2 (bound_i + bound_s)
        kern = selinv_kernel(lap, G2, tol)
        bound = kern.diagonal()[1]
        if delta == "mass":
            col = kern.columns(e)[:, 0]
        else:
            col = lap.mass * kern.columns(e * lap.mass[:, None])[:, 0]
            bound = bound * lap.mass ** 2
        return col, 2.0 * (bound + bound[s]), kern.bound_kind, None
    op2 = spectral_operator(lap, G2, method, tol)
    col = (op2.apply_inverse_mass(e) if delta == "mass" else lap.B @ op2.apply(e))[:, 0].real
    col_bound = np.nan if op2.error_bound is None else float(np.max(op2.error_bound))
    # |d^2 - d~^2| <= |dG_ss| + |dG_jj| + 2 |dG_js|: the diagonal's per-vertex bound (or
    # estimate) at j and s, and the column's per-entry bound
    derr = np.asarray(dinfo["abs_error"], dtype=float)
    err = derr + derr[s] + 2.0 * column_entry_error(lap, col_bound, delta)
    kind = weakest(dinfo["bound_kind"], op2.bound_kind, lambda_max_kind(lap))
    return col, err, kind, op2.method


def _combination_step(lap, filt, s, diag, col, err, kind, delta, method, tol, max_recompute):
    r""":math:`d^2 = G_{ss} + G_{jj} - 2G_{js}` with a bound of each :math:`|d - \tilde d|`;
    every entry not safely above its bound is recomputed as a norm (at most ``max_recompute``,
    the smallest first). Returns ``(d, abs_error, bound kind, recomputed, unverified, largest
    bound of d^2 over the entries not recomputed)``."""
    d2 = diag[s] + diag - 2.0 * col
    d2[s] = 0.0
    # plus the rounding of the cancellation (without a bound of the parts, the entries near 0
    # are still recomputed; the others then have no bound)
    thr = err + 64.0 * np.finfo(float).eps * (np.abs(diag[s]) + np.abs(diag) + 2.0 * np.abs(col))
    redo = np.flatnonzero(d2 <= np.nan_to_num(thr, nan=0.0))
    redo = redo[redo != s]
    unverified = redo[:0]
    if max_recompute is not None and redo.size > int(max_recompute):
        order = np.argsort(d2[redo], kind="stable")
        redo, unverified = np.sort(redo[order[:int(max_recompute)]]), np.sort(redo[order[int(max_recompute):]])
    elif redo.size > 1024:
        warnings.warn(f"{redo.size} one-to-all distances were within the diagonal's error of 0 and "
                      "are recomputed exactly; a more accurate diagonal (method='exact') is cheaper",
                      RuntimeWarning, stacklevel=3)
    d = np.sqrt(np.maximum(d2, 0.0))  # every entry is either > thr > 0, an exact norm or unverified
    # |d^2 - d~^2| <= thr for every entry not recomputed (clipping an unverified d~^2 < 0 at 0
    # only moves it closer); recomputed entries are norms with their own bound
    abs_error = root_error(d, thr)
    abs_error[s] = 0.0
    if redo.size:
        op = spectral_operator(lap, filt, method, tol)
        d2[redo], abs_error[redo] = _pair_norms(lap, op, s, redo, delta)
        d[redo] = np.sqrt(d2[redo])
        kind = weakest(kind, op.bound_kind)
    if np.isnan(abs_error).any():
        kind = None
    d2_bound = float(np.max(np.delete(thr, np.append(redo, s)), initial=0.0))
    return d, abs_error, kind, redo, unverified, d2_bound


def _finish(d, info, targets, n, return_info):
    """``d`` (and the per-entry fields of ``info``) at ``targets`` (all for None)."""
    if targets is not None:
        d = _select(d, targets, n)
        info["abs_error"] = _select(info["abs_error"], targets, n)
    return (d, info) if return_info else d


def _select(d, targets, n):
    if np.ndim(targets) == 0:
        return float(d[as_index(targets, n, "targets")])
    return d[as_indices(targets, n, "targets")]


def _eigen_distance(lap, filt, s, k, delta):
    """Truncated-eigenpair distance from s to all vertices (the classical baseline)."""
    k = 100 if not k else int(k)
    lam, W = low_rank(lap, max(1, min(k, lap.n)), delta)
    w = np.abs(phi_values(filt, lam, lap.n_components)) ** 2
    d2 = ((W - W[s]) ** 2) @ w
    return np.sqrt(np.maximum(d2, 0.0))


def pairwise_spectral_distance(lap, filt, seeds, delta: str = "mass", method: str = "auto",
                               tol: float = 1e-8, progress=None, block: int = 16,
                               return_info: bool = False):
    r"""(m, m) spectral distances between all pairs of ``seeds``.

    .. math:: D_{ab} = \|\varphi(\tilde L)B^{-1}(e_{s_a} - e_{s_b})\|_B

    The filter is :math:`\varphi` itself and the distance uses :math:`|\varphi|^2`, as in
    :func:`spectral_distance`: ``pairwise_spectral_distance(lap, filters.heat(t), S)`` is
    the diffusion distance at time :math:`2t`, since :math:`|e^{-ts}|^2 = e^{-2ts}`. For
    the named distances use :func:`pairwise_diffusion_distance` (time ``t`` as in
    :func:`diffusion_distance`), :func:`pairwise_biharmonic_distance`, ..., which pass
    the filter whose square is the named one.

    From the m kernel columns :math:`C = \varphi(\tilde L)B^{-1}E_S` (m engine
    applications) and their Gram matrix :math:`C^* B C`; any entry lost to cancellation
    is recomputed as the norm of the column difference, so the result is never negative.

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
    seeds : (m,) int
        Vertex indices.
    delta : {"mass", "seed"}
        As in :func:`spectral_distance`.
    method : str
        Engine approximation method (default ``"auto"``).
    tol : float
        Engine accuracy (default 1e-8).
    progress : bool, optional
        A progress bar on stderr, one step per block of ``block`` seeds (see
        :mod:`spectral_igl.progress`; default off).
    block : int
        Kernel columns computed together: one step of the bar.
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` (m, m), a bound of
        every :math:`|D_{ab} - \tilde D_{ab}|`: the B-norm bounds :math:`\beta_a + \beta_b` of
        the two columns (reverse triangle inequality) plus the rounding of the Gram matrix
        through :func:`root_error`; ``bound_kind``, ``method``, ``tol`` and ``bnorm_error``
        (the :math:`\beta_a`).

    Returns
    -------
    D : (m, m) float
        Symmetric, zero diagonal.
    info : dict
        Only with ``return_info=True``.

    Examples
    --------
    The heat filter at t/2 gives the diffusion distance at t:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D, info = sig.pairwise_spectral_distance(lap, sig.filters.heat(0.05), [0, 5, 9], return_info=True)
    >>> lam, X = sig.dense_eigs(lap)
    >>> Y = X[[0, 5, 9]] * np.exp(-0.05 * lam)
    >>> exact = np.sqrt(((Y[:, None] - Y[None]) ** 2).sum(-1))
    >>> bool(np.all(np.abs(D - exact) <= info["abs_error"])), info["bound_kind"]
    (True, 'proof')
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    delta = as_delta(delta)
    S = as_indices(seeds, lap.n, "seeds")
    m = S.size
    check_dense_size(8.0 * (2 * lap.n * m + 4 * m * m),
                     f"the kernel columns ({lap.n}, {m}) and the ({m}, {m}) distance matrix of {m} seeds",
                     "use fewer seeds, or OneToAll(lap, filt).distance(seed) one seed at a time")
    block = as_int(block, "block", lo=1)
    return_info = as_flag(return_info, "return_info")
    if filt.kind == "heat" and block_sources(lap, method, delta, S.size):
        # one factorization per pole, every seed in one block right-hand side
        C, hinfo = heat_kernels(lap, [filt.params["t"]], S, tol=tol, return_info=True)
        C, beta, kind, used = C[:, :, 0], hinfo["bnorm_error"][:, 0], hinfo["bound_kind"], hinfo["method"]
    else:
        op = spectral_operator(lap, filt, method, tol)
        blocks = np.array_split(S, -(-S.size // max(int(block), 1)))
        with progress_bar(len(blocks), "pairwise distances", progress, unit="block") as bar:
            cols, beta = [], []
            for blk in blocks:
                c, b = kernel_columns(lap, filt, blk, delta=delta, op=op, return_bound=True)
                cols.append(c)
                beta.append(b)
                bar.update()
        C, beta, kind, used = np.concatenate(cols, axis=1), np.concatenate(beta), op.bound_kind, op.method
    BC = lap.B @ C
    Gm = np.real(np.conj(C).T @ BC)
    g = np.diag(Gm).copy()
    D2 = g[:, None] + g[None, :] - 2.0 * Gm
    bad = np.argwhere(np.triu(D2 <= 1e-10 * (g[:, None] + g[None, :]), 1))
    for a, b in bad:
        diff = C[:, a] - C[:, b]
        D2[a, b] = D2[b, a] = float(np.real(np.vdot(diff, lap.B @ diff)))
    D2 = (D2 + D2.T) / 2.0
    np.fill_diagonal(D2, 0.0)
    D = np.sqrt(np.maximum(D2, 0.0))
    if not return_info:
        return D
    # |D_ab - ||C~_a - C~_b||_B| <= beta_a + beta_b; the computed D2 is within the Gram
    # products' rounding of ||C~_a - C~_b||_B^2, |C_a|^T B |C_b| <= sqrt(g_a g_b) / c
    r = np.sqrt(np.maximum(g, 0.0))
    rounding = 2.0 * _norm_rounding(lap) * (r[:, None] + r[None, :]) ** 2
    err = beta[:, None] + beta[None, :] + root_error(D, rounding)
    np.fill_diagonal(err, 0.0)
    kind = weakest(kind, lambda_max_kind(lap)) if np.all(np.isfinite(beta)) else None
    return D, bound_info(err, kind, used, tol=tol, bnorm_error=beta)


# ---------------------------------------------------------------------------------------
# named distances
# ---------------------------------------------------------------------------------------
def _timed(lap, t, time_unit):
    """``(lap, t)``: the Laplacian from any input and ``t`` in absolute units
    (:mod:`spectral_igl.laplacian.units`)."""
    lap = as_laplacian(lap)
    return lap, shape_time(lap, t, time_unit)


def diffusion_distance(lap, t, source, targets=None, time_unit: str = "absolute", **kwargs):
    r"""Diffusion distance at time ``t``: :math:`|\varphi|^2(s) = e^{-ts}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Diffusion time, :math:`t > 0`, in the units ``time_unit``.
    [one-to-all parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d_t^2(i, j) = \sum_l e^{-t\lambda_l} |x_l(i) - x_l(j)|^2 = K_t(i,i) + K_t(j,j) - 2K_t(i,j)

    with :math:`K_t = e^{-t\tilde L}B^{-1}` the heat kernel (the survey's diffusion distance,
    with :math:`B^{-1}e_i` for the delta so that it converges under refinement): the filter
    passed to :func:`spectral_distance` is ``heat(t / 2)``.

    With a few ``targets`` and ``method="auto"`` on a Metzler operator above
    :data:`~spectral_igl.kernels.LOCAL_MIN_VERTICES` vertices, each distance is the B-norm of a
    difference of two heat columns at time t/2 solved on regions around their sources
    (:func:`~spectral_igl.local_heat_kernel`), with the sum of their proved B-norm bounds;
    ``info["method"]`` is then ``"local"``. The one-to-all row needs the heat kernel
    signature of every vertex and stays on the global diagonal.

    The survey's §6.2.1 (diffusion distances) and §6.3 (their discretization).

    Examples
    --------
    Against the dense eigendecomposition of a small sphere:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.diffusion_distance(lap, 0.1, 0)
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = np.sqrt((X[0] - X) ** 2 @ np.exp(-0.1 * lam))
    >>> d.shape, bool(np.max(np.abs(d - exact)) < 1e-6)
    ((162,), True)
    """
    lap, t = _timed(lap, t, time_unit)
    return spectral_distance(lap, heat(t / 2.0), source, targets, **kwargs)


def commute_time_distance(lap, source, targets=None, **kwargs):
    r"""Commute-time distance: :math:`|\varphi|^2(s) = s^{-1}` on the complement of ker L.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    [one-to-all parameters]
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d^2(i, j) = \sum_{\lambda_l > 0} \lambda_l^{-1} |x_l(i) - x_l(j)|^2

    On surfaces it diverges logarithmically under refinement (the Green's function is
    singular at the diagonal); it is scale invariant in 2-D.

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.commute_time_distance(lap, 0, [1, 2, 3])
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = np.sqrt((X[0] - X[[1, 2, 3]])[:, 1:] ** 2 @ (1 / lam[1:]))
    >>> bool(np.max(np.abs(d - exact)) < 1e-6)
    True
    """
    return spectral_distance(lap, commute_time(), source, targets, **kwargs)


def biharmonic_distance(lap, source, targets=None, **kwargs):
    r"""Biharmonic distance (Lipman et al. 2010): :math:`|\varphi|^2(s) = s^{-2}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    [one-to-all parameters]
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d^2(i, j) = \sum_{\lambda_l > 0} \lambda_l^{-2} |x_l(i) - x_l(j)|^2

    Lipman et al.'s definition (the survey's biharmonic distance): smooth, and convergent
    under refinement on surfaces.

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d, info = sig.biharmonic_distance(lap, 0, return_info=True)
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = np.sqrt((X[0] - X)[:, 1:] ** 2 @ lam[1:] ** -2.0)
    >>> bool(np.all(np.abs(d - exact) <= info["abs_error"])), info["bound_kind"]
    (True, 'proof')
    """
    return spectral_distance(lap, biharmonic(), source, targets, **kwargs)


def polyharmonic_distance(lap, k, source, targets=None, **kwargs):
    r"""Poly-harmonic distance of integer order ``k``: :math:`|\varphi|^2(s) = s^{-k}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    k : int
        The order, 1 to :data:`MAX_ORDER` (16): :math:`\lambda^{-k}` spans
        :math:`(\lambda_{max}/\lambda_{min})^k`, beyond double precision for larger orders on
        any mesh, and the distance is then that of the first eigenfunction alone.
    [one-to-all parameters]
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d^2(i, j) = \sum_{\lambda_l > 0} \lambda_l^{-k} |x_l(i) - x_l(j)|^2

    ``k = 1`` is the commute-time distance, ``k = 2`` the biharmonic one.

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.polyharmonic_distance(lap, 3, 0, 7)
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = np.sqrt((X[0] - X[7])[1:] ** 2 @ lam[1:] ** -3.0)
    >>> bool(abs(d - exact) < 1e-6 * exact)
    True
    """
    k = as_int(k, "k", lo=1, hi=MAX_ORDER)
    return spectral_distance(lap, polyharmonic(k), source, targets, **kwargs)


def wave_distance(lap, t, source, targets=None, time_unit: str = "absolute", **kwargs):
    r"""Spectral distance of the Schrödinger wave kernel :math:`\varphi(s) = e^{-ist}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Time of the wave propagator, in the units ``time_unit`` (the distance does not
        depend on it, see Notes).
    [one-to-all parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d^2(i, j) = \sum_l |e^{-i\lambda_l t}|^2 |x_l(i) - x_l(j)|^2
              = \|B^{-1}(e_i - e_j)\|_B^2

    The wave propagator is unitary, :math:`|\varphi|^2 = 1`, so this distance does not
    depend on ``t``: it is the B-norm of the difference of the two discrete deltas
    (and grows under refinement). Provided for completeness of the survey's family.

    The survey's §6.1 (the filter's choice, Fig. 10) and §6.3.

    Examples
    --------
    With a lumped mass matrix the distance between two vertices is
    :math:`\sqrt{1/m_i + 1/m_j}`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.wave_distance(lap, 0.3, 0, 5)
    >>> bool(abs(d - np.sqrt(1 / lap.mass[0] + 1 / lap.mass[5])) < 1e-6 * d)
    True
    """
    lap, t = _timed(lap, t, time_unit)
    return spectral_distance(lap, wave(t), source, targets, **kwargs)


def mexican_hat_distance(lap, t, source, targets=None, time_unit: str = "absolute", **kwargs):
    r"""Mexican-hat distance: :math:`\varphi(s) = t s e^{-ts}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Scale of the wavelet, :math:`t > 0`, in the units ``time_unit``.
    [one-to-all parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [one-to-all options]

    Returns
    -------
    [one-to-all returns]

    Notes
    -----
    .. math:: d^2(i, j) = \sum_l t^2\lambda_l^2 e^{-2t\lambda_l} |x_l(i) - x_l(j)|^2

    The survey's §6.1 (the filter's choice, Fig. 10) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> d = sig.mexican_hat_distance(lap, 0.1, 0, [4, 9])
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = np.sqrt((X[0] - X[[4, 9]]) ** 2 @ (0.1 * lam * np.exp(-0.1 * lam)) ** 2)
    >>> bool(np.max(np.abs(d - exact)) < 1e-6)
    True
    """
    lap, t = _timed(lap, t, time_unit)
    return spectral_distance(lap, mexican_hat(t), source, targets, **kwargs)


class OneToAll:
    r"""One-to-all spectral distances of one filter on one shape, precomputed once.

    The kernel diagonal :math:`G_{jj}` (and, for ``diagonal="selinv"``, the factorizations
    of its partial fractions, kept in ``lap.cache`` within its factor budget) is computed
    when the object is made; each :meth:`distance` then costs about one kernel column. The
    one-call functions (:func:`spectral_distance`, :func:`diffusion_distance`, ...) keep the
    diagonal too, and the factorizations when all of them fit in the factor budget (a second
    source then costs about one column: 0.2 of a Cholesky factorization for diffusion on a
    43k-vertex mesh); when they do not fit, they hold one factorization at a time (the least
    memory) and a second source pays the factorizations again but not the selected
    inversion. For many sources this object states the intent.

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        :math:`\varphi` (the distance uses :math:`|\varphi|^2`).
    **options
        ``delta``, ``method``, ``tol``, ``diagonal`` and the diagonal estimator's
        parameters, as in :func:`spectral_distance`.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> solver = sig.OneToAll(lap, sig.filters.biharmonic())
    >>> d0, d5 = solver.distance(0), solver.distance(5)
    >>> bool(abs(d0[5] - d5[0]) < 1e-8)
    True
    """

    def __init__(self, lap, filt, **options):
        self.lap = as_laplacian(lap)
        self.filter = check_filter(filt)
        if "targets" in options or "return_info" in options:
            raise TypeError("OneToAll takes targets and return_info in distance(), not here")
        self.options = options
        keys = ("method", "delta", "k", "distance", "samples", "rtol", "max_colours", "tol")
        diag_opts = {("engine_method" if k == "method" else k): v for k, v in options.items() if k in keys}
        diag_opts["method"] = options.get("diagonal", "auto")
        G2 = self.filter.square
        delta = options.get("delta", "mass")
        kern = _coming_selinv_kernel(self.lap, G2, diag_opts["method"], delta, options.get("tol", 1e-8))
        if kern is not None:   # the factorizations stay (within the budget) for the columns to come
            kern.keep_factors = True
        if diag_opts["method"] != "eigen":
            self.diagonal, self.info = kernel_diagonal(self.lap, self.filter.square, return_info=True,
                                                       **diag_opts)
        else:
            self.diagonal, self.info = None, {"method": "eigen"}

    def distance(self, source, targets=None, return_info: bool = False):
        """Distances from ``source`` to ``targets`` (all vertices by default); see
        :func:`spectral_distance`."""
        return spectral_distance(self.lap, self.filter, source, targets, return_info=return_info,
                                 **self.options)

    def __repr__(self) -> str:
        return f"OneToAll({self.filter!r}, n={self.lap.n}, diagonal={self.info.get('method')!r})"


# ---------------------------------------------------------------------------------------
# named pairwise distances: the same filters as the one-to-all functions above
# ---------------------------------------------------------------------------------------
def pairwise_diffusion_distance(lap, t, seeds, time_unit: str = "absolute", **kwargs):
    r"""(m, m) diffusion distances at time ``t`` between ``seeds``; entries equal
    :func:`diffusion_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Diffusion time, :math:`t > 0`, in the units ``time_unit``.
    [pairwise parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_l e^{-t\lambda_l} |x_l(s_a) - x_l(s_b)|^2

    (the filter passed to :func:`pairwise_spectral_distance` is ``heat(t / 2)``).

    The survey's §6.2.1 (diffusion distances) and §6.3 (their discretization).

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.pairwise_diffusion_distance(lap, 0.1, [0, 5, 9])
    >>> d = sig.diffusion_distance(lap, 0.1, 5, [0, 5, 9])
    >>> D.shape, bool(np.allclose(D, D.T)), bool(np.max(np.abs(D[1] - d)) < 1e-6)
    ((3, 3), True, True)
    """
    lap, t = _timed(lap, t, time_unit)
    return pairwise_spectral_distance(lap, heat(t / 2.0), seeds, **kwargs)


def pairwise_commute_time_distance(lap, seeds, **kwargs):
    r"""(m, m) commute-time distances between ``seeds``; entries equal
    :func:`commute_time_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    [pairwise parameters]
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_{\lambda_l>0}\lambda_l^{-1}|x_l(s_a)-x_l(s_b)|^2

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.pairwise_commute_time_distance(lap, [0, 5, 9])
    >>> d = sig.commute_time_distance(lap, 9, [0, 5, 9])
    >>> bool(np.max(np.abs(D[2] - d)) < 1e-6), float(D[2, 2])
    (True, 0.0)
    """
    return pairwise_spectral_distance(lap, commute_time(), seeds, **kwargs)


def pairwise_biharmonic_distance(lap, seeds, **kwargs):
    r"""(m, m) biharmonic distances between ``seeds``; entries equal :func:`biharmonic_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    [pairwise parameters]
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_{\lambda_l>0}\lambda_l^{-2}|x_l(s_a)-x_l(s_b)|^2

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D, info = sig.pairwise_biharmonic_distance(lap, [0, 5, 9], return_info=True)
    >>> lam, X = sig.dense_eigs(lap)
    >>> Y = X[[0, 5, 9], 1:] / lam[1:]
    >>> exact = np.sqrt(((Y[:, None] - Y[None]) ** 2).sum(-1))
    >>> bool(np.all(np.abs(D - exact) <= info["abs_error"])), info["bound_kind"]
    (True, 'proof')
    """
    return pairwise_spectral_distance(lap, biharmonic(), seeds, **kwargs)


def pairwise_polyharmonic_distance(lap, k, seeds, **kwargs):
    r"""(m, m) poly-harmonic distances of order ``k`` between ``seeds``; entries equal
    :func:`polyharmonic_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    k : int
        The order, 1 to :data:`MAX_ORDER` (16), as in :func:`polyharmonic_distance`.
    [pairwise parameters]
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_{\lambda_l>0}\lambda_l^{-k}|x_l(s_a)-x_l(s_b)|^2

    The survey's §6.2.2 (commute-time and biharmonic distances) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.pairwise_polyharmonic_distance(lap, 2, [0, 5, 9])
    >>> B = sig.pairwise_biharmonic_distance(lap, [0, 5, 9])
    >>> bool(np.max(np.abs(D - B)) < 1e-6)
    True
    """
    k = as_int(k, "k", lo=1, hi=MAX_ORDER)
    return pairwise_spectral_distance(lap, polyharmonic(k), seeds, **kwargs)


def pairwise_wave_distance(lap, t, seeds, time_unit: str = "absolute", **kwargs):
    r"""(m, m) wave-kernel distances between ``seeds``; entries equal :func:`wave_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Time of the wave propagator, in the units ``time_unit`` (the distance does not
        depend on it: :math:`|\varphi|^2 = 1`).
    [pairwise parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_l |x_l(s_a) - x_l(s_b)|^2 = \|B^{-1}(e_{s_a} - e_{s_b})\|_B^2

    The survey's §6.1 (the filter's choice, Fig. 10) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.pairwise_wave_distance(lap, 0.3, [0, 5])
    >>> bool(abs(D[0, 1] - np.sqrt(1 / lap.mass[0] + 1 / lap.mass[5])) < 1e-6 * D[0, 1])
    True
    """
    lap, t = _timed(lap, t, time_unit)
    return pairwise_spectral_distance(lap, wave(t), seeds, **kwargs)


def pairwise_mexican_hat_distance(lap, t, seeds, time_unit: str = "absolute", **kwargs):
    r"""(m, m) Mexican-hat distances between ``seeds``; entries equal
    :func:`mexican_hat_distance`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Scale of the wavelet, :math:`t > 0`, in the units ``time_unit``.
    [pairwise parameters]
    time_unit : str
        ``"absolute"`` (default), or times in the shape's units
        (:mod:`spectral_igl.laplacian.units`).
    [pairwise options]

    Returns
    -------
    [pairwise returns]

    Notes
    -----
    .. math:: D_{ab}^2 = \sum_l t^2\lambda_l^2 e^{-2t\lambda_l} |x_l(s_a) - x_l(s_b)|^2

    The survey's §6.1 (the filter's choice, Fig. 10) and §6.3.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> D = sig.pairwise_mexican_hat_distance(lap, 0.1, [0, 5, 9])
    >>> d = sig.mexican_hat_distance(lap, 0.1, 0, [0, 5, 9])
    >>> bool(np.max(np.abs(D[0] - d)) < 1e-6)
    True
    """
    lap, t = _timed(lap, t, time_unit)
    return pairwise_spectral_distance(lap, mexican_hat(t), seeds, **kwargs)


# ---------------------------------------------------------------------------------------
# the sections the named distances share, written once
# ---------------------------------------------------------------------------------------
_SHARED_SECTIONS = {
    "one-to-all parameters": """\
    source : int
        Vertex index of the source.
    targets : None, int or (m,) int
        ``None`` (default): every vertex (one-to-all); otherwise the target vertices, each
        distance the exact B-norm of one filtered difference of deltas.""",
    "one-to-all options": """\
    **kwargs
        ``delta``, ``method``, ``tol``, ``diagonal``, ``k``, ``distance``, ``samples``,
        ``rtol``, ``max_colours``, ``max_recompute``, ``return_info``, ``progress``: as in
        :func:`spectral_distance` (``delta="mass"``, ``method="auto"``, ``tol=1e-8``,
        ``diagonal="auto"`` by default).""",
    "one-to-all returns": """\
    d : float, (m,) float or (n,) float
        The distances: a float for an integer target, one per target, or one per vertex.
    info : dict
        Only with ``return_info=True``: ``abs_error`` (a bound of every :math:`|d - \\tilde d|`,
        shaped as ``d``), ``bound_kind`` and ``method``; see :func:`spectral_distance`.""",
    "pairwise parameters": """\
    seeds : (m,) int
        Vertex indices.""",
    "pairwise options": """\
    **kwargs
        ``delta``, ``method``, ``tol``, ``progress``, ``block``, ``return_info``: as in
        :func:`pairwise_spectral_distance` (``delta="mass"``, ``method="auto"``,
        ``tol=1e-8`` by default).""",
    "pairwise returns": """\
    D : (m, m) float
        Symmetric, zero diagonal: ``D[a, b]`` is the distance between ``seeds[a]`` and
        ``seeds[b]``.
    info : dict
        Only with ``return_info=True``: ``abs_error`` (m, m), a bound of every
        :math:`|D_{ab} - \\tilde D_{ab}|`, ``bound_kind`` and ``method``; see
        :func:`pairwise_spectral_distance`.""",
}


def _fill_shared_sections(fn):
    """Put the shared sections in place of their ``[name]`` lines in ``fn``'s docstring."""
    for key, text in _SHARED_SECTIONS.items():
        fn.__doc__ = fn.__doc__.replace(f"    [{key}]", text)
    return fn


for _fn in (diffusion_distance, commute_time_distance, biharmonic_distance, polyharmonic_distance,
            wave_distance, mexican_hat_distance, pairwise_diffusion_distance,
            pairwise_commute_time_distance, pairwise_biharmonic_distance, pairwise_polyharmonic_distance,
            pairwise_wave_distance, pairwise_mexican_hat_distance):
    _fill_shared_sections(_fn)
