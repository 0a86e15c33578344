"""The generated shapes of :mod:`spectral_igl.data_generators`, under the repository's short name.

``from data_generators import icosphere`` (tests, examples, benchmarks of this repository)
and ``python -m data_generators`` keep working from a checkout; installed packages reach
the same functions as ``spectral_igl.data_generators``.
"""
from spectral_igl.data_generators import *  # noqa: F401,F403
from spectral_igl.data_generators import __all__  # noqa: F401
