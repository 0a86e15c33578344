"""Debiased convolutional Wasserstein distance between two narrow bumps on unit-area shapes.

Usage::

    python benchmarks/transport.py [--shapes cow,spot,flat] [--ratios 10,20,40] [--dists 4,6,8,12,20]
                                   [--kernels geodesic,heat]

For each shape (real meshes from ``../shared/data/meshes`` (beside the checkout), ``flat``: a random Delaunay
triangulation of the unit square, 3000 points), gamma = ratio * h^2 (h the mean edge
length) and bumps (Gaussian of width h in exact geodesic distance) whose centres are
``dist`` * h apart, prints W_gamma / d - 1 (d from ``igl.exact_geodesic``), the asymmetry
|W(a, b) - W(b, a)| / W, the time of one call on a fresh Laplacian (nothing cached: the
geodesic kernel's heat-method solves included; ``--cpu`` for process time on a loaded
machine), the Sinkhorn iterations and the number of vertices the kernel acts on. Any
``.obj`` of the meshes folder is a shape (``armadillo`` has 43k vertices).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import spectral_igl as sig  # noqa: E402
from spectral_igl.applications import wasserstein_distance  # noqa: E402
from spectral_igl.applications.geodesics import mean_edge_length  # noqa: E402

MESHES = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"   # ../shared beside the checkout


def shape(name):
    import igl

    if name == "flat":
        from scipy.spatial import Delaunay

        P = np.random.default_rng(0).random((3000, 2))
        V, F = np.c_[P, np.zeros(len(P))], Delaunay(P).simplices.astype(np.int64)
    else:
        V, F = igl.read_triangle_mesh(str(MESHES / f"{name}.obj"))[:2]
    return V / np.sqrt(igl.doublearea(V, F).sum() / 2.0), F


def main(argv=None):
    import igl

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shapes", default="cow,spot,flat")
    ap.add_argument("--ratios", default="10,20,40")
    ap.add_argument("--dists", default="4,6,8,12,20")
    ap.add_argument("--steps", type=int, default=16)
    ap.add_argument("--kernels", default="geodesic,heat", help="transport kernels to compare")
    ap.add_argument("--cpu", action="store_true", help="process CPU time instead of wall time")
    args = ap.parse_args(argv)
    clock = time.process_time if args.cpu else time.perf_counter
    for name in args.shapes.split(","):
        V, F = shape(name)
        lap = sig.laplacian(V, F)
        h, n = mean_edge_length(V, F), len(V)
        p = int(np.argmin(np.linalg.norm(V - V.mean(0), axis=1)))
        geo = lambda c: igl.exact_geodesic(V, F, np.array([c]), VT=np.arange(n))  # noqa: E731
        d0 = geo(p)
        a = np.exp(-0.5 * (d0 / h) ** 2)
        for kern, r in [(kk, float(x)) for kk in args.kernels.split(",") for x in args.ratios.split(",")]:
            row, times, asym, its, sizes, ok = [], [], 0.0, [], [], True
            for k in [float(x) for x in args.dists.split(",")]:
                q = int(np.argmin(np.abs(d0 - k * h)))
                b = np.exp(-0.5 * (geo(q) / h) ** 2)
                fresh = sig.laplacian(V, F)
                t0 = clock()
                w, info = wasserstein_distance(fresh, a, b, r * h * h, kernel=kern, steps=args.steps,
                                               return_info=True)
                times.append(clock() - t0)
                w2 = wasserstein_distance(fresh, b, a, r * h * h, kernel=kern, steps=args.steps)
                asym = max(asym, abs(w - w2) / w)
                its.append(info["iterations"])
                sizes.append(info["support"])
                ok &= info["converged"]
                row.append(f"{k:g}h {w / d0[q] - 1:+.3f}")
            print(f"{name} n={n} {kern} gamma={r:g}h^2: " + "  ".join(row)
                  + f"  | max asym {asym:.1e}, {min(times):.2f}-{max(times):.2f} s/call, "
                  f"{min(its)}-{max(its)} iterations, converged {ok}, kernel on {min(sizes)}-{max(sizes)} "
                  "vertices", flush=True)


if __name__ == "__main__":
    main()
