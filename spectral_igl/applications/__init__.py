"""Applications built on the engine: harmonic functions and critical points, smoothing,
time-scale selection, geodesic and transport distances, basis functions, waves."""
from .critical_points import CriticalPoints, critical_points
from .geodesics import HeatGeodesics, geodesic_distance, varadhan_distance
from .harmonic import harmonic
from .smoothing import diffusion_smooth, smooth, smooth_constrained

__all__ = [
    "CriticalPoints", "critical_points", "harmonic",
    "smooth", "smooth_constrained", "diffusion_smooth",
    "HeatGeodesics", "geodesic_distance", "varadhan_distance",
]
