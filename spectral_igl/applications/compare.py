r"""Shape comparison: global, isometry-invariant signatures with certified bounds, and distances.

Two signatures of a whole shape, both scale-normalised so that a shape and its scaled copy
get the same values, both returned with a bound of every entry
(:mod:`spectral_igl.accuracy`):

* :func:`shape_dna` (Reuter et al. 2006): the first k eigenvalues of
  :math:`Lx = \lambda Bx`, certified (:func:`spectral_igl.eigs`), times the shape's measure
  :math:`|M|^{2/d}` (the area of a surface, as LaPy's ``normalize_ev(..., "geometry")``
  does, the volume\ :sup:`2/3` of a solid);
* :func:`heat_trace`: :math:`Z(t) = \sum_l e^{-t\lambda_l} = \operatorname{tr} e^{-t\tilde L}`
  at times in the shape's units, spectrum-free, from the certified heat kernel diagonal.

:func:`shape_distance` compares two shapes by one signature, :func:`shape_distance_matrix`
a collection of signatures (for instance those stored by :meth:`spectral_igl.collection.Job.heat_trace`).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from .._validate import as_array, as_choice, as_flag, as_int, describe
from ..accuracy import info as bound_info, rounding_gamma, weakest
from ..descriptors import hks
from ..laplacian import as_laplacian
from ..laplacian.units import TIME_UNITS, time_scale
from ..linalg import eigs

__all__ = ["shape_dna", "heat_trace", "shape_distance", "shape_distance_matrix", "retrieval_scores",
           "TRACE_TIMES", "SIGNATURES", "SHAPE_DNA_LAPLACIAN"]

#: the default heat-trace grid, in the shape's units (x area on a surface): from where a
#: few thousand vertices still resolve the kernel to where only the first eigenvalues remain
TRACE_TIMES = np.geomspace(1e-3, 1.0, 31)

#: the Laplacian :func:`shape_dna` builds from a mesh: linear finite elements, cotan stiffness and
#: consistent mass (Reuter et al. 2006, and LaPy's ``compute_shapedna``); on the retrieval set
#: of ``benchmarks/shape_retrieval.py`` its mAP is 0.989, against 0.985 with the intrinsic
#: Delaunay weights and 0.959 with the lumped mass
SHAPE_DNA_LAPLACIAN = {"weights": "cotan", "mass": "full"}

#: the signatures :func:`shape_distance` knows
SIGNATURES = ("heat_trace", "shape_dna")

EPS = np.finfo(float).eps


def _gamma(m: int) -> float:
    """:math:`\\gamma_{2m}`: the rounding of m terms, counted with machine epsilon (2u) as unit."""
    return rounding_gamma(2 * m)


def shape_dna(lap, k: int = 50, normalize: str | None = "shape", return_info: bool = False):
    r"""ShapeDNA: the first ``k`` eigenvalues of :math:`Lx = \lambda Bx`, scale-normalised.

    .. math:: \mathrm{DNA}_i = s\,\lambda_i,\qquad i = 0, \dots, k - 1

    with :math:`s` = :func:`spectral_igl.time_scale` ``(lap, normalize)``: the area of a
    surface for ``"shape"`` (the default) and ``"area"``, the volume\ :sup:`2/3` of a solid
    for ``"shape"`` and ``"volume"``, :math:`h^2` for ``"h2"``, 1 for ``None``. Eigenvalues
    scale as :math:`1/\text{length}^2`, so :math:`s\lambda_i` does not change when the shape
    is scaled; by Weyl's law :math:`\lambda_i |M| / i \to 4\pi` on a surface.

    The eigenvalues are :func:`spectral_igl.eigs`'s, certified by residuals and an inertia
    count; the bound of each entry is its enclosure times :math:`s`, plus the rounding of
    :math:`s` (a sum of the entries of B) and of the product.

    Parameters
    ----------
    lap : Laplacian or mesh
        Anything :func:`spectral_igl.laplacian.as_laplacian` takes. A mesh is given the
        Laplacian ShapeDNA is defined with, linear finite elements
        (:data:`SHAPE_DNA_LAPLACIAN`: cotan weights, consistent mass), as LaPy computes it;
        a Laplacian is used as it is (the default lumped mass of
        :func:`spectral_igl.laplacian` gives less accurate eigenvalues on coarse meshes:
        retrieval mAP 0.959 against 0.989 in ``docs/compare.md``).
    k : int
        Number of eigenvalues, ``1 <= k < n`` (the first ``lap.n_components`` are 0).
    normalize : str or None
        ``"shape"``, ``"area"``, ``"volume"``, ``"h2"`` or ``None`` (no normalisation).
    return_info : bool
        Also return ``info``: ``abs_error`` (k,), ``bound_kind`` (``"proof"`` when the
        eigenvalue count is certified, else ``"estimate"``), ``method``, ``scale`` (s),
        ``normalize``.

    Returns
    -------
    (k,) float, ascending
    info : dict, only with ``return_info``

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> a, info = sig.shape_dna(sig.laplacian(V, F), 10, return_info=True)
    >>> b = sig.shape_dna(sig.laplacian(1e3 * V, F), 10)
    >>> bool(abs(a - b).max() < 1e-6 * a.max()), info["bound_kind"]
    (True, 'proof')

    From the arrays, the finite-element Laplacian; on the unit sphere the first nonzero
    eigenvalue is :math:`l(l+1) = 2`, three times (:math:`l = 1`):

    >>> c = sig.shape_dna((V, F), 4, normalize=None)
    >>> [round(float(x), 2) for x in c]
    [0.0, 2.01, 2.01, 2.01]
    """
    lap = as_laplacian(lap, **SHAPE_DNA_LAPLACIAN)
    k = as_int(k, "k", lo=1)
    if k >= lap.n:
        raise ValueError(f"k must be below the number of vertices n = {lap.n}, got {k}")
    scale, unit = _scale(lap, normalize)
    lam, _, eig_info = eigs(lap, k, return_info=True)
    lam = np.asarray(lam, dtype=float)
    values = lam * scale
    err = np.asarray(eig_info["abs_error"], dtype=float) * scale * (1 + EPS)
    # s is a sum over B's entries (area) or over the edges (h2), and a power of it
    err = err + _gamma(max(lap.B.nnz, lap.L.nnz) + 8) * np.abs(values)
    if not as_flag(return_info, "return_info"):
        return values
    return values, bound_info(err, eig_info["bound_kind"], "eigs", scale=scale, normalize=unit)


def _scale(lap, normalize):
    """``(s, unit)``: the factor that makes eigenvalues dimensionless, and its unit."""
    if normalize is None:
        return 1.0, None
    unit = as_choice(normalize, "normalize", tuple(u for u in TIME_UNITS if u != "absolute"))
    return time_scale(lap, unit), unit


def heat_trace(lap, times=None, time_unit: str = "shape", method: str = "auto", tol: float = 1e-8,
               return_info: bool = False):
    r"""The heat trace at ``times``, spectrum-free, with a bound of every entry.

    .. math:: Z(t) = \sum_l e^{-t\lambda_l} = \operatorname{tr} e^{-t\tilde L}
              = \sum_i (K_t)_{ii} B_{ii}

    The last equality holds for a lumped (diagonal) mass matrix B, as ``sig.laplacian``
    builds by default: :math:`\operatorname{tr}(X e^{-t\Lambda} X^\top B) = \operatorname{tr}(K_t B)`
    with :math:`K_t = e^{-t\tilde L}B^{-1}`. The diagonal :math:`(K_t)_{ii}` is the certified
    kernel diagonal of :func:`spectral_igl.hks` (selected inversion of a rational
    approximation), so no eigenpair is computed. A full mass matrix would need the entries of
    :math:`K_t` on B's off-diagonal pattern as well; it is refused.

    :math:`Z` is dimensionless and, at times in the shape's units (the default: ``t`` times
    the area of a surface), does not change when the shape is scaled. At small times
    :math:`Z(t) \approx |M|/(4\pi t)`, at large ones it tends to the number of connected
    components.

    Parameters
    ----------
    lap : Laplacian or mesh
        With a lumped mass matrix.
    times : float or (T,) float, optional
        In the units ``time_unit``. Default :data:`TRACE_TIMES` in the shape's units
        (31 times from 1e-3 to 1 times the area), the same relative grid on every shape so
        that traces of different shapes compare entry by entry.
    time_unit : str
        ``"shape"`` (default), ``"area"``, ``"volume"``, ``"h2"`` or ``"absolute"``
        (:mod:`spectral_igl.laplacian.units`).
    method, tol
        Passed to :func:`spectral_igl.hks`.
    return_info : bool
        Also return ``info``: ``abs_error`` (T,), a bound of
        :math:`|Z(t) - \tilde Z(t)|` from the diagonal's per-vertex bounds
        (:math:`\sum_i e_i B_{ii}`) and the rounding of the sum; ``bound_kind``, ``method``,
        ``times`` (absolute), ``time_unit`` and ``time_scale``.

    Returns
    -------
    float for a scalar time, (T,) float for an array of times.
    info : dict, only with ``return_info``

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> z, info = sig.heat_trace(sig.laplacian(V, F), [1e-2, 1.0], return_info=True)
    >>> Z = sig.heat_trace(sig.laplacian(1e-3 * V, F), [1e-2, 1.0])
    >>> bool(abs(z - Z).max() < 1e-6 * z.max()), round(float(z[1]), 6), info["bound_kind"]
    (True, 1.0, 'proof')
    """
    lap = as_laplacian(lap)
    unit = as_choice(time_unit, "time_unit", TIME_UNITS)
    if not lap.lumped:
        raise ValueError("heat_trace needs a lumped (diagonal) mass matrix: tr(K_t B) with a full B "
                         "needs the off-diagonal entries of K_t as well; build the Laplacian with "
                         "mass='lumped' (the default of sig.laplacian)")
    if times is None:
        if unit != "shape":
            raise ValueError(f"time_unit={time_unit!r} applies to times, which were not given (the "
                             "default grid TRACE_TIMES is in the shape's units)")
        times = TRACE_TIMES
    scalar = np.ndim(times) == 0
    H, hinfo = hks(lap, times, method=method, tol=tol, time_unit=unit, return_info=True)
    H = np.asarray(H, dtype=float).reshape(lap.n, -1)
    e = np.asarray(hinfo["abs_error"], dtype=float).reshape(lap.n, -1)
    m = lap.B.diagonal()
    Z = m @ H
    # |Z - Z~| <= sum_i e_i m_i + rounding of the n products and the sum of Z~ and of the bound
    err = (m @ e) * (1 + _gamma(lap.n + 1)) + _gamma(lap.n + 1) * (m @ np.abs(H))
    out = float(Z[0]) if scalar else Z
    if not as_flag(return_info, "return_info"):
        return out
    info = bound_info(float(err[0]) if scalar else err, hinfo["bound_kind"], hinfo["method"],
                      times=np.asarray(hinfo["times"]), time_unit=unit,
                      time_scale=time_scale(lap, unit))
    if hinfo.get("note"):
        info["note"] = hinfo["note"]
    return out, info


def _signature(lap, signature, kwargs):
    """``(values, abs_error, bound_kind)`` of one shape's signature."""
    fn = shape_dna if signature == "shape_dna" else heat_trace
    values, info = fn(lap, return_info=True, **kwargs)
    return np.atleast_1d(values), np.atleast_1d(info["abs_error"]), info["bound_kind"]


def _features(values, signature):
    r"""The vector whose Euclidean distance compares two signatures: :math:`\log Z(t)` per time,
    divided by :math:`\sqrt T` (an RMS over the grid), or the ShapeDNA values reweighted by
    their index, :math:`s\lambda_i / i` for :math:`i \ge 1` (Reuter's and LaPy's ``reweight_ev``:
    by Weyl's law every entry is near :math:`4\pi` on a surface, so each weighs alike)."""
    v = np.asarray(values, dtype=float)
    if signature == "heat_trace":
        if np.any(v <= 0):
            raise ValueError("a heat trace must be positive at every time to be compared (log Z)")
        return np.log(v) / np.sqrt(v.size)
    return v[1:] / np.arange(1, v.size)


def _feature_error(values, abs_error, signature):
    """A bound of the error of each computed feature from the bound of each signature entry,
    with the rounding of the feature itself (a log or a division: a few units of it)."""
    v, e = np.asarray(values, dtype=float), np.asarray(abs_error, dtype=float)
    rounding = 4 * EPS * np.abs(_features(v, signature))
    if signature == "heat_trace":
        with np.errstate(divide="ignore", invalid="ignore"):
            # |log Z - log Z~| <= -log(1 - e / Z~) while e < Z~
            out = np.where(e < v, -np.log1p(-np.minimum(e / v, 1.0)), np.inf)
        return out / np.sqrt(v.size) * (1 + 4 * EPS) + rounding
    return e[1:] / np.arange(1, v.size) * (1 + 2 * EPS) + rounding


def _check_signature(signature):
    return as_choice(signature, "signature", SIGNATURES)


def shape_distance(a, b, signature: str = "heat_trace", return_info: bool = False, **kwargs):
    r"""A distance between two shapes by a global signature, invariant to isometry and scale.

    ``"heat_trace"``: the root mean square, over the times of :func:`heat_trace` (its default
    grid in the shape's units unless ``times`` is given), of the difference of
    :math:`\log Z(t)`. ``"shape_dna"``: the Euclidean distance of the ShapeDNA values
    :math:`s\lambda_i` reweighted by :math:`1/i` (:math:`i \ge 1`), as LaPy compares spectra.

    .. math:: d_Z(a, b) = \Big(\frac1T\sum_j (\log Z_a(t_j) - \log Z_b(t_j))^2\Big)^{1/2}

    Parameters
    ----------
    a, b : Laplacian or mesh
    signature : str
        ``"heat_trace"`` (default) or ``"shape_dna"``.
    return_info : bool
        Also return ``info``: ``abs_error``, a bound of the distance's error from the bounds of
        the two signatures (the triangle inequality), ``bound_kind``, ``method``.
    **kwargs
        Passed to :func:`heat_trace` or :func:`shape_dna` (``times``, ``k``, ...).

    Returns
    -------
    float
    info : dict, only with ``return_info``

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> sig.shape_distance((V, F), (10 * V, F), "shape_dna", k=10) < 1e-9
    True
    """
    signature = _check_signature(signature)
    sa = _signature(as_laplacian(a), signature, kwargs)
    sb = _signature(as_laplacian(b), signature, kwargs)
    if sa[0].shape != sb[0].shape:
        raise ValueError(f"the two signatures differ in length ({sa[0].size} and {sb[0].size})")
    fa, fb = _features(sa[0], signature), _features(sb[0], signature)
    d = float(np.linalg.norm(fa - fb))
    if not as_flag(return_info, "return_info"):
        return d
    err = _feature_error(*sa[:2], signature) + _feature_error(*sb[:2], signature)
    bound = float(np.linalg.norm(err)) * (1 + _gamma(2 * fa.size + 2)) + _gamma(2 * fa.size + 2) * d
    return d, bound_info(bound, weakest(sa[2], sb[2]), signature)


def shape_distance_matrix(signatures, signature: str = "heat_trace", abs_error=None,
                          return_info: bool = False, components=None):
    r"""The (m, m) matrix of :func:`shape_distance` between ``m`` precomputed signatures.

    .. math:: D_{ij} = \lVert f(s_i) - f(s_j) \rVert_2

    with :math:`f` the features :func:`shape_distance` compares (:math:`\log Z(t)/\sqrt T`
    for the heat trace, :math:`s\lambda_l / l` for ShapeDNA).

    Parameters
    ----------
    signatures : sequence of (T,) float, or (m, T) float
        One signature per shape, all of one kind and length: :func:`heat_trace` values on a
        common grid (for instance :meth:`spectral_igl.collection.Job.heat_trace` results
        loaded from a store) or :func:`shape_dna` values with the same ``k``.
    signature : str
        ``"heat_trace"`` (default) or ``"shape_dna"``: how to compare them.
    abs_error : (m, T) float, optional
        The bound of every signature entry (``info["abs_error"]`` of :func:`heat_trace` or
        :func:`shape_dna`, the stored ``<key>_abs_error``); needed for a bound of ``D``.
    return_info : bool
        Also return ``info``: ``abs_error`` (m, m), a bound of :math:`|D_{ij} - \tilde D_{ij}|`
        (inf without ``abs_error``), ``bound_kind`` (``"proof"`` when ``abs_error`` is
        given: the caller vouches for its kind; None without), ``method``.
    components : (m,) int, optional
        Heat traces only: each shape's number of connected components :math:`\beta_0`
        (``lap.n_components``; ``n_components`` in a collection's records). The zero
        eigenvalues add :math:`\beta_0` to :math:`Z(t)` at every time, which hides the
        decaying rest at middle and large times; with ``components`` the features are
        :math:`\log(Z(t) - \beta_0)` and :math:`\log\beta_0`, so that at large times each
        trace shows its first nonzero eigenvalue (:math:`\log(Z - \beta_0) \approx
        \log m_1 - t\lambda_1`). Every :math:`Z(t) - \beta_0` must be positive: use times
        at which the first nonzero eigenvalues have not decayed below the bounds.

    Returns
    -------
    (m, m) float, symmetric, zero on the diagonal
    info : dict, only with ``return_info``

    Notes
    -----
    With :math:`e_i` a bound of the error of the features of shape i (from the bound of
    each signature entry, as :func:`shape_distance` does), the triangle inequality gives
    :math:`|D_{ij} - \tilde D_{ij}| \le \lVert e_i\rVert + \lVert e_j\rVert`, plus the
    rounding of the norms.

    Examples
    --------
    >>> import numpy as np
    >>> D = shape_distance_matrix([[3.0, 2.0, 1.0], [3.0, 2.0, 1.0], [4.0, 2.0, 1.0]])
    >>> D.shape, bool(D[0, 1] == 0 and D[0, 2] == D[2, 0] > 0)
    ((3, 3), True)
    >>> D, info = shape_distance_matrix([[3.0, 2.0], [4.0, 2.0]], abs_error=[[1e-9, 1e-9]] * 2,
    ...                                 return_info=True)
    >>> bool(info["abs_error"].max() < 1e-9), info["bound_kind"]
    (True, 'proof')
    """
    signature = _check_signature(signature)
    S = _signature_array(signatures, "signatures")
    S, extra = _without_zero_modes(S, signature, components)
    X = np.stack([_features(s, signature) for s in S])
    D = cdist(np.c_[X, extra], np.c_[X, extra])
    if not as_flag(return_info, "return_info"):
        return D
    if abs_error is None:
        return D, bound_info(np.full(D.shape, np.inf), None, signature)
    E = _signature_array(abs_error, "abs_error")
    if E.shape != S.shape or np.any(E < 0):
        raise ValueError(f"abs_error must be a non-negative array of the signatures' shape {S.shape}, "
                         f"got {describe(abs_error)}")
    if components is not None:   # the rounding of Z - beta_0, and of log(beta_0)
        E = E + EPS * np.abs(S)
    norms = np.array([np.linalg.norm(_feature_error(s, e, signature)) for s, e in zip(S, E)])
    norms = norms + 4 * EPS * np.abs(extra).sum(axis=1)
    g = _gamma(2 * X.shape[1] + 6)
    bound = (norms[:, None] + norms[None, :]) * (1 + g) + g * D
    np.fill_diagonal(bound, 0.0)      # a signature against itself: exactly zero
    return D, bound_info(bound, "proof", signature)


def _without_zero_modes(S, signature, components):
    """``(S - beta_0, log(beta_0) / sqrt(T))`` for heat traces with ``components``; else ``(S, [])``."""
    if components is None:
        return S, np.zeros((S.shape[0], 0))
    if signature != "heat_trace":
        raise ValueError(f"components applies to heat traces, not to signature={signature!r}")
    b = as_array(components, "components")
    if b.shape != (S.shape[0],) or b.dtype.kind not in "iu" or np.any(b < 1):
        raise ValueError(f"components must be ({S.shape[0]},) integers >= 1, one per signature, got "
                         f"{describe(components)}")
    R = S - b[:, None]
    if np.any(R <= 0):
        i, j = np.argwhere(R <= 0)[0]
        raise ValueError(f"the heat trace of signature {i} at entry {j} is not above its {b[i]} "
                         "component(s): at that time only the zero eigenvalues remain; use smaller times")
    return R, np.log(b.astype(float))[:, None] / np.sqrt(S.shape[1])


def _signature_array(x, name):
    """``x`` as an (m, T) float array of finite numbers, T >= 2."""
    S = as_array(x, name)
    if S.dtype.kind not in "iuf" or S.ndim != 2 or S.shape[0] < 1 or S.shape[1] < 2:
        raise ValueError(f"{name} must be an (m, T) array of numbers with T >= 2, got {describe(x)}")
    if not np.all(np.isfinite(S)):
        raise ValueError(f"{name} must be finite")
    return S.astype(float)


def retrieval_scores(D, labels):
    r"""Leave-one-out retrieval scores of a distance matrix over labelled shapes.

    Each shape is a query against all the others, ranked by increasing distance (ties kept
    in index order); the relevant shapes are those with its label.

    .. math:: \text{NN} = \frac1m \sum_q [\ell(r_q(1)) = \ell(q)],\qquad
              \text{mAP} = \frac1m \sum_q \frac{1}{|R_q|}\sum_{j:\,\ell(r_q(j)) = \ell(q)}
              \frac{|\{i \le j: \ell(r_q(i)) = \ell(q)\}|}{j}

    with :math:`r_q(j)` the j-th nearest other shape and :math:`R_q` the relevant ones.

    Parameters
    ----------
    D : (m, m) float
        Distances, for instance from :func:`shape_distance_matrix`.
    labels : sequence of m hashables
        The class of each shape; every class needs at least two members (a query without a
        relevant shape has no average precision).

    Returns
    -------
    nn_accuracy : float
        The fraction of queries whose nearest other shape has their class.
    mean_average_precision : float

    Examples
    --------
    >>> import numpy as np
    >>> D = np.array([[0, 1, 5, 6], [1, 0, 5, 6], [5, 5, 0, 2], [6, 6, 2, 0]], float)
    >>> retrieval_scores(D, ["a", "a", "b", "b"])
    (1.0, 1.0)
    >>> nn, mAP = retrieval_scores(D, ["a", "b", "a", "b"])   # APs 1/2, 1/3, 1/2, 1/3
    >>> nn, round(mAP, 12) == round(5 / 12, 12)
    (0.0, True)
    """
    D = as_array(D, "D")
    labels = np.asarray(labels)
    m = labels.shape[0] if labels.ndim == 1 else -1
    if D.dtype.kind not in "iuf" or D.ndim != 2 or D.shape != (m, m) or m < 2:
        raise ValueError(f"D must be an (m, m) array of numbers for m = len(labels) >= 2 labels, got "
                         f"{describe(D)} and {m if m >= 0 else 'labels of shape ' + str(labels.shape)}")
    if not np.all(np.isfinite(D)):
        raise ValueError("D must be finite")
    values, counts = np.unique(labels, return_counts=True)
    if counts.min() < 2:
        raise ValueError(f"labels: every class needs at least two shapes, {values[counts.argmin()]!r} "
                         "has one")
    nn, aps = [], []
    for q in range(m):
        order = np.argsort(D[q], kind="stable")
        order = order[order != q]
        rel = labels[order] == labels[q]
        nn.append(rel[0])
        aps.append(np.mean(np.cumsum(rel)[rel] / (np.flatnonzero(rel) + 1)))
    return float(np.mean(nn)), float(np.mean(aps))
