"""Families of filters sharing poles: kernel diagonals and columns at many scales.

Heat at many times, WKS at many energies: one set of common poles, one factorization per
pole for the whole family, and each member's residues certified on their own.

- :mod:`.fits`: the poles (hyperbolic contours for heat, set-valued AAA otherwise) and the
  certified per-member residues;
- :mod:`.diagonals`: kernel diagonals, one selected inversion per pole;
- :mod:`.columns`: heat-kernel columns, one block solve per pole.
"""
from .columns import heat_columns
from .diagonals import MultiDiagonal, diagonals_from_fits, family_diagonals, heat_diagonals
from .fits import HYPERBOLA, SCALAR_FLOOR, as_filters, family_poles, fit_family, heat_poles, heat_targets

__all__ = ["MultiDiagonal", "family_poles", "heat_poles", "fit_family", "family_diagonals",
           "diagonals_from_fits", "heat_targets", "SCALAR_FLOOR",
           "heat_diagonals", "heat_columns", "HYPERBOLA", "as_filters"]
