"""Command line: write a generated shape to a file.

Examples::

    python -m spectral_igl.data_generators icosphere --level 4 --out sphere.obj
    python -m spectral_igl.data_generators torus --out torus.off --normal-noise 0.01
    python -m spectral_igl.data_generators cylinder --holes 3 --out cyl.obj
    python -m spectral_igl.data_generators icosphere --points 10000 --out pts.npy
    python -m spectral_igl.data_generators box_tets --out box.mesh
    python -m spectral_igl.data_generators box_voxels --out box.npy
    python -m spectral_igl.data_generators volume --level 3 --out ball.mesh
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from . import (box_tets, box_voxels, cylinder, gaussian_noise, icosphere, make_holes,
               mean_edge_length, normal_noise, resample, sample_points, torus, uv_sphere,
               volume_from_surface)

SHAPES = ("icosphere", "uv_sphere", "torus", "cylinder", "box_tets", "box_voxels", "volume")


def _surface(a):
    if a.shape == "icosphere" or a.shape == "volume":
        return icosphere(a.level)
    if a.shape == "uv_sphere":
        return uv_sphere(a.n, 2 * a.n)
    if a.shape == "torus":
        return torus(n_major=2 * a.n, n_minor=max(3, a.n // 2))
    return cylinder(n_theta=2 * a.n, n_z=a.n)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m spectral_igl.data_generators", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("shape", choices=SHAPES)
    p.add_argument("--out", required=True, help=".obj/.off/.ply/.stl (surface), .mesh (tets), "
                   ".npy (points, voxel mask, or vertices)")
    p.add_argument("--level", type=int, default=3, help="icosphere subdivision level")
    p.add_argument("--n", type=int, default=32, help="resolution of uv_sphere/torus/cylinder/boxes")
    p.add_argument("--noise", type=float, default=0.0, help="Gaussian noise, in mean edge lengths")
    p.add_argument("--normal-noise", type=float, default=0.0, help="noise along normals, in mean edge lengths")
    p.add_argument("--resample", type=float, default=0.0, help="fraction of faces split irregularly")
    p.add_argument("--holes", type=int, default=0, help="number of holes to cut")
    p.add_argument("--points", type=int, default=0, help="sample this many points (writes .npy)")
    p.add_argument("--nonuniform", type=float, default=0.0, help="density contrast of the point sample")
    p.add_argument("--edge-length-fac", type=float, default=0.1, help="tet size for 'volume'")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    out = Path(a.out)
    if a.shape == "box_voxels":
        mask, spacing = box_voxels((a.n, a.n, a.n), (1.0, 1.0, 1.0))
        np.save(out, mask)
        print(f"wrote {out}: mask {mask.shape}, spacing {spacing.tolist()}")
        return 0
    if a.shape == "box_tets":
        V, T = box_tets((a.n, a.n, a.n), (1.0, 1.0, 1.0))
        from ..io import write_mesh

        write_mesh(out, V, T)
        print(f"wrote {out}: {len(V)} vertices, {len(T)} tetrahedra")
        return 0
    V, F = _surface(a)
    h = mean_edge_length(V, F)
    if a.resample:
        V, F = resample(V, F, a.resample, seed=a.seed)
    if a.noise:
        V = gaussian_noise(V, a.noise * h, seed=a.seed)
    if a.normal_noise:
        V = normal_noise(V, F, a.normal_noise * h, seed=a.seed)
    if a.holes:
        V, F = make_holes(V, F, a.holes, seed=a.seed)
    if a.shape == "volume":
        V, T = volume_from_surface(V, F, edge_length_fac=a.edge_length_fac)
        from ..io import write_mesh

        write_mesh(out, V, T)
        print(f"wrote {out}: {len(V)} vertices, {len(T)} tetrahedra")
        return 0
    if a.points:
        P = sample_points(V, F, a.points, density=a.nonuniform or None, seed=a.seed)
        np.save(out, P)
        print(f"wrote {out}: {len(P)} points")
        return 0
    if out.suffix == ".npy":
        np.save(out, V)
        print(f"wrote {out}: {len(V)} vertices (faces not saved in .npy)")
        return 0
    from ..io import write_mesh

    write_mesh(out, V, F)
    print(f"wrote {out}: {len(V)} vertices, {len(F)} faces")
    return 0


if __name__ == "__main__":
    sys.exit(main())
