"""Generated shapes with known answers, for tests, examples and benchmarks.

Run ``python -m spectral_igl.data_generators --help`` to write them to files.
"""
from .flat_torus import flat_torus, flat_torus_eigenvalues, flat_torus_laplacian
from .perturb import (bend, gaussian_noise, make_holes, mean_edge_length, midpoint_subdivide,
                      normal_noise, resample, sample_points, vertex_normals, volume_from_surface)
from .shapes import box_eigenvalues, box_tets, icosphere, sphere_eigenvalues
from .surfaces import (box_voxel_eigenvalues, box_voxels, cylinder, cylinder_eigenvalues,
                       quad_sphere, sphere_points, torus, uv_sphere)

__all__ = ["icosphere", "uv_sphere", "sphere_eigenvalues", "sphere_points", "torus", "cylinder",
           "cylinder_eigenvalues", "box_tets", "box_eigenvalues", "box_voxels",
           "box_voxel_eigenvalues", "gaussian_noise", "normal_noise", "resample", "make_holes",
           "sample_points", "midpoint_subdivide", "volume_from_surface", "vertex_normals",
           "mean_edge_length", "bend",
           "flat_torus", "flat_torus_laplacian", "flat_torus_eigenvalues", "quad_sphere"]
