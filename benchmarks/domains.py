"""The README's table of domains: spectrum error of each discretisation at two sizes.

Against analytic spectra: the unit sphere's l(l+1) (first 16 nonzero eigenvalues, largest
relative error) for triangles (icospheres), quads (cube spheres, polygon Laplacian) and
point clouds sampled four ways (the default ``point_cloud_laplacian`` beside
robust_laplacian, in the same run); the Neumann rectangle [0, 2] x [0, 1],
π²(i²/4 + j²) (first 8 nonzero), for quads and random points.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/domains.py [--json-dir docs/results]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere, quad_sphere, sphere_eigenvalues  # noqa: E402
from _results import Table  # noqa: E402
from point_clouds import SAMPLINGS  # noqa: E402

EX16 = sphere_eigenvalues(17)[1:]
i, j = np.meshgrid(np.arange(8), np.arange(5), indexing="ij")
RECT = np.sort((np.pi ** 2 * (i ** 2 / 4.0 + j ** 2)).ravel())[1:9]


def err(L, M, exact):
    ev = np.sort(spla.eigsh(L.tocsc(), len(exact) + 1, M.tocsc(), sigma=-1e-4)[0])[1:]
    return float(np.max(np.abs(ev - exact) / exact))


def rect_quads(nx):
    ny = nx // 2 + 1
    x, y = np.meshgrid(np.linspace(0, 2, nx), np.linspace(0, 1, ny), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(nx * ny)]
    idx = np.arange(nx * ny).reshape(nx, ny)
    Q = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4)
    return V, Q


def rect_points(n, seed=5):
    rng = np.random.default_rng(seed)
    return np.c_[rng.random((n, 2)) * [2.0, 1.0], np.zeros(n)]


def main(argv=None):
    import robust_laplacian

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    args = ap.parse_args(argv)

    rows = []
    for lev in (3, 4):
        V, F = icosphere(lev)
        lap = sig.laplacian(V, F)
        rows.append(("sphere, triangles (cotan)", len(V), err(lap.L, lap.B, EX16), None))
    for n in (16, 32):
        V, Q = quad_sphere(n)
        lap = sig.laplacian(V, Q)
        rows.append(("sphere, quads (polygon Laplacian)", len(V), err(lap.L, lap.B, EX16), None))
    for name, gen in SAMPLINGS.items():
        for n in (4000, 16000):
            P = gen(n)
            lap = sig.point_cloud_laplacian(P)
            L, M = robust_laplacian.point_cloud_laplacian(P)
            rows.append((f"sphere, points ({name})", n, err(lap.L, lap.B, EX16), err(L, M, EX16)))
    for nx in (41, 81):
        V, Q = rect_quads(nx)
        lap = sig.laplacian(V, Q)
        rows.append(("Neumann rectangle, quads", len(V), err(lap.L, lap.B, RECT), None))
    for n in (4000, 16000):
        P = rect_points(n)
        lap = sig.point_cloud_laplacian(P)   # the default finds the rim ("auto")
        L, M = robust_laplacian.point_cloud_laplacian(P)
        rows.append(("Neumann rectangle, random points", n, err(lap.L, lap.B, RECT), err(L, M, RECT)))
        for b in (True, False):   # every open cell a rim; none (clipped as on a closed surface)
            lap = sig.point_cloud_laplacian(P, boundary=b)
            rows.append((f"Neumann rectangle, random points (`boundary={b}`)", n, err(lap.L, lap.B, RECT), None))
    table = Table("domains", ["domain", "n", "spectral_igl", "robust_laplacian"], args.json_dir)
    for name, n, e, r in rows:
        table.add(name, f"{n:,}", f"{100 * e:.2f}%", "" if r is None else f"{100 * r:.2f}%")
    table.close()


if __name__ == "__main__":
    main()
