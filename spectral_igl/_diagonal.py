r"""The diagonal of a spectral kernel :math:`G = \varphi(\tilde L)B^{-1}` at every vertex.

One-to-all spectral distances and the descriptors (HKS, WKS, ADF, eccentricity) need
:math:`G_{ii}` at all n vertices. The kernel is dense, so its diagonal is not a by-product
of any single solve. Methods:

``"exact"``
    n applications of the engine (in blocks): exact up to the engine's certified bound.
    For small and moderate n.
``"dense"``
    Dense generalized eigen-decomposition (n <= 8000): the ground truth. The
    decomposition is cached on the Laplacian, so further filters and times cost one
    matrix product each. ``"auto"`` uses it for n <= 3000 when ``"selinv"`` does not
    apply (n = 2562: 18 s once, against 37 s per filter for ``"exact"``).
``"eigen"``
    Truncated eigen-expansion with the ``k`` lowest eigenpairs: the classical baseline.
    No error bound; wrong by the whole omitted tail of the spectrum.
``"selinv"``
    Spectrum-free and exact up to a certified rational error: a partial-fraction
    approximation :math:`r(s) = \alpha_0 + \sum_j c_j/(\sigma s - z_j)` of the filter turns
    the diagonal into :math:`\alpha_0\,\mathrm{diag}(B^{-1}) + \sum_j c_j\,
    \mathrm{diag}((\sigma L - z_j B)^{-1})`, and the diagonal of each inverse comes from its
    sparse LDLᵀ factor by selected inversion (no column of the inverse is formed). The heat
    filter uses the Carathéodory--Fejér approximant, other filters an AAA fit. The
    commute-time kernel (:math:`s^{-1}`) is exact: :math:`G = QXQ^\top` with X the inverse of
    the grounded stiffness and :math:`Q = I - 1w^\top` the B-orthogonal projector off ker L;
    the biharmonic kernel (:math:`s^{-2}`) is exact too, :math:`G_c B G_c`, with
    :math:`\mathrm{diag}(XBX)` the complex-step derivative of
    :math:`\mathrm{diag}((L_g - zB)^{-1})` at z = 0 (one complex factorization). Error: :math:`|G_{ii} - \tilde G_{ii}| \le \varepsilon\,(B^{-1})_{ii}` with
    :math:`\varepsilon = \max|\varphi - r|` on the spectrum (reported as
    ``abs_error_bound``), and the error is also measured at ``samples`` vertices.
``"probing"``
    Spectrum-free estimator: probing vectors built from a distance-``D`` colouring of
    the mesh graph (two vertices of one colour are more than ``D`` edges apart), so that
    :math:`(G z_c)_i = G_{ii} + \sum_{j \in c, j \ne i} G_{ij}` and the far entries
    :math:`G_{ij}` are the error; the slowly-decaying low-frequency part of the kernel is
    optionally removed exactly with ``k`` low eigenpairs (deflation). Its accuracy is
    *measured* and reported: the exact diagonal is computed at ``samples`` random
    vertices and compared (those entries are then exact in the output).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .kernels import _check_delta, _check_filter, _check_lap, _operator
from .laplacian import dense_eigs, eigs
from .progress import progress_bar

__all__ = ["kernel_diagonal", "distance_colouring"]

_METHODS = ("auto", "exact", "dense", "eigen", "selinv", "probing")
#: ``auto`` uses ``exact`` up to this many vertices
EXACT_MAX = 3000
#: default colour budget of ``"probing"`` (engine applications)
MAX_COLOURS = 256
#: deflation rank tried by ``"probing"`` when the kernel does not decay fast enough
KDEFL = 100


def _gram_apply(lap, op, delta):
    """Z -> G Z for G = phi(L~) B^-1 (mass) or B phi(L~) (seed)."""
    if delta == "mass":
        return op.apply_inverse_mass
    return lambda Z: lap.B @ op.apply(Z)


def _low_rank(lap, k: int, delta: str, cache_eigs=True):
    """(evals, W) with G_low = W diag(phi(evals)) W^T, W = X (mass) or B X (seed)."""
    key = ("kernel_diagonal_eigs", int(k))
    if key in lap.cache:
        lam, X = lap.cache[key]
    else:
        lam, X = (dense_eigs(lap, k) if k >= lap.n - 1 else eigs(lap, k))
        if cache_eigs:
            lap.cache[key] = (lam, X)
    W = X if delta == "mass" else np.asarray(lap.B @ X)
    return lam, W


def _phi_values(filt, lam, c):
    with np.errstate(all="ignore"):
        ph = np.array(filt(lam), dtype=np.complex128 if getattr(filt, "is_complex", False) else float)
    if filt.singular:
        ph[:c] = 0.0
    return ph


def distance_colouring(lap, distance: int = 2, order: str = "bfs") -> np.ndarray:
    """(n,) greedy colouring in which two vertices of one colour are more than ``distance``
    edges apart in the graph of the nonzeros of L (a distance-``distance`` colouring).

    The number of colours is about the number of vertices in a ball of ``distance`` rings.
    """
    n = lap.n
    distance = int(distance)
    if distance < 1:
        raise ValueError(f"distance must be >= 1, got {distance}")
    A = sp.csr_matrix((np.ones(lap.L.nnz, dtype=np.int8), lap.L.indices, lap.L.indptr), shape=(n, n))
    A = (A + sp.identity(n, dtype=np.int8, format="csr")).astype(bool).astype(np.int8)
    P = A.copy()
    for _ in range(distance - 1):
        P = (P @ A).astype(bool).astype(np.int8)
    P = P.tocsr()
    P.sort_indices()
    if order == "bfs":
        from scipy.sparse.csgraph import breadth_first_order

        seen = np.zeros(n, bool)
        perm = []
        for s in range(n):
            if not seen[s]:
                o = breadth_first_order(A, s, directed=False, return_predecessors=False)
                seen[o] = True
                perm.append(o)
        perm = np.concatenate(perm)
    else:
        perm = np.arange(n)
    colours = np.full(n, -1, dtype=np.int64)
    mark = np.full(n + 1, -1, dtype=np.int64)
    indptr, indices = P.indptr, P.indices
    for v in perm:
        used = colours[indices[indptr[v]:indptr[v + 1]]]
        used = used[used >= 0]
        mark[used] = v
        free = np.flatnonzero(mark[: used.size + 1] != v)
        colours[v] = free[0]
    return colours


def _colour_budget(n: int, max_colours) -> int:
    if max_colours is None:
        return int(max(8, min(MAX_COLOURS, n // 4)))
    return int(max(1, max_colours))


def _adjacency(lap):
    n = lap.n
    return sp.csr_matrix((np.ones(lap.L.nnz, dtype=np.int8), lap.L.indices, lap.L.indptr), shape=(n, n))


def _probing_prediction(R, dist, exact, Ds):
    """Predicted relative probing error for each colouring distance in ``Ds``.

    For sample column i, the error of probing is the sum of G_ij over the j that share
    i's colour; every vertex further than D rings away does so with probability about
    1/ncol(D), and ncol(D) is about 0.55 times the number of vertices within D rings
    (greedy distance-D colouring of a surface mesh); the few nearest allowed vertices
    (D+1 and D+2 rings away) are counted at their full weight. Returns (pred, ncol).
    """
    s = R.shape[1]
    dmax = int(dist.max()) + 1
    pred = np.zeros(len(Ds))
    balls = np.zeros((s, len(Ds)))
    Ds = np.asarray(Ds)
    for i in range(s):
        a = np.abs(R[:, i])
        w = np.bincount(dist[i], weights=a, minlength=dmax + 3)
        cnt = np.bincount(dist[i], minlength=dmax + 3)
        peak = np.zeros(dmax + 3)
        np.maximum.at(peak, dist[i], a)
        tail = w.sum() - np.cumsum(w)
        ball = np.cumsum(cnt)
        D = np.minimum(Ds, dmax)
        balls[i] = ball[D]
        # far vertices share i's colour with probability ~1/ncol; a few of the nearest
        # allowed ones (D+1, D+2 rings) do so for sure: greedy colouring packs colours
        near = 3.0 * np.maximum(peak[D + 1], peak[D + 2])
        pred = np.maximum(pred, (tail[D] / (0.55 * ball[D]) + near) / max(abs(exact[i]), np.finfo(float).tiny))
    return pred, np.maximum(1.0, 0.55 * np.median(balls, axis=0))


def _choose_probing(lap, filt, delta, C, idx, exact, k, distance, rtol, budget):
    """(k, distance) for probing from the exact columns C at the sample vertices idx.

    The off-diagonal decay of the kernel, or of its remainder after deflation with k
    eigenpairs, is read off the sample columns against graph distance; the cheapest
    colouring distance whose predicted error meets ``rtol`` within the colour budget is
    taken, else the most accurate one. Deflation is tried only when the kernel itself
    does not decay fast enough: a truncated low-mode expansion is not local (its
    off-diagonal entries oscillate over the whole shape), so deflating a local kernel
    makes the remainder non-local and probing worse.
    """
    from scipy.sparse.csgraph import shortest_path

    n, c = lap.n, lap.n_components
    dist = shortest_path(_adjacency(lap), unweighted=True, indices=idx)
    far = dist[np.isfinite(dist)].max() + 1 if np.isfinite(dist).any() else 1
    dist = np.where(np.isfinite(dist), dist, far).astype(np.int64)   # other components: G_ij = 0
    Dall = np.arange(1, int(far) + 1) if distance is None else np.array([int(distance)])

    def best(kk):
        if kk:
            lam, W = _low_rank(lap, kk, delta)
            ph = _phi_values(filt, lam, c)
            R = C - (W * ph) @ W[idx].T
        else:
            R = C
        pred, ncol = _probing_prediction(np.real(R) if not np.iscomplexobj(R) else R, dist, exact, Dall)
        ok = ncol <= budget
        if not ok.any():
            ok[0] = True
        good = np.flatnonzero(ok & (pred <= rtol))
        j = good[0] if good.size else np.flatnonzero(ok)[np.argmin(pred[ok])]
        return {"k": kk, "distance": int(Dall[j]), "predicted": float(pred[j])}

    if k is not None:
        return best(max(0, min(int(k), n - 1)))
    plain = best(0)
    if plain["predicted"] <= rtol:
        return plain
    kd = int(min(KDEFL, max(0, n // 20)))
    if kd == 0:
        return plain
    defl = best(kd)
    return defl if defl["predicted"] < plain["predicted"] else plain


class _NoSelinv(Exception):
    """The filter or the mass matrix is outside what ``"selinv"`` handles."""


def selinv_supported(lap, filt, delta: str = "mass") -> bool:
    """Whether :func:`kernel_diagonal` can use ``method="selinv"`` for this input."""
    from . import _selinv

    if not _selinv.available() or (delta == "seed" and not lap.lumped):
        return False
    return not getattr(filt, "is_complex", False)


def _ldlt(lap, A):
    from . import _selinv
    from .solvers import ldlt_pattern

    return _selinv.LDLT(A, ldlt_pattern(lap))


def _inverse_mass_diagonal(lap):
    """diag(B^-1): 1/m for a lumped mass, else by selected inversion (cached)."""
    if lap.lumped:
        return 1.0 / lap.mass
    d = lap.cache.get("inverse_mass_diagonal")
    if d is None:
        from .solvers import shifted_factor

        d = lap.cache["inverse_mass_diagonal"] = shifted_factor(lap, 0.0, 1.0, backend="ldlt").inverse_diagonal()
    return d


def _component_volume(lap):
    """(n,) the mass 1_c^T B 1_c of each vertex's component."""
    comp = lap.components
    return np.bincount(comp, weights=np.asarray(lap.B.sum(axis=1)).ravel(), minlength=lap.n_components)[comp]


def _grounded_stiffness(lap):
    """(L_g, grounded): L with one vertex per component (largest stiffness diagonal) turned
    into an identity row and column, so that L_g is SPD and its inverse, with zeros at the
    grounded vertices, is the grounded pseudo-inverse X."""
    from .solvers import grounded_vertices

    grounded = grounded_vertices(lap)
    keep = sp.diags((~grounded).astype(float))
    return (keep @ lap.L @ keep + sp.diags(grounded.astype(float))).tocsr(), grounded


def _grounded_ldlt(lap):
    """Cached (LDLᵀ of L_g, L_g, grounded mask)."""
    g = lap.cache.get("grounded_ldlt")
    if g is None:
        Lg, grounded = _grounded_stiffness(lap)
        g = lap.cache["grounded_ldlt"] = (_ldlt(lap, Lg), Lg, grounded)
    return g


class _SelinvKernel:
    r"""One approximation R of :math:`G = \varphi(\tilde L)B^{-1}` giving its diagonal (by
    selected inversion), its columns and the per-vertex bound :math:`|G_{ii} - R_{ii}|`.

    Distances built from the diagonal and a column of the same R are the exact distances
    of R: :math:`|d^2 - d_R^2| \le \varepsilon \|B^{-1}(e_i - e_j)\|_B^2`, with no error
    from mixing two approximations.
    """

    def __init__(self, lap, filt, tol):
        self.lap, self.filt = lap, filt
        p = filt.params.get("p") if filt.kind == "power" else None
        self.power = int(round(p)) if p is not None and abs(p - round(p)) < 1e-12 and round(p) in (1, 2) else 0
        self._diag = None
        if self.power:
            self.vol = _component_volume(lap)
            self.w = np.asarray(lap.B.sum(axis=1)).ravel() / self.vol   # Q = I - 1 w^T per component
            self.fac, self.Lg, self.grounded = _grounded_ldlt(lap)
            self.eps, self.n_factorizations = 0.0, 2
        else:
            self._rational(tol)

    # ----------------------------------------------------------------- rational filters
    def _rational(self, tol):
        from .approx import lambda_max, lambda_min_positive
        from .approx._rational import RationalPlan, aaa_fit, certify, rounding

        lap, filt = self.lap, self.filt
        b = lambda_max(lap)
        a = lambda_min_positive(lap) if filt.singular else 0.0
        self.minv = _inverse_mass_diagonal(lap)
        if filt.kind == "power":
            pf = aaa_fit(filt, a, b, rtol=max(tol * 1e-3, 1e-13))
            if pf is None:
                raise _NoSelinv("no usable rational fit")
            eps = certify(pf, filt, a, b) + rounding(pf, a, b, b)
        else:
            if filt.kind == "heat":
                # |error_i| <= eps (B^-1)_ii and G_ii >= 1/V_c (the constant mode): this
                # eps makes the error at most tol G_ii at every vertex
                tol = max(tol * float(np.min(1.0 / (_component_volume(lap) * self.minv))), 1e-15)
            try:
                plan = RationalPlan(lap, filt, a, b, tol)
            except (ValueError, RuntimeError) as exc:
                raise _NoSelinv(str(exc)) from None
            pf, eps = plan.pf, plan.scalar_error + plan.rounding
        for c, z, k in pf.terms:
            # a real pole inside the spectrum's hull makes sigma L - z B indefinite
            if abs(z.imag) <= 1e-12 * max(1.0, abs(z)) and 0.0 <= z.real / pf.sigma <= b:
                raise _NoSelinv(f"real pole {z.real / pf.sigma:.3g} inside the spectrum")
            if filt.singular and abs(z / pf.sigma) < 0.5 * a:   # ker L would dominate that term
                raise _NoSelinv(f"pole {z / pf.sigma:.3g} too close to the singularity at 0")
        self.pf, self.eps, self.n_factorizations = pf, eps, len(pf.terms)

    def _factors(self):
        from .solvers import shifted_factor

        for c, z, k in self.pf.terms:
            theta = -z.real if z.imag == 0 else -z
            yield c, k, shifted_factor(self.lap, self.pf.sigma, theta, backend="ldlt")

    def _kernel_part(self):
        """r(0) / V_c: what r puts on ker L, where a singular filter is 0."""
        return float(np.real(self.pf(np.zeros(1))[0])) / _component_volume(self.lap)

    # ----------------------------------------------------------------- exact powers
    def _X(self, b):
        """The grounded pseudo-inverse X (zero rows at the grounded vertices)."""
        x = self.fac.solve(b)
        x[self.grounded] = 0.0
        return x

    def _commute(self, V):
        r""":math:`Q X Q^\top V` for V of shape (n, k): the kernel of :math:`s^{-1}`."""
        w = self.w[:, None]
        Y = self._X(V - w * self._comp_sum(V))
        return Y - self._comp_sum(w * Y)

    # ----------------------------------------------------------------- public
    def columns(self, E):
        """R E for E of shape (n, k)."""
        lap = self.lap
        if self.power == 1:
            return self._commute(E)
        if self.power == 2:                 # G = G_c B G_c
            return self._commute(lap.B @ self._commute(E))
        out = np.zeros(E.shape)
        for c, k, fac in self._factors():
            out += k * (c * fac.solve(E)).real       # a conjugate pair (k = 2): 2 Re(c x)
        from .solvers import mass_solve

        out += self.pf.alpha0.real * mass_solve(lap, E, backend="ldlt")
        if self.filt.singular:
            out -= self._kernel_part()[:, None] * self._comp_sum(E)
        return out

    def _comp_sum(self, e):
        r""":math:`\sum_c 1_c 1_c^\top e`: each entry replaced by its component's sum ((n,) or (n, k))."""
        comp = self.lap.components
        S = sp.csr_matrix((np.ones(self.lap.n), (np.arange(self.lap.n), comp)),
                          shape=(self.lap.n, self.lap.n_components))
        return S @ (S.T @ e)

    def diagonal(self, progress=None):
        """(diag R, per-vertex bound of |G_ii - R_ii|), computed once."""
        if self._diag is None:
            self._diag = self._power_diagonal() if self.power else self._rational_diagonal(progress)
        return self._diag

    def _rational_diagonal(self, progress=None):
        diag = np.zeros(self.lap.n)
        with progress_bar(len(self.pf.terms), "kernel diagonal", progress, unit="pole") as bar:
            for c, k, fac in self._factors():
                diag += k * (c * fac.inverse_diagonal()).real
                bar.update()
        diag += self.pf.alpha0.real * self.minv
        if self.filt.singular:
            diag -= self._kernel_part()
        return diag, self.eps * self.minv

    def _power_diagonal(self):
        lap, w, vol = self.lap, self.w, self.vol
        u = self._X(w)
        if self.power == 1:
            xd = self.fac.inverse_diagonal()
            xd[self.grounded] = 0.0
            mdiag, Mw = xd, u
        else:
            # G = Q (X B X - V u u^T) Q^T, since Q^T B Q = B - V w w^T per component.
            # diag(X B X) is the derivative at z = 0 of diag((L_g - z B_g)^-1) (B_g: B
            # without the grounded rows), taken by a complex step: Im diag((L_g - ihB_g)^-1)/h
            # is sum_l x_l(i)^2 / (mu_l^2 + h^2), exact to rounding for h = 1e-20 lambda_max,
            # and nothing cancels.
            from .approx import lambda_max

            h = 1e-20 * lambda_max(lap)
            keep = sp.diags((~self.grounded).astype(float))
            step = _ldlt(lap, (self.Lg - 1j * h * (keep @ lap.B @ keep)).tocsr())
            xbx = step.inverse_diagonal().imag / h
            xbx[self.grounded] = 0.0
            mdiag = xbx - vol * u * u
            Mw = self._X(lap.B @ u) - vol * u * self._comp_sum(u * w)
        # diag(Q M Q^T) = M_ii - 2 (M w)_i + (w^T M w)_c(i)
        return mdiag - 2.0 * Mw + self._comp_sum(w * Mw), np.zeros(lap.n)


def _selinv_kernel(lap, filt, tol) -> _SelinvKernel:
    """The :class:`_SelinvKernel` of ``filt``, cached on ``lap`` while the filter lives."""
    import weakref

    cache = lap.cache.setdefault("selinv_kernels", weakref.WeakKeyDictionary())
    kern = cache.get(filt, {}).get(tol)
    if kern is None:
        kern = _SelinvKernel(lap, filt, tol)
        cache.setdefault(filt, {})[tol] = kern
    return kern


def kernel_diagonal(lap, filt, method: str = "auto", delta: str = "mass", k: int | None = None,
                    distance: int | None = None, samples: int = 16, rtol: float = 1e-4,
                    max_colours: int | None = None, tol: float = 1e-8,
                    engine_method: str = "auto", seed: int = 0, return_info: bool = False,
                    progress=None):
    r"""Diagonal of the spectral kernel :math:`G = \varphi(\tilde L)B^{-1}` at every vertex.

    .. math:: G_{ii} = \sum_l \varphi(\lambda_l)\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        The filter whose kernel diagonal is wanted (for spectral distances pass
        :math:`|\varphi|^2`, see :func:`spectral_igl.kernels.abs_square`).
    method : {"auto", "exact", "dense", "selinv", "probing", "eigen"}
        See the module notes. ``"auto"``: ``"selinv"``; where it does not apply (a complex
        filter, ``delta="seed"`` with a full mass matrix, a fit with poles near 0 such as
        :math:`s^{-3}`), ``"dense"`` (cached) for ``n <= 3000``, else ``"probing"``.
    delta : {"mass", "seed"}
        ``"seed"`` gives the diagonal of :math:`B\varphi(\tilde L)` (the seed-delta Gram
        matrix).
    k : int, optional
        Eigenpairs: the truncation of ``"eigen"`` (default 100), the deflation rank of
        ``"probing"`` (0: no deflation). ``"probing"`` chooses it when not given: 0 if
        the kernel decays fast enough for ``rtol``, else the better of 0 and 100.
    distance : int, optional
        Colouring distance of ``"probing"`` (graph rings). Chosen when not given: the
        smallest distance whose error, predicted from the decay of the exact sample
        columns with graph distance, is below ``rtol`` within ``max_colours`` colours
        (else the most accurate one within the budget).
    samples : int
        ``"probing"``: vertices at which the exact kernel column is computed; they set
        the choices above and measure the error (reported in ``info``), and are exact
        in the output. At least 1 unless both ``k`` and ``distance`` are given.
        ``"selinv"``: vertices where the selected inversion is checked against solves
        with the same factors (0 to skip); the approximation error itself is certified
        (``abs_error_bound``).
    rtol : float
        ``"probing"``: relative accuracy aimed at when choosing ``k`` and ``distance``
        (the reported error is measured, not this target).
    max_colours : int, optional
        ``"probing"``: colour budget (engine applications), default
        ``min(256, n // 4)``.
    tol, engine_method : passed to the engine.
    seed : int
        Random seed of the sample vertices.
    return_info : bool
        Also return a dict: ``method``, ``applications`` (engine columns), ``k``,
        ``distance``, ``colours``, and for ``"probing"`` the measured ``sample_abs_error``
        and ``sample_rel_error`` (max over the samples), the ``samples`` and, when
        chosen, the ``predicted_rel_error``; for ``"exact"`` the certified
        ``abs_error_bound`` (max over vertices).

    progress : bool, optional
        Draw a progress bar on stderr, one step per pole (``"selinv"``) or block of 64 columns or colours; see :mod:`spectral_igl.progress`
        (default: off).

    Returns
    -------
    diag : (n,) float (complex for a complex filter)
    info : dict, only with ``return_info``
    """
    lap = _check_lap(lap)
    filt = _check_filter(filt)
    delta = _check_delta(delta)
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    n, c = lap.n, lap.n_components
    auto = method == "auto"
    if auto:
        method = "selinv" if selinv_supported(lap, filt, delta) else ("dense" if n <= EXACT_MAX else "probing")
    info = {"method": method, "applications": 0, "k": 0, "distance": None, "colours": None}
    cplx = bool(getattr(filt, "is_complex", False))
    dtype = np.complex128 if cplx else np.float64

    if method == "dense":
        if "dense_eigs" not in lap.cache:
            lap.cache["dense_eigs"] = dense_eigs(lap)
        lam, X = lap.cache["dense_eigs"]
        W = X if delta == "mass" else np.asarray(lap.B @ X)
        diag = (W ** 2) @ _phi_values(filt, lam, c)
        info["k"] = n
        return (diag, info) if return_info else diag

    if method == "eigen":
        k = 100 if k is None else int(k)
        k = max(1, min(k, n))
        lam, W = _low_rank(lap, k, delta)
        diag = (W ** 2) @ _phi_values(filt, lam, c)
        info["k"] = k
        return (diag, info) if return_info else diag

    if method == "selinv":
        if not selinv_supported(lap, filt, delta):
            raise ValueError("method='selinv' needs the compiled extension and pymetis, a real filter, "
                             "and a lumped mass for delta='seed'")
        try:
            kern = _selinv_kernel(lap, filt, tol)
            diag, bound = kern.diagonal(progress)
            nfac = kern.n_factorizations
        except _NoSelinv as exc:
            if not auto:
                raise ValueError(f"method='selinv' cannot handle {filt.name!r}: {exc}; use 'probing'") from None
            return kernel_diagonal(lap, filt, "dense" if n <= EXACT_MAX else "probing", delta, k, distance,
                                   samples, rtol, max_colours, tol, engine_method, seed, return_info,
                                   progress)
        if delta == "seed":       # diag(B G B) = m^2 G_ii for a lumped mass
            diag, bound = diag * lap.mass ** 2, bound * lap.mass ** 2
        info.update(factorizations=nfac, abs_error_bound=float(bound.max(initial=0.0)))
        samples = int(min(max(samples, 0), n))
        if samples:     # the selected inversion against solves with the same factors
            rng = np.random.default_rng(seed)
            idx = np.sort(rng.choice(n, samples, replace=False))
            E = np.zeros((n, samples))
            E[idx, np.arange(samples)] = 1.0
            if delta == "seed":
                E *= lap.mass[:, None]
            exact = kern.columns(E)[idx, np.arange(samples)]
            if delta == "seed":
                exact *= lap.mass[idx]
            err = np.abs(diag[idx] - exact)
            info.update(samples=idx, sample_abs_error=float(err.max()),
                        sample_rel_error=float(np.max(err / np.maximum(np.abs(exact), np.finfo(float).tiny))))
        return (diag, info) if return_info else diag

    op = _operator(lap, filt, engine_method, tol)
    G = _gram_apply(lap, op, delta)
    block = 64
    if method == "exact":
        diag = np.empty(n, dtype=dtype)
        bound = np.zeros(n)
        minv = 1.0 / lap.mass
        bar = progress_bar(-(-n // block), "kernel diagonal", progress, unit="block")
        for a in range(0, n, block):
            idx = np.arange(a, min(a + block, n))
            E = np.zeros((n, idx.size))
            E[idx, np.arange(idx.size)] = 1.0
            Y = G(E)
            diag[idx] = Y[idx, np.arange(idx.size)]
            eb = np.asarray(getattr(op, "error_bound", np.nan), dtype=float).reshape(-1)
            # |e_i^T dY| <= ||B^-1 e_i||_B ||dY||_B, (B^-1)_ii <= 5/m_i for linear FEM masses
            fac = 1.0 if lap.lumped else 5.0
            bound[idx] = eb * np.sqrt(fac * minv[idx]) if delta == "mass" else np.nan
            bar.update()
        bar.close()
        info["applications"] = n
        info["abs_error_bound"] = float(np.max(bound)) if np.all(np.isfinite(bound)) else float("nan")
        return (diag, info) if return_info else diag

    # --- probing -------------------------------------------------------------------------
    samples = int(min(max(samples, 0), n))
    if samples == 0 and (k is None or distance is None):
        raise ValueError("method='probing' chooses k and distance from exact columns at sample "
                         "vertices: pass samples >= 1, or both k and distance")
    idx = np.empty(0, dtype=np.int64)
    if samples:
        rng = np.random.default_rng(seed)
        idx = np.sort(rng.choice(n, samples, replace=False))
        E = np.zeros((n, samples))
        E[idx, np.arange(samples)] = 1.0
        C = G(E)                                   # exact columns at the samples
        exact = C[idx, np.arange(samples)]
        info["applications"] += samples
    budget = _colour_budget(n, max_colours)
    if k is None or distance is None:
        choice = _choose_probing(lap, filt, delta, C, idx, exact, k, distance, rtol, budget)
        k, distance = choice["k"], choice["distance"]
        info["predicted_rel_error"] = choice["predicted"]
    k = max(0, min(int(k), n - 1))
    distance = int(distance)
    colours = distance_colouring(lap, distance)
    ncol = int(colours.max()) + 1
    info.update(distance=distance, colours=ncol, k=k)
    diag = np.zeros(n, dtype=dtype)
    rows = np.arange(n)
    bar = progress_bar(-(-ncol // block), "kernel diagonal", progress, unit="block")
    for a in range(0, ncol, block):
        cols = np.arange(a, min(a + block, ncol))
        sel = (colours >= cols[0]) & (colours <= cols[-1])
        Z = np.zeros((n, cols.size))
        Z[rows[sel], colours[sel] - a] = 1.0
        Y = G(Z)
        diag[sel] = Y[rows[sel], colours[sel] - a]
        bar.update()
    bar.close()
    info["applications"] += ncol
    if k > 0:
        lam, W = _low_rank(lap, k, delta)
        ph = _phi_values(filt, lam, c)
        low_diag = (W ** 2) @ ph
        # (G_low Z)_{i, c(i)} = sum over i's colour class of G_low(i, j)
        S = np.zeros((ncol, W.shape[1]), dtype=W.dtype)
        np.add.at(S, colours, W)                     # Z^T W
        low_probe = np.einsum("ij,ij->i", W * ph, S[colours])
        diag += low_diag - low_probe
    # measured accuracy at the sample vertices (made exact there)
    if samples:
        err = np.abs(diag[idx] - exact)
        info["sample_abs_error"] = float(err.max())
        info["sample_rel_error"] = float(np.max(err / np.maximum(np.abs(exact), np.finfo(float).tiny)))
        info["samples"] = idx
        diag[idx] = exact
    return (diag, info) if return_info else diag
