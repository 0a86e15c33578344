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

from ._validate import as_flag, as_index, as_tol
from .accuracy import info as make_info
from .accuracy import warn_missed
from .approx import choose_method
from .approx.region import region_heat_column
from .filters import heat, mexican_hat
from .kernels import heat_kernel, spectral_kernel
from .laplacian import Laplacian, as_laplacian, shape_time

__all__ = ["local_heat_kernel", "local_mexican_hat"]

U = 2.0 ** -53


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
    lap = as_laplacian(lap)
    if not lap.is_metzler:
        raise ValueError("local_heat_kernel needs a Metzler Laplacian (lumped mass and non-negative "
                         f"edge weights), got {lap!r}: build it with mass='lumped' and positive=True "
                         "(the default of sig.laplacian on triangle meshes)")
    t = float(shape_time(lap, t, time_unit))
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
    miss.

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
    lap = as_laplacian(lap)
    if not lap.is_metzler:
        raise ValueError("local_mexican_hat needs a Metzler Laplacian (lumped mass and non-negative "
                         f"edge weights), got {lap!r}: build it with mass='lumped' and positive=True "
                         "(the default of sig.laplacian on triangle meshes)")
    t = float(shape_time(lap, t, time_unit))
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
        heat_tol = heat_tol * max(target / bnorm, 1e-6) * 0.5
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


def _gamma(k):
    return k * U / (1.0 - k * U)
