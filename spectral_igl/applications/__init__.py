"""Applications built on the engine: harmonic functions and critical points, smoothing,
time-scale selection, geodesic and transport distances, basis functions, waves,
mean-curvature flow, shape comparison, shape correspondence."""
from .basis import diffusion_basis, feature_points, graph_extrema
from .compare import heat_trace, retrieval_scores, shape_distance, shape_distance_matrix, shape_dna
from .correspondence import (Correspondence, functional_map, landmark_descriptors, map_error,
                             match_shapes, pair_descriptors, point_map, zoomout)
from .critical_points import CriticalPoints, critical_points
from .geodesics import HeatGeodesics, geodesic_distance, varadhan_distance
from .harmonic import harmonic
from .mcf import mean_curvature_flow
from .scale import HeatFamily, optimal_shape_time, optimal_time, shape_noise
from .smoothing import diffusion_smooth, smooth, smooth_constrained
from .transport import sinkhorn, wasserstein_barycenter, wasserstein_distance
from .waves import schrodinger

__all__ = [
    "CriticalPoints", "critical_points", "harmonic",
    "smooth", "smooth_constrained", "diffusion_smooth", "optimal_time", "optimal_shape_time", "shape_noise", "HeatFamily",
    "HeatGeodesics", "geodesic_distance", "varadhan_distance",
    "sinkhorn", "wasserstein_distance", "wasserstein_barycenter",
    "diffusion_basis", "feature_points", "graph_extrema",
    "schrodinger", "mean_curvature_flow",
    "shape_dna", "heat_trace", "shape_distance", "shape_distance_matrix", "retrieval_scores",
    "Correspondence", "match_shapes", "pair_descriptors", "landmark_descriptors", "functional_map",
    "point_map", "zoomout", "map_error",
]
