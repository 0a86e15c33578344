"""spectral_igl: Laplacian spectral kernels and distances on 3D shapes.

Spectrum-free evaluation of φ(B⁻¹L)f by polynomial and rational approximation of
the filter φ, with a certified error bound, on triangle meshes, tetrahedral
meshes, point clouds, voxel grids and graphs.
"""
from ._version import __version__
from .laplacian import Laplacian, dense_eigs, eigs, laplacian, make_laplacian

__all__ = ["__version__", "Laplacian", "make_laplacian", "laplacian", "eigs", "dense_eigs"]

# --- engine ---
from . import filters, solvers  # noqa: E402
from .approx import SpectralOperator, apply_filter, lambda_max  # noqa: E402

__all__ += ["filters", "solvers", "apply_filter", "SpectralOperator", "lambda_max"]
# --- end engine ---

# --- constructors ---
from .laplacian import (anisotropic_laplacian, graph_laplacian, point_cloud_laplacian,  # noqa: E402
                        tetrahedralize, voxel_laplacian)

__all__ += ["point_cloud_laplacian", "anisotropic_laplacian", "voxel_laplacian",
            "graph_laplacian", "tetrahedralize"]
