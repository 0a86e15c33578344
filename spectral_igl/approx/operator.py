r"""The engine's operator :math:`f \mapsto \varphi(\tilde L) f` with its certified bound (see
:mod:`spectral_igl.approx` for the kernel split and the bound), and the plan that drops a
remainder below the tolerance."""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse.linalg as spla

from ..accuracy import warn_missed
from .._validate import as_positive, as_signal, as_tol, check_dense_size, check_spectral_function
from ..filters import as_filter
from ..laplacian import Laplacian, as_laplacian, lambda_max, lambda_max_kind, mass_ratio
from ..linalg import check_backend, gap_lower_bound, lambda_min_positive, lambda_min_positive_kind
from .choice import HEAT_ONLY, LARGE_T, METHODS, PLANS, check_engine_options, choose_method
from .common import (EPS, abs_bnorm, abs_mass_apply, bnorm, filter_sup, inv_bnorm_lower, inv_bnorm_upper,
                     mass_rounding, nonnegative_mass, projection_rounding)
from .spectral import DensePlan

#: complex (n, k) arrays the engine holds at its peak for an (n, k) signal (measured: 1.2 GB
#: for an (2562, 4000) signal with the heat filter, 8 such arrays)
WORK_COPIES = 8

__all__ = ["SpectralOperator", "ZeroPlan", "apply_filter", "spectral_operator"]

log = logging.getLogger(__name__)


class SpectralOperator(spla.LinearOperator):
    r"""Reusable :math:`f \mapsto \varphi(\tilde L) f` for one Laplacian, filter and method.

    The scalar approximation (poles, coefficients, degree) is built once; factorizations
    are cached on the Laplacian, so applying to many signals, or to kernel columns, only
    costs the solves. It is a :class:`scipy.sparse.linalg.LinearOperator` (``op @ f``,
    ``op.matvec``, ``op.matmat``), so it plugs into scipy's iterative solvers and
    eigensolvers; its Euclidean adjoint is :math:`B\,\bar\varphi(\tilde L)B^{-1}` (the
    operator itself is self-adjoint in the B-inner product).

    .. math:: u = \varphi(B^{-1}L)\, f, \qquad \|u - \varphi(\tilde L) f\|_B \le
              \texttt{error\_bound}

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        E.g. ``filters.heat(t)``; a plain vectorised callable is wrapped in a Filter.
    method : str
        One of :data:`METHODS` (default ``"auto"``).
    tol : float
        Target relative accuracy in the B-norm: methods that choose their degree pick the
        smallest with ``error_bound <= tol * ||f||_B``.
    backend : {"auto", "cholespy", "pypardiso", "superlu"}
        Sparse direct solver for real shifted matrices (complex ones use SuperLU).
    **options
        Method settings: ``k`` (eigen), ``steps`` (euler, krylov, shift_invert), ``degree``
        (taylor, chebyshev, rational, power), ``squarings`` (power), ``nodes`` (contour, gauss_legendre),
        ``shift`` (shift_invert).

    Attributes
    ----------
    method : str
        The method in use (``"auto"`` resolved).
    error_bound : float, (k,) float array, or None
        Absolute B-norm error bound of the last call (per column for (n, k) input).
        ``None`` for ``"eigen"``, which cannot bound its truncation error.
    bound_kind : {"proof", "estimate"} or None
        Whether ``error_bound`` is a mathematical upper bound of the error (see the module
        notes); ``None`` for ``"eigen"``.
    bound_parts : dict
        The kind of each ingredient: ``lambda_max``, ``lambda_min_positive``,
        ``approximation`` (``"proof"``/``"estimate"``) and ``rounding`` (``"a-priori"`` or
        ``"residual"``).
    n_solves : int
        Sparse solves per right-hand side (excluding one-off factorizations).

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl import filters
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> op = sig.SpectralOperator(lap, filters.heat(0.01), method="rational")
    >>> u = op.apply(np.ones(lap.n))          # heat preserves constants
    >>> bool(np.allclose(u, 1.0)), bool(op.error_bound < 1e-8 * np.sqrt(lap.area()))
    (True, True)
    """

    def __init__(self, lap: Laplacian, filt, method: str = "auto", tol: float = 1e-8,
                 backend: str = "auto", **options):
        lap = as_laplacian(lap)
        filt = as_filter(filt)
        tol = as_tol(tol, "tol")
        if not isinstance(method, str) or method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        backend = check_backend(backend)
        options = check_engine_options(method, options, lap.n)
        check_spectral_function(filt, 0.0, lambda_max(lap), repr(filt), singular=filt.singular)
        super().__init__(np.complex128 if filt.is_complex else np.float64, (lap.n, lap.n))
        if method == "auto":
            method = choose_method(lap, filt, tol)
            log.info("auto chose method %r for %r (n=%d, tol=%g)", method, filt, lap.n, tol)
        if method in HEAT_ONLY and filt.kind != "heat":
            raise ValueError(f"method {method!r} approximates the heat filter only, got {filt!r}; "
                             "use 'rational', 'chebyshev', 'shift_invert' or 'krylov'")
        self.lap, self.filter, self.method, self.tol = lap, filt, method, tol
        self.lambda_max = lambda_max(lap)
        self.split = method not in ("dense", "eigen")
        t = filt.params.get("t") if filt.kind in ("heat", "mexican_hat", "mexican_hat_survey") else None
        decays = self.split and t is not None and t * self.lambda_max > LARGE_T
        self.a, a_kind = 0.0, "unused"
        if decays and not filt.singular:
            self.a, a_kind = self._decay_floor(t)
        elif filt.singular:
            self.a, a_kind = lambda_min_positive(lap), lambda_min_positive_kind(lap)
        if self.a >= self.lambda_max:          # only isolated vertices, or a 1-edge mesh
            self.a = 0.5 * self.lambda_max
        kwargs = dict(options)
        if method not in ("dense", "eigen"):
            kwargs["backend"] = backend
        self.plan = None
        if self.split:
            self.plan = ZeroPlan.attempt(filt, self.a, self.lambda_max, self._plan_tol())
        if self.plan is None:
            try:
                self.plan = PLANS[method](lap, filt, self.a, self.lambda_max, self._plan_tol(), **kwargs)
            except TypeError as err:
                raise TypeError(f"invalid options for method {method!r}: {sorted(options)} ({err})") from err
        self.phi0 = filt.at_zero()
        scal = getattr(self.plan, "scalar_error", 0.0)
        if scal is None or not np.isfinite(scal):
            raise ValueError(f"method {method!r} cannot bound its error for {filt!r} on the spectrum "
                             f"[{self.a:.3g}, {self.lambda_max:.3g}] (t * lambda_max too large for it); "
                             "use method='rational', 'krylov' or 'chebyshev', or a smaller t")
        self._enclosure = {"lambda_max": lambda_max_kind(lap),
                           "lambda_min_positive": a_kind if self.a > 0 else "unused"}
        self.n_solves = getattr(self.plan, "n_solves", None)
        self.error_bound = None
        pf = getattr(self.plan, "pf", None)
        log.debug("%s: %s solves per column, degree %s, poles %s", self, self.n_solves,
                  getattr(self.plan, "m", None), None if pf is None else [z for _, z, _ in pf.terms])

    def _decay_floor(self, t):
        r"""``(a, kind)``: the lower end of the interval a decaying filter is approximated on at
        large t, a proved lower bound of :math:`\lambda_{c+1}` found cheaply where that suffices.

        Heat drops its remainder (:class:`ZeroPlan`) once :math:`e^{-ta} \le` tol/2, i.e. for
        any proved :math:`a \ge \ln(4/\mathrm{tol})/t` (a factor 2 to spare): one inertia count there
        (:func:`~spectral_igl.linalg.gap_lower_bound`) replaces the Lanczos run and counts of
        :func:`~spectral_igl.linalg.lambda_min_positive`. Where the remainder stays, the
        Carathéodory--Fejér fit of the ``"rational"`` method does not depend on a (its error is
        that of :math:`e^{-x}` on :math:`[0, \infty)`), so any proved a > 0 will do. Else, and
        when no count proves a bound, :func:`~spectral_igl.linalg.lambda_min_positive`.
        """
        lap, filt = self.lap, self.filter
        if filt.kind == "heat" and t > 0:
            # e^(-ta) at tol/4: room for the slack of the certified maximum ZeroPlan takes
            want = np.log(4.0 / self._plan_tol()) / t
            if want < self.lambda_max:
                a = gap_lower_bound(lap, want, any_bound=self.method == "rational")
                if a is not None:
                    return a, "proof"
        return lambda_min_positive(lap), lambda_min_positive_kind(lap)

    @property
    def bound_parts(self) -> dict:
        """The kind of each ingredient of ``error_bound`` (see the module notes)."""
        if self.method == "eigen":
            return {}
        if self.method == "dense":   # exact up to the eigensolver's rounding, not certified
            return {"lambda_max": "unused", "lambda_min_positive": "unused",
                    "approximation": "estimate", "rounding": "a-priori"}
        return dict(self._enclosure,
                    approximation="proof" if getattr(self.plan, "proved", False) else "estimate",
                    rounding="residual" if (self.method == "rational" and self.filter.kind == "power"
                                            and getattr(self.plan, "pf", None) is None) else "a-priori")

    @property
    def bound_kind(self):
        """``"proof"`` or ``"estimate"`` (``None`` for ``"eigen"``): see the module notes."""
        if self.method == "eigen":
            return None
        ok = all(v in ("proof", "unused", "a-priori", "residual") for v in self.bound_parts.values())
        return "proof" if ok else "estimate"

    def _matvec(self, x):
        return self.apply(np.asarray(x).reshape(-1))

    def _matmat(self, X):
        return self.apply(np.asarray(X))

    def _adjoint_apply(self, y):
        # A^H y = B conj(phi)(L~) B^-1 y = conj(B phi(L~) B^-1 conj(y))
        y = np.asarray(y)
        if self.filter.is_complex:
            return np.conj(self.lap.B @ self.apply_inverse_mass(np.conj(y)))
        return self.lap.B @ self.apply_inverse_mass(y)

    def _rmatvec(self, y):
        return self._adjoint_apply(np.asarray(y).reshape(-1))

    def _rmatmat(self, Y):
        return self._adjoint_apply(Y)

    def __repr__(self) -> str:
        return (f"SpectralOperator({self.filter!r}, method={self.method!r}, tol={self.tol:g}, "
                f"n={self.lap.n}, solves={self.n_solves})")

    def apply(self, f):
        r""":math:`\varphi(\tilde L) f` for ``f`` of shape (n,) or (n, k); sets ``error_bound``.

        Warns (:class:`~spectral_igl.accuracy.AccuracyWarning`) when ``error_bound`` exceeds
        ``tol * ||f||_B``.
        """
        u = self._apply(f, rhs=False)
        self._check_tol(f, rhs=False)
        return u

    def apply_inverse_mass(self, g):
        r""":math:`\varphi(\tilde L) B^{-1} g` (kernel columns: ``g = e_i``); sets ``error_bound``.

        Rational, Euler and shift-invert methods need no solve with B here, since
        :math:`(I + \beta\tilde L)^{-1}B^{-1} = (B + \beta L)^{-1}`. The bound is relative to
        :math:`\|B^{-1}g\|_B`, itself bounded without a solve; a bound above ``tol`` times
        that norm warns (:class:`~spectral_igl.accuracy.AccuracyWarning`).
        """
        u = self._apply(g, rhs=True)
        self._check_tol(g, rhs=True)
        return u

    def _plan_tol(self):
        r"""The scalar target of the plans: ``tol``, times :math:`\sqrt c` for a non-diagonal B.

        A kernel column's bound is the scalar error times :func:`.common.inv_bnorm_upper`
        :math:`= (g^\top D^{-1}g / c)^{1/2}`, which exceeds :math:`\|B^{-1}g\|_B \ge
        (g^\top D^{-1}g)^{1/2}` (B entrywise non-negative, D its row sums) by up to
        :math:`1/\sqrt c`; the factor keeps the bound within ``tol`` times the true norm."""
        lap = self.lap
        if lap.lumped or not nonnegative_mass(lap):
            return self.tol
        return self.tol * float(np.sqrt(mass_ratio(lap)))

    def _check_tol(self, f, rhs):
        r"""Warn, naming the achieved bound, when the bound of the last call misses ``tol`` times
        the input's norm (for a kernel column a lower bound of :math:`\|B^{-1}g\|_B`:
        :math:`(g^\top D^{-1}g)^{1/2}` when B is entrywise non-negative, since then
        :math:`D^{-1}B` has spectral radius 1)."""
        if self.error_bound is None:
            return
        f = np.asarray(f)
        lap = self.lap
        norm = bnorm(lap, f) if not rhs else inv_bnorm_lower(lap, f)
        if norm is None:
            norm = inv_bnorm_upper(lap, f)
        warn_missed(f"{self!r}", self.error_bound, self.tol * norm, stacklevel=4)

    def _apply(self, f, rhs):
        lap = self.lap
        f = as_signal(f, lap.n, "g" if rhs else "f")
        check_dense_size(WORK_COPIES * 16.0 * f.size, f"the work arrays of the engine for a signal of shape "
                         f"{f.shape}", "apply the filter to fewer columns at a time")
        kernel_part = None
        split = self.filter.singular or self.split
        if split:
            Z = lap.component_basis()
            c0 = Z.T @ f if rhs else Z.T @ (lap.B @ f)       # P0 f = Z c0 (P0 B^-1 g for rhs)
            p0 = Z @ c0
            e_p0 = projection_rounding(lap, np.abs(f) if rhs else abs_mass_apply(lap, f), not rhs)
            f = f - lap.B @ p0 if rhs else f - p0
            if self.split and self.phi0 != 0:
                kernel_part = Z @ (self.phi0 * c0)
        u, src, scal = self.plan.apply(f, rhs)
        if split:
            u_plan = u
            u = lap.project_out_kernel(u)
        if kernel_part is not None:
            u = u + kernel_part
        if not np.all(np.isfinite(u)):
            raise ValueError(f"method {self.method!r} overflowed for {self.filter!r} "
                             f"(lambda_max = {self.lambda_max:.3g}); use method='rational' or 'krylov'")
        if scal is None:
            self.error_bound = None
        else:
            if src is not None:
                norm = bnorm(lap, src)
            elif isinstance(self.plan, DensePlan):
                norm = self.plan.coef_norm
            else:
                norm = inv_bnorm_upper(lap, f)
            bound = scal * norm + getattr(self.plan, "residual_bound", 0.0)
            if split:
                bound = bound + self._split_rounding(f, p0, u, u_plan, kernel_part, e_p0, scal, rhs)
            bound = np.asarray(bound, dtype=float)
            if not np.all(np.isfinite(bound)):
                raise ValueError(f"method {self.method!r} cannot bound its error for {self.filter!r} on "
                                 f"[{self.a:.3g}, {self.lambda_max:.3g}]; use method='rational' or "
                                 "'krylov', or a smaller t")
            self.error_bound = float(bound) if f.ndim == 1 else np.broadcast_to(bound, f.shape[1:]).copy()
        if not self.filter.is_complex and np.isrealobj(f) and np.iscomplexobj(u):
            u = u.real
        return u

    def _split_rounding(self, rem, p0, u, u_plan, kernel_part, e_p0, scal, rhs):
        r"""B-norm bound of the rounding of the kernel split (entrywise bounds, see
        :func:`.common.projection_rounding`), each scaled to the magnitudes that cancel:

        - :math:`\varphi(0)P_0f`: the projection's rounding ``e_p0`` and the product by φ(0);
        - the remainder :math:`f - P_0f` handed to the method is off by ``e_p0`` and the
          subtraction (for a kernel column also the product by B): the method maps that
          error through :math:`|r| \le \max_{[a, \lambda_{\max}]}|\varphi|` + its scalar error;
        - the projection of the method's result off ker L, and the final sum.
        """
        lap, half = self.lap, 0.5 * EPS
        e_sub = half * np.abs(rem)
        if rhs:
            e_in = abs_bnorm(lap, e_p0) + inv_bnorm_upper(lap, e_sub + mass_rounding(lap, p0))
        else:
            e_in = abs_bnorm(lap, e_p0 + e_sub)
        sup = getattr(self, "_phi_sup", None)
        if sup is None:
            sup = self._phi_sup = (self.plan.scalar_error if isinstance(self.plan, ZeroPlan)
                                   else filter_sup(self.filter, self.a, self.lambda_max)[0])
        e_proj = projection_rounding(lap, abs_mass_apply(lap, u_plan), True)
        # the subtraction of the projection and the sum with the kernel part: u each, on
        # |u - kernel_part| <= |u| + |kernel_part| and on |u|
        out = e_proj + (1.0 + EPS) * half * (2.0 * np.abs(u))
        if kernel_part is not None:
            out = out + abs(self.phi0) * e_p0 * (1.0 + half) + 2.0 * half * np.abs(kernel_part)
        return abs_bnorm(lap, out) + (sup + scal) * e_in


class ZeroPlan:
    r"""The remainder dropped: when :math:`\max_{[a, b]}|\varphi| \le` tol/2 (heat at large t,
    for example), :math:`\varphi(\tilde L)(f - P_0f)` is within that maximum of 0."""

    n_solves = 0

    def __init__(self, bound, proved):
        self.scalar_error, self.proved, self.m = bound, proved, 0

    @classmethod
    def attempt(cls, filt, a, b, tol):
        top, proved = filter_sup(filt, a, b, tol)
        if np.isfinite(top) and top <= 0.5 * tol:
            return cls(float(top), proved)
        return None

    def apply(self, f, rhs):
        return np.zeros_like(f), (None if rhs else f), self.scalar_error


def apply_filter(lap: Laplacian, filt, f, method: str = "auto", tol: float = 1e-8, **options):
    r""":math:`\varphi(\tilde L) f = X\varphi(\Lambda)X^\top B f` without the spectrum.

    .. math:: u = \varphi(B^{-1}L) f

    Parameters
    ----------
    lap : Laplacian
    filt : Filter or callable
    f : (n,) or (n, k) float (or complex)
    method, tol, **options :
        See :class:`SpectralOperator`.

    Returns
    -------
    u : same shape as ``f``; complex for complex filters (wave).

    Examples
    --------
    Against the dense eigendecomposition, :math:`X\varphi(\Lambda)X^\top B f`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> f = lap.data["V"][:, 0] ** 2
    >>> u = sig.apply_filter(lap, sig.filters.heat(0.2), f)
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = X @ (np.exp(-0.2 * lam) * (X.T @ (lap.B @ f)))
    >>> bool(np.sqrt((u - exact) @ lap.B @ (u - exact)) < 1e-8 * np.sqrt(f @ lap.B @ f))
    True
    """
    return SpectralOperator(lap, filt, method=method, tol=tol, **options).apply(f)


def spectral_operator(lap: Laplacian, filt, method: str = "auto", tol: float = 1e-8,
                      backend: str = "auto") -> SpectralOperator:
    r"""The :class:`SpectralOperator` of ``(filt, method, tol, backend)``, cached on ``lap``.

    Filters are values, so every call with an equal filter (``filters.heat(0.1)`` built
    anew, say) reuses the same operator: its poles, degree and factorizations.

    Parameters
    ----------
    lap : Laplacian or mesh
    filt : Filter or callable
        :math:`\varphi`.
    method : str
        Approximation method (:data:`METHODS`; default ``"auto"``), see :class:`SpectralOperator`.
    tol : float
        Target B-norm accuracy relative to :math:`\|f\|_B` (default 1e-8).
    backend : str
        Sparse solver of the factorizations (see :func:`spectral_igl.linalg.factorize`).

    Returns
    -------
    SpectralOperator
        ``op.apply(f)`` is :math:`\varphi(\tilde L) f`, ``op.error_bound`` its bound.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> a = sig.spectral_operator(lap, sig.filters.heat(0.1))
    >>> a is sig.spectral_operator(lap, sig.filters.heat(0.1))
    True
    """
    lap = as_laplacian(lap)
    filt = as_filter(filt)
    key = (filt, method, float(as_positive(tol, "tol")), backend)
    return lap.cache.fetch("operator", key, lambda: SpectralOperator(lap, filt, method=method, tol=tol,
                                                                      backend=backend))
