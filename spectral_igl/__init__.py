"""spectral_igl: Laplacian spectral kernels and distances on 3D shapes.

Spectrum-free evaluation of φ(B⁻¹L)f by polynomial and rational approximation of
the filter φ, with a certified error bound, on triangle meshes, tetrahedral
meshes, point clouds, voxel grids and graphs.

The stages, each importing only from those before it: ``laplacian`` (domains to (L, B),
the cache, spectral bounds) -> ``filters`` -> ``linalg`` (factorizations, pseudo-solves,
eigenpairs) -> ``approx`` (φ(L̃)f by method) -> ``families`` (families of filters sharing
poles: diagonals and columns at many scales) -> ``diagonal`` (kernel diagonals) ->
``kernels``, ``distances``, ``descriptors``, ``embedding`` -> ``applications`` ->
``quantity`` -> ``collection`` -> ``viz`` -> ``cli``.
"""
from . import accuracy, filters, linalg
from ._validate import memory_budget, set_memory_budget
from ._version import __version__
from .applications import (
                           Correspondence,
                           CriticalPoints,
                           HeatGeodesics,
                           critical_points,
                           diffusion_basis,
                           diffusion_smooth,
                           feature_points,
                           functional_map,
                           geodesic_distance,
                           harmonic,
                           heat_trace,
                           landmark_descriptors,
                           map_error,
                           match_shapes,
                           mean_curvature_flow,
                           optimal_time,
                           pair_descriptors,
                           point_map,
                           retrieval_scores,
                           schrodinger,
                           shape_distance,
                           shape_distance_matrix,
                           shape_dna,
                           smooth,
                           smooth_constrained,
                           optimal_shape_time,
                           varadhan_distance,
                           wasserstein_barycenter,
                           wasserstein_distance,
                           zoomout,
)
from .approx import METHODS, SpectralOperator, apply_filter, spectral_operator
from .descriptors import (
                           auto_diffusion_function,
                           eccentricity,
                           hks,
                           hks_times,
                           spectral_band,
                           spectral_descriptor,
                           wks,
                           wks_energies,
)
from .diagonal import distance_colouring, kernel_diagonal
from .distances import (
                           OneToAll,
                           biharmonic_distance,
                           commute_time_distance,
                           diffusion_distance,
                           mexican_hat_distance,
                           pairwise_biharmonic_distance,
                           pairwise_commute_time_distance,
                           pairwise_diffusion_distance,
                           pairwise_mexican_hat_distance,
                           pairwise_polyharmonic_distance,
                           pairwise_spectral_distance,
                           pairwise_wave_distance,
                           polyharmonic_distance,
                           spectral_distance,
                           wave_distance,
)
from .embedding import spectral_embedding
from .kernels import heat_kernel, heat_kernels, spectral_kernel
from .local import local_heat_kernel, local_mexican_hat, sparse_diffusion_distance, sparse_heat_kernel
from .laplacian import (
                           Laplacian,
                           anisotropic_laplacian,
                           graph_laplacian,
                           lambda_max,
                           laplacian,
                           make_laplacian,
                           point_cloud_laplacian,
                           polygon_laplacian,
                           shape_time,
                           tetrahedralize,
                           time_scale,
                           voxel_laplacian,
)
from .linalg import dense_eigs, eigs, lambda_min_positive

__all__ = [
    "__version__", "memory_budget", "set_memory_budget",
    # domains
    "Laplacian", "make_laplacian", "laplacian", "point_cloud_laplacian", "anisotropic_laplacian",
    "voxel_laplacian", "graph_laplacian", "tetrahedralize", "polygon_laplacian", "lambda_max",
    "shape_time", "time_scale",
    "lambda_min_positive",
    "eigs", "dense_eigs",
    # engine
    "accuracy", "filters", "linalg", "METHODS", "apply_filter", "SpectralOperator", "spectral_operator",
    # kernels, distances, descriptors
    "spectral_kernel", "heat_kernel", "heat_kernels", "local_heat_kernel", "local_mexican_hat", "sparse_heat_kernel", "sparse_diffusion_distance", "kernel_diagonal",
    "distance_colouring",
    "spectral_distance", "OneToAll", "pairwise_spectral_distance", "pairwise_diffusion_distance",
    "pairwise_commute_time_distance", "pairwise_biharmonic_distance", "pairwise_polyharmonic_distance",
    "pairwise_wave_distance", "pairwise_mexican_hat_distance", "diffusion_distance",
    "commute_time_distance", "biharmonic_distance", "polyharmonic_distance", "wave_distance",
    "mexican_hat_distance", "spectral_descriptor", "hks", "wks", "auto_diffusion_function",
    "hks_times", "wks_energies", "spectral_band",
    "eccentricity", "spectral_embedding",
    # applications
    "CriticalPoints", "critical_points", "harmonic", "smooth", "smooth_constrained",
    "diffusion_smooth", "optimal_time", "optimal_shape_time", "HeatGeodesics", "geodesic_distance",
    "varadhan_distance", "wasserstein_distance", "wasserstein_barycenter", "diffusion_basis", "feature_points",
    "schrodinger", "mean_curvature_flow", "shape_dna", "heat_trace", "shape_distance",
    "shape_distance_matrix", "retrieval_scores",
    "Correspondence", "match_shapes", "pair_descriptors",
    "landmark_descriptors", "functional_map", "point_map", "zoomout", "map_error",
]

# --- collection ---
from . import collection  # noqa: E402  (dask and zarr are imported only when it runs)
from .retrieval import collection_distance_matrix  # noqa: E402

__all__ += ["collection", "collection_distance_matrix"]
