"""Generated shapes with known answers, for tests, examples and benchmarks.

Run ``python -m data_generators --help`` to write them to files.
"""
from .shapes import box_eigenvalues, box_tets, icosphere, sphere_eigenvalues

__all__ = ["icosphere", "sphere_eigenvalues", "box_tets", "box_eigenvalues"]
