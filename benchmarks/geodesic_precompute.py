"""Heat-geodesic precompute time against libigl and potpourri3d, and one Cholesky of B + tL.

    OPENBLAS_NUM_THREADS=1 python benchmarks/geodesic_precompute.py [--meshes DIR] [--repeat 3]

Each mesh is scaled to unit area; each time is the best of ``--repeat`` runs in this process.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import spectral_igl as sig
from spectral_igl.applications.geodesics import HeatGeodesics
from spectral_igl.io import read_mesh
from spectral_igl.linalg import factorize

ROOT = Path(__file__).resolve().parents[1]


def best(fn, repeat):
    out = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t0)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=Path, default=ROOT.parent / "shared" / "data" / "meshes")
    ap.add_argument("--names", default="cow.obj,homer.obj,fandisk.obj,rocker-arm.obj,armadillo.obj")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    import igl

    try:
        import potpourri3d as pp3d
    except ImportError:
        pp3d = None
    print("| mesh | n | spectral_igl (s) | libigl (s) | potpourri3d (s) | ours ÷ libigl | ours ÷ Cholesky |")
    print("|---|---|---|---|---|---|---|")
    for name in args.names.split(","):
        V, F = read_mesh(args.meshes / name)
        lap0 = sig.laplacian(V, F, mass="lumped")
        V = V / np.sqrt(lap0.area())
        lap = sig.laplacian(V, F, mass="lumped")
        h = float(igl.avg_edge_length(V, F))
        ours = best(lambda: HeatGeodesics(lap), args.repeat)

        def libigl():
            data = igl.HeatGeodesicsData()
            igl.heat_geodesics_precompute(V, F, h * h, data)

        theirs = best(libigl, args.repeat)
        pp = best(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F), args.repeat) if pp3d else float("nan")
        chol = best(lambda: factorize(lap.B + h * h * lap.L), args.repeat)
        print(f"| {name} | {lap.n:,} | {ours:.3f} | {theirs:.3f} | {pp:.3f} | {ours / theirs:.2f} | "
              f"{ours / chol:.2f} |", flush=True)


if __name__ == "__main__":
    main()
