r"""The engine's sparse linear algebra: factorizations, grounded pseudo-solves, eigenpairs.

- :mod:`.factor`: ``factorize(A)`` over the backends (CHOLMOD through cholespy, MKL PARDISO
  through pypardiso, the package's LDLᵀ, SuperLU);
- :mod:`.ldlt`: the supernodal LDLᵀ with selected inversion (compiled), on a METIS
  nested-dissection or a minimum-degree ordering;
- :mod:`.solves`: cached factorizations of :math:`\theta B + \beta L` for one
  :class:`~spectral_igl.Laplacian`, the one grounding rule and the pseudo-inverse solves;
- :mod:`.eigen`: generalized eigenpairs (the truncated baseline and the dense ground truth)
  and the smallest positive eigenvalue.
"""
from .eigen import (EIG_METHODS, cached_eigs, dense_eigs, eigenvalue_bracket, eigs, gap_lower_bound, lambda_min_positive,
                    lambda_min_positive_kind, negative_inertia)
from .factor import BACKENDS, Factor, available_backends, factorize
from .ldlt import LDLT, Pattern
from .solves import (
                     check_backend,
                     clear_cache,
                     grounded_factor,
                     grounded_vertices,
                     inverse_mass_diagonal,
                     ldlt_factor,
                     ldlt_pattern,
                     MassTraces,
                     mass_solve,
                     pseudo_solve,
                     shifted_factor,
)

__all__ = ["factorize", "Factor", "available_backends", "BACKENDS", "LDLT", "Pattern",
           "shifted_factor", "mass_solve", "inverse_mass_diagonal", "pseudo_solve", "grounded_vertices", "grounded_factor",
           "ldlt_pattern", "ldlt_factor", "MassTraces", "check_backend", "clear_cache", "eigs", "EIG_METHODS", "dense_eigs",
           "cached_eigs", "lambda_min_positive", "lambda_min_positive_kind", "negative_inertia", "eigenvalue_bracket",
           "gap_lower_bound"]
