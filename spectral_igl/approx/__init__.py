r"""Spectrum-free evaluation of :math:`\varphi(\tilde L) f`, :math:`\tilde L = B^{-1}L`, with a certified bound.

The kernel of L (the constants of each connected component) is split off exactly: with
:math:`P_0 = ZZ^\top B` the B-orthogonal projector onto ker L,

.. math:: \varphi(\tilde L)f = \varphi(0)\,P_0 f + \varphi(\tilde L)(f - P_0 f),

and every spectrum-free method replaces φ by a scalar approximation r on
:math:`[a, \lambda_{\max}]` and the remainder is projected back onto the complement of
ker L. a = :func:`~spectral_igl.linalg.lambda_min_positive` (a certified lower bound of the
smallest positive eigenvalue) for the singular filters, and for the heat and Mexican-hat
filters once :math:`t\lambda_{\max}` exceeds :data:`LARGE_T`; a = 0 otherwise (the
remainder has no component in ker L, so [0, λ_max] encloses its spectrum too). So the heat at any large t tends to the projection onto
the constants of each component, and the approximation never has to resolve φ near 0. When
:math:`\max_{[a, \lambda_{\max}]}|\varphi| \le` ``tol``/2 (heat at large t), the remainder is
dropped and that maximum is the bound. Since :math:`\tilde L` is self-adjoint in the B-inner
product,

.. math:: \|\varphi(\tilde L)f - u\|_B \le \max_{s \in [a, \lambda_{\max}]}
          |\varphi(s) - r(s)| \, \|f - P_0 f\|_B + \text{rounding},

and that number is reported as ``error_bound``. The Lanczos methods report their a-priori
bound :math:`2\min_{p}\max|g - p|\,\|f - P_0f\|_B` instead (see :mod:`.krylov`).

``bound_kind`` says whether the bound is a proof: ``"proof"`` when both ends of the
spectrum's enclosure are certified (:func:`~spectral_igl.laplacian.lambda_max_kind`,
:func:`~spectral_igl.linalg.lambda_min_positive_kind`) and the scalar error is proved
(:func:`.common.certified_sup`, :func:`.common.ellipse_tails`, the Lagrange remainder);
``"estimate"`` otherwise (a user filter, ``"power"``'s sampled error, ``"dense"``'s rounding
model, a non-FEM mass matrix). ``bound_parts`` gives each ingredient's kind; the rounding of
the solves is an a-priori allowance except for the pseudo-solves of ``"rational"``, which
use a-posteriori residuals.

Methods
-------
``"dense"``       all eigenpairs (exact; small n only).
``"eigen"``       truncated spectral approximation with ``k`` eigenpairs (no bound: ``None``).
``"euler"``       backward Euler, ``steps`` solves with :math:`B + (t/m)L` (heat only).
``"taylor1"``     :math:`BF = (B - tL)f` (heat only).
``"power"``       truncated power series with scaling and squaring (heat only).
``"krylov"``      Lanczos on :math:`\tilde L` in the B-inner product.
``"shift_invert"``  Lanczos on :math:`(I + \gamma\tilde L)^{-1}`: one real Cholesky.
``"taylor"``      the survey's Algorithm 2, case I (monomial polynomial).
``"chebyshev"``   Chebyshev expansion of φ on :math:`[a, \lambda_{\max}]`.
``"rational"``    partial fractions :math:`\sum_i c_i(\sigma L - z_iB)^{-1}Bf`: best rational
                  approximation (Carathéodory--Fejér) for heat, exact pseudo-solves for
                  :math:`s^{-k/2}`, an AAA fit otherwise.
``"contour"``     Talbot quadrature of the Cauchy integral (heat only).
``"gauss_legendre"``  the survey's Algorithm 2, case II: Gauss--Legendre quadrature of the
                  Cauchy integral on an ellipse around the spectrum, any analytic filter
                  (``nodes`` complex solves).
``"auto"``        the cheapest of the above meeting ``tol`` (see :func:`choose_method`).
"""
from __future__ import annotations

from .choice import HEAT_ONLY, LARGE_T, METHODS, OPTIONS, PROOF_PREMIUM, check_engine_options, choose_method
from .operator import SpectralOperator, ZeroPlan, apply_filter, spectral_operator

__all__ = ["apply_filter", "SpectralOperator", "spectral_operator", "METHODS", "HEAT_ONLY", "OPTIONS", "check_engine_options",
           "choose_method"]
