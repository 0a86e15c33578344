"""Domains to (L, B): triangle and tetrahedral meshes, point clouds, voxels, graphs.

Also the :class:`Laplacian`'s cache and the proved bounds of its spectrum that need no
factorization.
"""
from ._operator import Laplacian, make_laplacian
from .anisotropic import anisotropic_laplacian
from .bounds import entry_error, lambda_max, lambda_max_kind, mass_ratio
from .cache import Cache
from .graph import graph_laplacian
from .inputs import as_laplacian
from .mesh import laplacian
from .points import point_cloud_laplacian
from .polygon import polygon_laplacian
from .tetrahedralize import tetrahedralize
from .units import TIME_UNITS, mean_edge_length, shape_time, time_scale
from .voxels import voxel_laplacian

__all__ = ["Laplacian", "Cache", "make_laplacian", "as_laplacian", "laplacian",
           "point_cloud_laplacian", "anisotropic_laplacian", "voxel_laplacian",
           "graph_laplacian", "tetrahedralize", "lambda_max", "lambda_max_kind", "mass_ratio",
           "entry_error", "TIME_UNITS", "shape_time", "time_scale", "mean_edge_length",
           "polygon_laplacian"]
