"""Heat-geodesic precompute and per-source solve time against libigl and potpourri3d, and one
Cholesky of B + tL.

``from (V, F)`` is the precompute as a user runs it, from the arrays
(``HeatGeodesics((V, F))``: the Laplacian built inside, cold); ``prebuilt`` starts from a
Laplacian built beforehand. libigl and potpourri3d start from the arrays too.

    OPENBLAS_NUM_THREADS=1 python benchmarks/geodesic_precompute.py [--meshes DIR] [--repeat 5] [--cpu] [--json-dir DIR]

Each mesh is scaled to unit area. Each time is the median of ``--repeat`` runs in this
process, the contenders taking turns within each repetition (the machine's load drifts; a
ratio compares runs made seconds apart). ``solve`` is one single-source distance (ours:
``HeatGeodesics.compute``; libigl: ``heat_geodesics_solve``): the mean over ``--sources``
sources in a row, median over the repetitions.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _results import Table  # beside this script

import spectral_igl as sig
from spectral_igl.applications.geodesics import HeatGeodesics
from spectral_igl.io import read_mesh
from spectral_igl.linalg import factorize

ROOT = Path(__file__).resolve().parents[1]


CLOCK = [time.perf_counter]


def timed(fn):
    t0 = CLOCK[0]()
    out = fn()
    return CLOCK[0]() - t0, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=Path, default=ROOT.parent / "shared" / "data" / "meshes")
    ap.add_argument("--names", default="cow.obj,spot.obj,homer.obj,fandisk.obj,rocker-arm.obj,armadillo.obj")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--sources", type=int, default=40)
    ap.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    ap.add_argument("--cpu", action="store_true",
                    help="process CPU time instead of wall time (steadier on a loaded machine)")
    args = ap.parse_args()
    if args.cpu:
        CLOCK[0] = time.process_time
    import igl

    try:
        import potpourri3d as pp3d
    except ImportError:
        pp3d = None
    table = Table("geodesic_precompute",
                  ["mesh", "n", "ours from (V, F) (s)", "ours prebuilt (s)", "libigl (s)", "potpourri3d (s)",
                   "(V, F) ÷ libigl", "prebuilt ÷ libigl", "prebuilt ÷ Cholesky", "solve: ours (ms)",
                   "solve: libigl (ms)", "solve ratio"], args.json_dir)
    for name in args.names.split(","):
        V, F = read_mesh(args.meshes / name)
        lap0 = sig.laplacian(V, F, mass="lumped")
        V = V / np.sqrt(lap0.area())
        lap = sig.laplacian(V, F, mass="lumped")
        h = float(igl.avg_edge_length(V, F))

        def libigl():
            data = igl.HeatGeodesicsData()
            igl.heat_geodesics_precompute(V, F, h * h, data)
            return data

        T = {k: [] for k in ("arrays", "ours", "libigl", "pp3d", "chol", "s_ours", "s_libigl")}
        sources = np.random.default_rng(0).choice(lap.n, args.sources, replace=False)
        for r in range(args.repeat):
            T["arrays"].append(timed(lambda: HeatGeodesics((V, F)))[0])
            dt, hg = timed(lambda: HeatGeodesics(lap))
            T["ours"].append(dt)
            dt, data = timed(libigl)
            T["libigl"].append(dt)
            if pp3d is not None:
                T["pp3d"].append(timed(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F))[0])
            T["chol"].append(timed(lambda: factorize(lap.B + h * h * lap.L))[0])
            T["s_ours"].append(timed(lambda: [hg.compute(int(s)) for s in sources])[0] / len(sources))
            T["s_libigl"].append(timed(lambda: [igl.heat_geodesics_solve(data, np.array([s]))
                                                for s in sources])[0] / len(sources))
        m = {k: float(np.median(v)) if v else float("nan") for k, v in T.items()}
        table.add(name, f"{lap.n:,}", f"{m['arrays']:.3f}", f"{m['ours']:.3f}", f"{m['libigl']:.3f}",
                  f"{m['pp3d']:.3f}", f"{m['arrays'] / m['libigl']:.2f}", f"{m['ours'] / m['libigl']:.2f}",
                  f"{m['ours'] / m['chol']:.2f}", f"{1e3 * m['s_ours']:.2f}", f"{1e3 * m['s_libigl']:.2f}",
                  f"{m['s_ours'] / m['s_libigl']:.2f}")
    table.close()


if __name__ == "__main__":
    main()
