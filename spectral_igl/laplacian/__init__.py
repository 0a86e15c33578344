"""Domains to (L, B): triangle and tetrahedral meshes, point clouds, voxels, graphs."""
from ._operator import Laplacian, make_laplacian
from .eigen import dense_eigs, eigs
from .mesh import laplacian

# --- constructors ---
from .anisotropic import anisotropic_laplacian
from .graph import graph_laplacian
from .points import point_cloud_laplacian
from .polygon import polygon_laplacian
from .tetrahedralize import tetrahedralize
from .voxels import voxel_laplacian

__all__ = ["Laplacian", "make_laplacian", "laplacian", "eigs", "dense_eigs",
           "point_cloud_laplacian", "anisotropic_laplacian", "voxel_laplacian",
           "graph_laplacian", "tetrahedralize", "polygon_laplacian"]
