"""Convolutional Wasserstein distance between two Diracs on the unit sphere: accuracy and time.

Usage::

    python benchmarks/transport.py [--levels 4,5] [--ratios 20,10,5,2]

For each icosphere level and gamma = ratio * h^2 (h the mean edge length), prints
W_gamma between Diracs at geodesic distance ~0.5, its relative error, and the time.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl.applications import wasserstein_distance  # noqa: E402
from spectral_igl.applications.geodesics import mean_edge_length  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--levels", default="4,5")
    ap.add_argument("--ratios", default="20,10,5,2")
    ap.add_argument("--kernel-tol", type=float, default=1e-12)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", RuntimeWarning)
    for lev in [int(x) for x in args.levels.split(",")]:
        V, F = icosphere(lev)
        lap = sig.laplacian(V, F, mass="lumped")
        h = mean_edge_length(V, F)
        p = 0
        q = int(np.argmin(np.abs(np.arccos(np.clip(V @ V[p], -1, 1)) - 0.5)))
        d = float(np.arccos(V[p] @ V[q]))
        mu0, mu1 = np.zeros(lap.n), np.zeros(lap.n)
        mu0[p], mu1[q] = 1.0, 1.0
        for r in [float(x) for x in args.ratios.split(",")]:
            g = r * h * h
            t0 = time.perf_counter()
            w = wasserstein_distance(lap, mu0, mu1, g, kernel_tol=args.kernel_tol)
            print(f"icosphere({lev}) n={lap.n} h={h:.4f} gamma={g:.4g} (= {r:g} h^2): W={w:.4f} "
                  f"geodesic={d:.4f} rel.err={(w - d) / d:+.3f}  {time.perf_counter() - t0:.1f} s", flush=True)


if __name__ == "__main__":
    main()
