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

# --- kernels and distances ---
from ._diagonal import distance_colouring, kernel_diagonal  # noqa: E402
from .descriptors import auto_diffusion_function, eccentricity, hks, spectral_descriptor, wks  # noqa: E402
from .distances import (  # noqa: E402
    biharmonic_distance,
    commute_time_distance,
    diffusion_distance,
    mexican_hat_distance,
    pairwise_spectral_distance,
    polyharmonic_distance,
    spectral_distance,
    wave_distance,
)
from .embedding import spectral_embedding  # noqa: E402
from .kernels import heat_kernel, spectral_kernel  # noqa: E402

__all__ += [
    "spectral_kernel", "heat_kernel", "kernel_diagonal", "distance_colouring",
    "spectral_distance", "pairwise_spectral_distance", "diffusion_distance",
    "commute_time_distance", "biharmonic_distance", "polyharmonic_distance", "wave_distance",
    "mexican_hat_distance", "spectral_descriptor", "hks", "wks", "auto_diffusion_function",
    "eccentricity", "spectral_embedding",
]

# --- applications ---
from .applications import (  # noqa: E402
    CriticalPoints, HeatGeodesics, critical_points, diffusion_basis,
    diffusion_smooth, feature_points, geodesic_distance, harmonic, optimal_time, schrodinger,
    smooth, smooth_constrained, varadhan_distance, wasserstein_distance,
)

__all__ += [
    "CriticalPoints", "critical_points", "harmonic", "smooth", "smooth_constrained",
    "diffusion_smooth", "optimal_time", "HeatGeodesics", "geodesic_distance",
    "varadhan_distance", "wasserstein_distance", "diffusion_basis", "feature_points",
    "schrodinger",
]
# --- end applications ---

# --- collection ---
from . import collection  # noqa: E402  (dask and zarr are imported only when it runs)

__all__ += ["collection"]
