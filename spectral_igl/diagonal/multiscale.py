"""Former home of the common-pole families, now :mod:`spectral_igl.families`: its names,
kept importable from here."""
from ..families import (HYPERBOLA, SCALAR_FLOOR, MultiDiagonal, as_filters, diagonals_from_fits, family_diagonals,
                        family_poles, fit_family, heat_columns, heat_diagonals, heat_poles, heat_targets)

__all__ = ["MultiDiagonal", "family_poles", "heat_poles", "fit_family", "family_diagonals",
           "diagonals_from_fits", "heat_targets", "SCALAR_FLOOR",
           "heat_diagonals", "heat_columns", "HYPERBOLA", "as_filters"]
