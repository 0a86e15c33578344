r"""Spectral kernels :math:`K = \varphi(\tilde L) B^{-1}`, evaluated column by column.

The discrete kernel of a filter :math:`\varphi` is the symmetric matrix

.. math:: K = \varphi(\tilde L)\, B^{-1} = X \varphi(\Lambda) X^\top,

whose column ``i`` is :math:`\varphi(\tilde L)` applied to the discrete delta
:math:`B^{-1} e_i`; it converges to the smooth kernel :math:`K(p_i, \cdot)` under
refinement. Nothing here computes eigenpairs: every column is one application of the
spectral engine (:class:`spectral_igl.SpectralOperator`), with its certified error bound.
"""
from __future__ import annotations

import numbers
import warnings

import numpy as np

from .accuracy import info as make_info
from .accuracy import AccuracyWarning, relative_error, warn_missed, weakest
from ._validate import as_delta, as_flag, as_index, as_indices, as_tol, check_dense_size
from .approx import spectral_operator
from .approx.region import region_heat_column
from .approx.uniformization import metzler_heat, products_needed
from .diagonal import EXACT_MAX as DENSE_LIMIT
from .families import heat_columns
from .filters import check_filter, heat
from .laplacian import Laplacian, as_laplacian, entry_error, lambda_max_kind, mass_ratio, shape_time

__all__ = ["spectral_kernel", "heat_kernel", "heat_kernels", "kernel_columns", "source_indices", "BLOCK",
           "block_sources", "MANY_SOURCES", "LOCAL_MIN_VERTICES"]

#: columns per engine call; bounds the (n, block) work arrays
BLOCK = 64



def _unit_columns(n: int, idx: np.ndarray, weights=None) -> np.ndarray:
    E = np.zeros((n, idx.size))
    E[idx, np.arange(idx.size)] = 1.0 if weights is None else weights
    return E


def kernel_columns(lap, filt, idx, delta: str = "mass", method: str = "auto", tol: float = 1e-8,
                   op=None, return_bound: bool = False):
    r"""(n, m) columns ``idx`` of the kernel: :math:`\varphi(\tilde L)B^{-1}e_i` (``delta="mass"``)
    or :math:`\varphi(\tilde L)e_i` (``delta="seed"``), in blocks of :data:`BLOCK`.

    With ``return_bound`` also returns the (m,) certified B-norm error bound of each column.
    """
    n = lap.n
    idx = np.asarray(idx, dtype=np.int64).reshape(-1)
    check_dense_size(16.0 * n * idx.size, f"{idx.size} dense kernel columns of length {n}",
                     "ask for fewer sources at a time, or for distances/diagonals, which need no columns")
    op = spectral_operator(lap, filt, method, tol) if op is None else op
    dtype = np.complex128 if getattr(filt, "is_complex", False) else np.float64
    out = np.empty((n, idx.size), dtype=dtype)
    bound = np.zeros(idx.size)
    for a in range(0, idx.size, BLOCK):
        sl = slice(a, min(a + BLOCK, idx.size))
        E = _unit_columns(n, idx[sl])
        Y = op.apply_inverse_mass(E) if delta == "mass" else op.apply(E)
        out[:, sl] = Y
        bound[sl] = _as_bound(getattr(op, "error_bound", np.nan), sl.stop - sl.start)
    return (out, bound) if return_bound else out


def _as_bound(b, m: int) -> np.ndarray:
    b = np.asarray(b if b is not None else np.nan, dtype=float).reshape(-1)
    return np.broadcast_to(b, (m,)).copy() if b.size in (1, m) else np.full(m, np.nan)


def source_indices(sources, n: int):
    """(indices, scalar?) for a vertex index or a 1-D array of them. A scalar must be an
    integer (a float such as 5.0 is refused, not read as the array [5])."""
    if isinstance(sources, (numbers.Number, np.generic)) or (isinstance(sources, np.ndarray) and sources.ndim == 0):
        return np.array([as_index(sources, n, "source")]), True
    return as_indices(sources, n, "sources"), False


#: default floor of the per-entry tolerance: entries below this fraction of their column's peak
#: are not bound relatively
FLOOR = 1e-10
#: the smallest B-norm tolerance the engine is asked for when tightening for ``rtol``
#: (below it the rounding of the solves dominates)
TIGHTEST = 1e-13
#: sparse products per block of columns that the cancellation-free heat path may take
MAX_PRODUCTS = 20000
#: up to this many products (each about 1/400 of a Cholesky of the same size), ``rtol`` heat
#: columns go straight to the cancellation-free path instead of trying the rational one first
DIRECT_PRODUCTS = 400


def _column_info(lap, filt, K, bnorm, kind, method, tol):
    """The accuracy ``info`` of kernel columns (:mod:`spectral_igl.accuracy`): the per-entry
    bound from the B-norm bounds; heat columns of a Metzler operator clipped at 0 (the exact
    kernel is non-negative there, so clipping only moves an entry closer to it)."""
    bnorm = np.asarray(bnorm, dtype=float)
    if kind is None or not np.all(np.isfinite(bnorm)):
        return K, make_info(np.full(K.shape, np.nan), None, method, tol=tol, bnorm_error=bnorm)
    err = entry_error(lap, bnorm)
    kind = weakest(kind, lambda_max_kind(lap))
    if filt.kind == "heat" and lap.is_metzler:
        K = np.maximum(K, 0.0)
    return K, make_info(err, kind, method, tol=tol, bnorm_error=bnorm)


def _misses(K, info, rtol, floor):
    """Columns where an entry above ``floor`` of the column's peak is not proved within ``rtol``,
    and the B-norm bound each column would need."""
    mag = np.abs(K)
    peak = np.max(mag, axis=0)
    need = mag >= floor * peak[None, :]
    rel = relative_error(K, info["abs_error"])
    bad = np.any(need & ~(rel <= rtol), axis=0)
    # |e_j| <= bnorm * w_j, and rel <= rtol needs |e_j| <= rtol |K_j| / (1 + rtol)
    w = info["abs_error"] / np.where(info["bnorm_error"] > 0, info["bnorm_error"], np.inf)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        allowed = np.where(need, rtol / (1.0 + rtol) * mag / w, np.inf)
    return bad, np.min(allowed, axis=0)


def _uniform_tail(lap, idx, rtol, floor):
    """Truncation of the uniformization well below rtol * floor * peak, with peak >= 1 / area
    (heat is conserved) and the largest input 1 / m_i."""
    return 1e-3 * rtol * floor * float(np.min(lap.mass[idx])) / lap.area() if floor > 0 else 1e-300


def _uniformized(lap, t, idx, tol, rtol, floor):
    """Heat columns by the cancellation-free uniformization, with their ``info``."""
    tail = _uniform_tail(lap, idx, rtol, floor)
    G = np.zeros((lap.n, idx.size))
    G[idx, np.arange(idx.size)] = 1.0 / lap.mass[idx]
    U, err = metzler_heat(lap, t, G, tail)
    rel = relative_error(U, err)
    work = products_needed(lap, t, tail)
    if np.any((U >= floor * U.max(axis=0)[None, :]) & ~(rel <= rtol)):
        raise ValueError(f"rtol={rtol:g}: not reached even without cancellation (rounding of "
                         f"{work} sparse products); ask for a larger rtol")
    return U, make_info(err, "proof", "uniformization", tol=tol, rtol=rtol, floor=floor, rel_error=rel,
                        bnorm_error=np.full(idx.size, np.nan), products=work)


def _entrywise(lap, filt, idx, delta, method, tol, rtol, floor):
    """Kernel columns with every entry above ``floor`` of its column's peak proved within
    ``rtol`` of the truth, or a ValueError saying why not."""
    uniform = method == "auto" and filt.kind == "heat" and delta == "mass" and lap.is_metzler
    if uniform:
        work = products_needed(lap, filt.params["t"], _uniform_tail(lap, idx, rtol, floor))
        # straight to the only path that reaches far entries when it is cheaper than a rational
        # column, or when no B-norm accuracy can reach them (|e_j| >= TIGHTEST |delta|_B / ...)
        if work <= DIRECT_PRODUCTS or (work <= MAX_PRODUCTS and rtol * floor < TIGHTEST):
            return _uniformized(lap, filt.params["t"], idx, tol, rtol, floor)
    with warnings.catch_warnings():   # a missed tol here is judged by rtol below, not reported
        warnings.simplefilter("ignore", AccuracyWarning)
        K, bnorm = kernel_columns(lap, filt, idx, delta=delta, method=method, tol=tol, return_bound=True)
    op = spectral_operator(lap, filt, method, tol)
    K, info = _column_info(lap, filt, K, bnorm, op.bound_kind, op.method, tol)
    if info["bound_kind"] != "proof":
        raise ValueError(f"rtol: the bound of method {op.method!r} for {filt!r} is "
                         f"{'missing' if info['bound_kind'] is None else 'an estimate'}, so no entry can "
                         f"be proved within rtol={rtol:g}; use method='auto' with a built-in filter")
    bad, allowed = _misses(K, info, rtol, floor)
    if not bad.any():
        return K, dict(info, rtol=rtol, floor=floor, rel_error=relative_error(K, info["abs_error"]))
    norms = info["bnorm_error"] / tol if tol > 0 else None
    want = float(np.min(0.5 * allowed[bad] / np.maximum(norms[bad], np.finfo(float).tiny)))
    if method == "auto" and want >= TIGHTEST:
        return _entrywise(lap, filt, idx, delta, method, want, rtol, floor)
    if uniform:
        if work <= MAX_PRODUCTS:
            return _uniformized(lap, filt.params["t"], idx, want, rtol, floor)
        why = (f"the cancellation-free evaluation needs {work} sparse products at t={filt.params['t']:g} "
               f"(more than {MAX_PRODUCTS}: a large t, or elements that make lambda_max large)")
    elif method != "auto":
        why = f"method={method!r} was asked for; method='auto' tightens tol or avoids cancellation"
    elif filt.kind == "heat":
        why = ("the operator is not Metzler (a full mass matrix or positive off-diagonal stiffness), so "
               "no cancellation-free evaluation applies")
    else:
        why = f"{filt!r} changes sign, so its small entries come from cancelling sums"
    raise ValueError(f"rtol={rtol:g} above floor={floor:g} of the peak cannot be proved: the entries "
                     f"need a B-norm accuracy of {want:.2g} relative, below what double precision "
                     f"reaches ({TIGHTEST:g}), and {why}. Raise floor or rtol, or drop rtol for the "
                     "B-norm bound (return_info=True gives every entry's bound)")


def _kernel(lap, filt, sources, delta, method, tol, return_info, rtol, floor):
    idx, scalar = source_indices(sources, lap.n)
    if filt.kind == "heat":
        lap.warn_if_not_metzler("heat kernel", stacklevel=4)
    return_info = as_flag(return_info, "return_info")
    if rtol is not None:
        rtol = as_tol(rtol, "rtol")
        floor = as_tol(floor, "floor", allow_zero=True)
        K, info = _entrywise(lap, filt, idx, delta, method, tol, rtol, floor)
    else:
        K, bnorm = kernel_columns(lap, filt, idx, delta=delta, method=method, tol=tol, return_bound=True)
        op = spectral_operator(lap, filt, method, tol)
        K, info = _column_info(lap, filt, K, bnorm, op.bound_kind, op.method, tol)
    if scalar:
        K = K[:, 0]
        info = {k: (v[:, 0] if isinstance(v, np.ndarray) and v.ndim == 2 else
                    (float(v[0]) if isinstance(v, np.ndarray) and v.ndim == 1 else v))
                for k, v in info.items()}
    return (K, info) if return_info else K


# ---------------------------------------------------------------------------------------
# public API
# ---------------------------------------------------------------------------------------
_ACCURACY_DOC = r"""
    tol : float
        Target accuracy of the engine: the B-norm error of each column relative to
        :math:`\|B^{-1}e_i\|_B`. A column whose bound misses it warns
        (:class:`spectral_igl.accuracy.AccuracyWarning`).
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error``, a bound of the error
        of **every entry**, ``bound_kind`` (``"proof"``/``"estimate"``), ``method``,
        ``bnorm_error`` (each column's B-norm bound) and, with ``rtol``, ``rel_error``.
        By default (no ``rtol``) an entry is within
        :math:`\texttt{tol}\,\|B^{-1}e_i\|_B / \sqrt{c\,D_{jj}}` of the truth, D the lumped mass and
        c = 1 for a lumped, 1/4 (1/5) for the full triangle (tet) mass: on a unit-area mesh of n
        even vertices about ``tol * n`` absolute, against a peak of about :math:`1/(4\pi t)`, so
        entries far below ``tol * n`` times the peak may carry no correct digit.
    rtol, floor : float, optional
        Per-entry accuracy on request: every entry at or above ``floor`` (default 1e-10) times its
        column's peak is proved within ``rtol`` of the truth, relatively, or the call raises
        ValueError with the reason. ``method="auto"`` first tightens ``tol`` (down to 1e-13),
        then, for the heat kernel of a Metzler operator (lumped mass, non-negative weights),
        evaluates without cancellation (:mod:`spectral_igl.approx.uniformization`: every entry
        to about 1e-13 relative, at a cost of about :math:`1.6\,t\lambda` sparse products,
        refused beyond 20,000).
"""


def spectral_kernel(lap: Laplacian, filt, sources, delta: str = "mass", method: str = "auto",
                    tol: float = 1e-8, return_info: bool = False, rtol: float | None = None,
                    floor: float = FLOOR):
    r"""Columns :math:`K(:, i)` of the spectral kernel :math:`K = \varphi(\tilde L)B^{-1}`.

    .. math:: K(:, i) = \varphi(\tilde L) B^{-1} e_i = \sum_l \varphi(\lambda_l)\, x_l(i)\, x_l

    computed spectrum-free (one application of the engine per column), never from
    truncated eigenpairs, with a bound of every entry.

    Parameters
    ----------
    lap : Laplacian
    filt : spectral_igl.filters.Filter
        The filter :math:`\varphi` (``filters.heat(t)``, ``filters.biharmonic()``, ...).
        Singular filters act on the B-orthogonal complement of ker L.
    sources : int or (m,) int
        Vertex index, or indices, of the kernel's source points.
    delta : {"mass", "seed"}
        ``"mass"`` (default) uses the discrete delta :math:`B^{-1}e_i`, so that
        ``K[j, i]`` converges to :math:`K(p_j, p_i)` under refinement and ``K`` is
        symmetric. ``"seed"`` applies the filter to :math:`e_i` itself (the survey's
        Eq. (5) as printed): mesh dependent, offered for comparison only.
    method : str
        Approximation method of the engine (``"auto"``, ``"rational"``, ``"dense"``, ...).
    {accuracy}

    Returns
    -------
    K : (n,) or (n, m) float
        One column for a single source, (n, m) for m sources (complex for a complex filter
        such as the wave kernel).
    info : dict
        Only with ``return_info=True`` (entries shaped as ``K``).

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> k, info = sig.spectral_kernel(lap, sig.filters.heat(0.1), 0, return_info=True)
    >>> k.shape, info["bound_kind"], bool(info["abs_error"].max() < 1e-6)
    ((162,), 'proof', True)
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    delta = as_delta(delta)
    return _kernel(lap, filt, sources, delta, method, tol, return_info, rtol, floor)


def heat_kernel(lap: Laplacian, t: float, sources, delta: str = "mass", method: str = "auto",
                tol: float = 1e-8, return_info: bool = False, rtol: float | None = None,
                floor: float = FLOOR, time_unit: str = "absolute"):
    r"""Columns of the heat kernel :math:`K_t = e^{-t\tilde L}B^{-1}`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float
        Time, :math:`t > 0`, in the units ``time_unit``.
    sources : int or (m,) int
        Vertex index, or indices, of the kernel's source points.
    delta : {"mass", "seed"}
        ``"mass"`` (default): the discrete delta :math:`B^{-1}e_i`, convergent under
        refinement; ``"seed"``: :math:`e_i` (mesh dependent, see :func:`spectral_kernel`).
    method : str
        Approximation method of the engine (``"auto"``, ``"rational"``, ``"dense"``, ...).
    {accuracy}
    time_unit : str
        ``"absolute"`` (default), or ``t`` in the shape's units
        (:mod:`spectral_igl.laplacian.units`).

    Returns
    -------
    K : (n,) or (n, m) float
        The column :math:`K_t(:, i)` for one source, (n, m) for m sources.
    info : dict
        Only with ``return_info=True`` (entries shaped as ``K``); ``info["time"]`` is the
        absolute time used.

    Notes
    -----
    .. math:: K_t(:, i) = e^{-t \tilde L} B^{-1} e_i = \sum_l e^{-t\lambda_l} x_l(i)\, x_l

    ``t`` is in the units ``time_unit`` (:mod:`spectral_igl.laplacian.units`): the default
    ``"absolute"`` takes it as given (a squared length); ``time_unit="shape"`` multiplies it
    by the area of a surface (volume\ :sup:`2/3` of a solid), so that ``t=1e-3`` means the
    same on a scan in millimetres and on the unit sphere; ``"h2"`` by the squared mean edge
    length. ``info["time"]`` is the absolute time used. On a Metzler operator (lumped mass and
    non-negative weights: :attr:`Laplacian.is_metzler`) the exact kernel is non-negative and
    so is the returned one.

    The discrete heat kernel of the survey's §5.3, computed as in §5.5.

    With ``method="auto"`` (and no ``rtol``) on a Metzler operator of more than
    :data:`LOCAL_MIN_VERTICES` vertices, each column is first solved on a region around its
    source (:func:`~spectral_igl.local_heat_kernel`: at small t a small fraction of one
    factorization, with the same proved per-entry bound); ``info["method"]`` is then
    ``"local"``. When a region would cost too much the global path is taken, after at most
    :data:`~spectral_igl.approx.region.BUDGET` products of the whole operator, and
    ``info["note"]`` says why.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> K = sig.heat_kernel(lap, 0.05, [0, 1])
    >>> bool(np.allclose(K.T @ lap.B @ np.ones(lap.n), 1.0))  # heat is conserved
    True
    >>> k, info = sig.heat_kernel(lap, 1e-3, 0, rtol=1e-6, return_info=True)
    >>> bool(np.all(info["rel_error"][k >= 1e-10 * k.max()] <= 1e-6))
    True
    """
    lap = as_laplacian(lap)
    t = shape_time(lap, t, time_unit)
    delta = as_delta(delta)
    idx, scalar = source_indices(sources, lap.n)
    tried = None
    if rtol is None and method == "auto" and delta == "mass" and lap.is_metzler and lap.n > LOCAL_MIN_VERTICES:
        K, info = _local_columns(lap, float(t), idx, as_tol(tol))
        if K is not None:
            info["time"] = t
            if scalar:
                K = K[:, 0]
                info = {k: (v[:, 0] if isinstance(v, np.ndarray) and v.ndim == 2 else
                            (v[0].item() if isinstance(v, np.ndarray) and v.ndim == 1 else v))
                        for k, v in info.items()}
            return (K, info) if as_flag(return_info, "return_info") else K
        tried = info
    if rtol is None and block_sources(lap, method, delta, idx.size):
        lap.warn_if_not_metzler("heat kernel")
        K, info = heat_kernels(lap, [t], idx, tol=tol, return_info=True)
        # one time: drop the trailing time axis of every per-time entry
        K, info = K[:, :, 0], {k: (v[..., 0] if isinstance(v, np.ndarray) and v.ndim >= 2 else
                                   (float(v[0]) if isinstance(v, np.ndarray) and v.shape == (1,) else v))
                               for k, v in info.items()}
        info["time"] = t
        if tried is not None:
            info["note"] = tried["note"]
        return (K, info) if as_flag(return_info, "return_info") else K
    out = _kernel(lap, heat(t), sources, delta, method, tol, return_info, rtol, floor)
    if isinstance(out, tuple):
        out[1]["time"] = t
        if tried is not None:
            out[1]["note"] = tried["note"]
    return out


#: above this many vertices ``method="auto"`` heat columns of a Metzler operator are first tried
#: on a region around their source (:mod:`spectral_igl.approx.region`); below it the global
#: path costs little
LOCAL_MIN_VERTICES = DENSE_LIMIT


def _local_columns(lap, t, idx, tol):
    """(n, m) heat columns each on a region around its source, with their ``info``, or
    (None, {"note": why}) at the first column whose region would cost too much (that attempt
    costs at most :data:`~spectral_igl.approx.region.BUDGET` products of the whole operator)."""
    K = np.zeros((lap.n, idx.size))
    parts = []
    for c, s in enumerate(idx):
        col, info = region_heat_column(lap, t, int(s), tol)
        if col is None:
            info["note"] = "local column declined: " + info["note"]
            return None, info
        K[:, c] = col
        parts.append(info)
    stack = {k: np.stack([p[k] for p in parts], axis=-1) for k in ("abs_error", "solver_error")}
    flat = {k: np.array([p[k] for p in parts]) for k in ("bnorm_error", "region", "m_lost", "products", "cost")}
    warn_missed("heat_kernel", flat["bnorm_error"], tol / np.sqrt(lap.mass[idx]), stacklevel=4)
    return K, make_info(stack["abs_error"], "proof", "local", tol=tol, solver_error=stack["solver_error"], **flat)


for _fn in (spectral_kernel, heat_kernel):
    _fn.__doc__ = _fn.__doc__.replace("    {accuracy}\n", _ACCURACY_DOC.lstrip("\n"))


#: from this many sources on, ``method="auto"`` heat columns use the common-pole block solves
MANY_SOURCES = 8


def block_sources(lap, method, delta, m) -> bool:
    """Whether m heat columns go through one factorization per pole with all sources as one
    block: from :data:`MANY_SOURCES` sources on, above the dense limit (where factorizations,
    not solves, dominate the cost of the Krylov path)."""
    from .diagonal import EXACT_MAX
    from .linalg import ldlt

    return (method == "auto" and delta == "mass" and m >= MANY_SOURCES and lap.n > EXACT_MAX
            and ldlt.available())


def heat_kernels(lap: Laplacian, times, sources, tol: float = 1e-8, return_bound: bool = False,
                 return_info: bool = False, time_unit: str = "absolute"):
    r"""Heat-kernel columns at many times and sources, sharing one set of poles.

    .. math:: K_t(:, i) = e^{-t\tilde L}B^{-1}e_i, \qquad
              \|K_t(:,i) - \tilde K_t(:,i)\|_B \le \varepsilon_t \|B^{-1}e_i\|_B

    One sparse factorization per common pole of the whole family of times
    (:func:`spectral_igl.families.heat_columns`), each solved with every source
    as one block right-hand side; adding a time costs a weighted sum.

    Parameters
    ----------
    lap : Laplacian
    times : (T,) float
        Positive times, in the units ``time_unit`` (as in :func:`heat_kernel`; ``info["times"]``
        holds the absolute ones).
    sources : int or (m,) int
    tol : float
        Certified B-norm error of each column relative to :math:`\|B^{-1}e_i\|_B`; a time whose
        bound misses it warns (:class:`spectral_igl.accuracy.AccuracyWarning`).
    return_bound : bool
        Also return the (T,) certified :math:`\varepsilon_t`.
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` of every entry (shaped
        as ``K``), ``bound_kind``, ``method`` (``"rational"``), ``eps`` (the :math:`\varepsilon_t`)
        and ``bnorm_error``. Entries are bounded as in :func:`spectral_kernel`; heat columns of a
        Metzler operator are clipped at 0.

    Returns
    -------
    K : (n, T) float for one source, (n, m, T) float for m sources.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> K = sig.kernels.heat_kernels(lap, [0.01, 0.1], [0, 3])
    >>> K.shape, bool(np.allclose(K[:, 1, 1], sig.heat_kernel(lap, 0.1, 3)))
    ((162, 2, 2), True)
    """
    lap = as_laplacian(lap)
    times = shape_time(lap, times, time_unit, "times")
    lap.warn_if_not_metzler("heat kernel")
    return_bound = as_flag(return_bound, "return_bound")
    return_info = as_flag(return_info, "return_info")
    tol = as_tol(tol)
    idx, scalar = source_indices(sources, lap.n)
    K, eps = heat_columns(lap, times, idx, tol=tol)
    warn_missed("heat_kernels", eps, tol)
    if lap.is_metzler:         # the exact kernel is non-negative: clipping only gets closer
        np.maximum(K, 0.0, out=K)
    out = (K,)
    if return_bound:
        out += (eps,)
    if return_info:
        norm = np.sqrt(1.0 / (mass_ratio(lap) * lap.mass[idx]))          # >= ||B^-1 e_i||_B
        bn = norm[:, None] * eps[None, :]                                  # (m, T)
        err = entry_error(lap, bn.reshape(-1)).reshape(lap.n, idx.size, eps.size)
        info = make_info(err, lambda_max_kind(lap), "rational", tol=tol, eps=eps, bnorm_error=bn,
                         times=np.atleast_1d(times))
        out += (info,)
    if scalar:
        out = (out[0][:, 0, :],) + out[1:]
        if return_info:
            out[-1]["abs_error"] = out[-1]["abs_error"][:, 0, :]
            out[-1]["bnorm_error"] = out[-1]["bnorm_error"][0]
    return out[0] if len(out) == 1 else out
