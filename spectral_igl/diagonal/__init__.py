r"""The diagonal of a spectral kernel :math:`G = \varphi(\tilde L)B^{-1}` at every vertex.

One-to-all spectral distances and the descriptors need :math:`G_{ii}` at all n vertices.
:func:`kernel_diagonal` dispatches by method; each method has its room:

- :mod:`.selinv`: partial fractions of the filter and selected inversion of each
  shifted matrix (certified; exact for commute-time and biharmonic);
- :mod:`.probing`: colourings of the mesh graph with measured error;
- :mod:`.spectral`: the dense eigendecomposition (ground truth) and the truncated baseline;
- :mod:`.core`: the dispatcher and the ``"exact"`` method (n engine columns).
"""
from .core import EXACT_MAX, METHODS, check_diagonal_options, heat_projection_applies, kernel_diagonal
from .probing import distance_colouring
from ..linalg import inverse_mass_diagonal
from .selinv import NoSelinv, SelinvKernel, selinv_kernel, selinv_supported
from .spectral import eigen_diagonal, low_rank, phi_values

__all__ = ["check_diagonal_options", "heat_projection_applies", "kernel_diagonal", "METHODS", "EXACT_MAX", "distance_colouring", "NoSelinv", "SelinvKernel",
           "selinv_kernel", "selinv_supported", "inverse_mass_diagonal", "eigen_diagonal",
           "low_rank", "phi_values"]
