"""Assembly time per nonzero of every constructor, beside libigl's cotmatrix.

    python benchmarks/assembly.py --quick        # n ≈ 10k only
    python benchmarks/assembly.py                # n ≈ 10k, 160k, 655k (icosphere levels 5, 7, 8)
    python benchmarks/assembly.py --levels 5 6 7 8
    python benchmarks/assembly.py --levels 5 7 --json-dir docs/results   # also docs/results/assembly.json

Run it with the installed package (``pip install -e .``) to time the compiled kernels;
the first line of the output says which kernels were used.

Each row: best of ``--repeat`` wall-clock times, nnz(L), nanoseconds per nonzero, and the
ratio of that to ``igl.cotmatrix`` per nonzero on the sphere of the same n. Point clouds
have the same n (random points on the sphere), voxels a cube of about n voxels, graphs
the edges of the same sphere.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from _results import Table  # beside this script

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere, sphere_points  # noqa: E402


def best(fn, repeat):
    out, ts = None, []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return min(ts), out


def rows_for_level(level, repeat, skip):
    import igl

    V, F = icosphere(level)
    n = len(V)
    P = sphere_points(n, seed=0)
    side = max(2, round(n ** (1 / 3)))
    mask = np.ones((side, side, side), bool)
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    cases = [
        ("igl.cotmatrix", lambda: igl.cotmatrix(V, F)),
        ("laplacian (defaults: intrinsic Delaunay cotan, lumped mass)", lambda: sig.laplacian(V, F)),
        ("laplacian (cotan, full mass)", lambda: sig.laplacian(V, F, weights="cotan", mass="full")),
        ("anisotropic_laplacian", lambda: sig.anisotropic_laplacian(V, F, 1.0)),
        ("point_cloud_laplacian belkin", lambda: sig.point_cloud_laplacian(P, method="belkin")),
        ("point_cloud_laplacian liu", lambda: sig.point_cloud_laplacian(P, method="liu")),
        ("point_cloud_laplacian belkin k=16", lambda: sig.point_cloud_laplacian(P, k=16, method="belkin")),
        ("point_cloud_laplacian delaunay", lambda: sig.point_cloud_laplacian(P)),
        ("voxel_laplacian", lambda: sig.voxel_laplacian(mask, 1.0 / side)),
        ("graph_laplacian", lambda: sig.graph_laplacian(n, E)),
    ]
    try:
        import robust_laplacian

        cases.append(("robust_laplacian.point_cloud_laplacian", lambda: robust_laplacian.point_cloud_laplacian(P)))
    except ImportError:
        pass
    rows, ref = [], None
    for name, fn in cases:
        if any(s in name for s in skip):
            continue
        try:
            t, out = best(fn, repeat)
        except ValueError as exc:          # e.g. beyond the memory budget: say so in the row
            rows.append((level, name, None, None, None, None, f"refused: {str(exc).split(';')[0]}"))
            continue
        L = out.L if isinstance(out, sig.Laplacian) else out[0] if isinstance(out, tuple) else out
        nnz = L.nnz
        per = t / nnz
        ref = per if ref is None else ref
        size = out.n if isinstance(out, sig.Laplacian) else L.shape[0]
        rows.append((level, name, size, nnz, t, per * 1e9, per / ref))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="n ≈ 10k only")
    ap.add_argument("--levels", type=int, nargs="*", default=None, help="icosphere levels (n = 10·4^l + 2)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip", nargs="*", default=[], help="skip constructors whose name contains any of these")
    ap.add_argument("--json-dir", help="also write the table as assembly.json in this folder (docs/results)")
    a = ap.parse_args(argv)
    levels = a.levels or ([5] if a.quick else [5, 7, 8])
    warnings.simplefilter("ignore")
    try:
        from spectral_igl.laplacian import _assembly  # noqa: F401
        compiled = "compiled kernels (spectral_igl.laplacian._assembly)"
    except ImportError:
        compiled = "NumPy reference kernels (no spectral_igl.laplacian._assembly build)"
    print(f"{compiled}; numpy {np.__version__}\n")
    table = Table("assembly", ["n", "constructor", "rows", "nnz(L)", "seconds", "ns / nnz", "× cotmatrix per nnz"],
                  a.json_dir)
    for level in levels:
        for lvl, name, size, nnz, t, ns, ratio in rows_for_level(level, 1 if level >= 8 else a.repeat, a.skip):
            if size is None:
                table.add(f"{10 * 4 ** lvl + 2:,}", name, "", "", "", "", ratio)
            else:
                table.add(f"{10 * 4 ** lvl + 2:,}", name, f"{size:,}", f"{nnz:,}", f"{t:.3f}", f"{ns:.1f}",
                          f"{ratio:.2f}")
    table.close()


if __name__ == "__main__":
    main()
