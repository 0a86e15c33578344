"""Domains to (L, B): triangle and tetrahedral meshes, point clouds, voxels, graphs."""
from ._operator import Laplacian, make_laplacian
from .eigen import dense_eigs, eigs
from .mesh import laplacian

__all__ = ["Laplacian", "make_laplacian", "laplacian", "eigs", "dense_eigs"]
