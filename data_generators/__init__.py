"""The generated shapes of :mod:`spectral_igl.data_generators`, under the repository's short name.

``from data_generators import icosphere`` and ``from data_generators.perturb import ...``
(tests, examples, benchmarks of this repository) and ``python -m data_generators`` keep
working from a checkout; installed packages reach the same modules as
``spectral_igl.data_generators``.
"""
import importlib
import sys

from spectral_igl.data_generators import *  # noqa: F401,F403
from spectral_igl.data_generators import __all__  # noqa: F401

# the submodules are the package's own module objects, not second copies
for _sub in ("flat_torus", "perturb", "shapes", "surfaces"):
    sys.modules[f"{__name__}.{_sub}"] = importlib.import_module(f"spectral_igl.data_generators.{_sub}")
