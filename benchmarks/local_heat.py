"""Local heat kernel columns against the global path, ``expm_multiply`` and one Cholesky.

For each shape (unit area) and t: the region :func:`spectral_igl.local_heat_kernel` grows
(vertices, share of n), the time of a cold local column (the Laplacian's cache cleared first,
so everything the call derives is included), of a cold global ``sig.heat_kernel`` column
(default tol 1e-8, ``method="rational"``: the global path), of the default
``sig.heat_kernel`` (``method="auto"``: local when the region is cheap, the global path after a
bounded attempt otherwise), of scipy's ``expm_multiply`` on the lumped operator B^-1 L, all as ratios
to one cholespy Cholesky factorization of B + tL in the same process; the largest error of the
local column against a global reference (``heat_kernel`` at tol 1e-12, ``"rational"``, whose bound is
added), the largest proved bound, the B-norm bound against the tolerance's target, and the
number of entries of the local and the auto columns outside their bound (must be 0).
Medians over the sources.

With ``--targets``: diffusion distances from the first source to that many random targets,
``sig.diffusion_distance(lap, t, s, targets)`` by default (local half-time columns when they fit
their budget) and with ``method="rational"`` (the global path), cold, as ratios to one
Cholesky, and the number of distances where the two differ by more than the sum of their
proved bounds (must be 0).

Usage::

    python benchmarks/local_heat.py --mesh ../shared/data/meshes/armadillo.obj
    python benchmarks/local_heat.py --mesh ../shared/data/meshes/armadillo.obj --subdivide 1
    python benchmarks/local_heat.py --mesh ../shared/data/meshes/stanford-bunny.obj --subdivide 1 \
        --times 1e-5 1e-4 --targets 1 8 32
"""
from __future__ import annotations

import argparse
import datetime
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import expm_multiply

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import spectral_igl as sig  # noqa: E402
from spectral_igl.data_generators import midpoint_subdivide  # noqa: E402
from _timing import median_time  # noqa: E402


def load(path, subdivide):
    import igl

    V, F = igl.read_triangle_mesh(path)[:2]
    name = Path(path).name
    if subdivide:
        V, F = midpoint_subdivide(V, F, subdivide)
        name += f" (midpoint x{4 ** subdivide})"
    lap = sig.laplacian(V, F)
    return name, sig.laplacian(V / np.sqrt(lap.area()), F)


def cholesky_seconds(lap, t):
    from cholespy import CholeskySolverD, MatrixType

    M = (lap.B + t * lap.L).tocoo()

    def run():
        CholeskySolverD(lap.n, M.row, M.col, M.data, MatrixType.COO)

    return median_time(run, 3)[0]


def cold(lap, fn):
    lap.cache.clear()
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def row(lap, t, sources, chol):
    n = lap.n
    A = sp.csr_matrix(sp.diags(-t / lap.mass) @ lap.L)
    r = {k: [] for k in ("region", "local", "auto", "glob", "expm", "err", "bound", "bnorm", "bad",
                         "expm_err", "auto_bad")}
    method, auto = set(), set()
    for s in sources:
        sec, (k, info) = cold(lap, lambda: sig.local_heat_kernel(lap, t, s, return_info=True))
        method.add(info["method"])
        r["local"].append(sec / chol)
        r["region"].append(info["region"])
        sec, (ka, ainfo) = cold(lap, lambda: sig.heat_kernel(lap, t, s, return_info=True))
        auto.add(ainfo["method"])
        r["auto"].append(sec / chol)
        r["glob"].append(cold(lap, lambda: sig.heat_kernel(lap, t, s, method="rational"))[0] / chol)
        with warnings.catch_warnings():     # the reference's bound is used as it is, met or not
            warnings.simplefilter("ignore", sig.accuracy.AccuracyWarning)
            ref, rinfo = sig.heat_kernel(lap, t, s, method="rational", tol=1e-12, return_info=True)
        g = np.zeros(n)
        g[s] = 1.0 / lap.mass[s]
        t0 = time.perf_counter()
        x = expm_multiply(A, g)
        r["expm"].append((time.perf_counter() - t0) / chol)
        r["expm_err"].append(float(np.max(np.abs(x - ref))) / ref.max())
        d = np.abs(k - ref)
        r["err"].append(float(d.max()) / ref.max())
        r["bound"].append(float(info["abs_error"].max()) / ref.max())
        r["bnorm"].append(float(info["bnorm_error"]) * np.sqrt(lap.mass[s]) / 1e-8)
        r["bad"].append(int(np.count_nonzero(d > info["abs_error"] + rinfo["abs_error"])))
        r["auto_bad"].append(int(np.count_nonzero(np.abs(ka - ref) > ainfo["abs_error"] + rinfo["abs_error"])))
    med = {k: float(np.median(v)) for k, v in r.items()}
    med["bad"] = int(np.sum(r["bad"]) + np.sum(r["auto_bad"]))
    return med, "/".join(sorted(method)), "/".join(sorted(auto))


def distance_rows(lap, times, source, counts):
    """Print the diffusion-distance table: local (auto) against the global path."""
    print("| t | targets | auto's path | auto | global | Cholesky (s) | max difference / max distance | "
          "outside both bounds |")
    print("|---|---|---|---|---|---|---|---|")
    rng = np.random.default_rng(1)
    for t in times:
        chol = cholesky_seconds(lap, t)
        for m in counts:
            targets = rng.choice(lap.n, m, replace=False)
            sec, (d, info) = cold(lap, lambda: sig.diffusion_distance(lap, t, source, targets, return_info=True))
            gsec, (g, ginfo) = cold(lap, lambda: sig.diffusion_distance(lap, t, source, targets, method="rational",
                                                                       return_info=True))
            diff = np.abs(d - g)
            bad = int(np.count_nonzero(diff > info["abs_error"] + ginfo["abs_error"]))
            print(f"| {t:g} | {m} | {info['method']} | {sec / chol:.3f} | {gsec / chol:.2f} | {chol:.3f} | "
                  f"{diff.max() / g.max():.1e} | {bad} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", required=True, help="a triangle mesh (armadillo.obj)")
    ap.add_argument("--subdivide", type=int, default=0)
    ap.add_argument("--times", type=float, nargs="+", default=[1e-6, 1e-5, 1e-4, 3e-4, 1e-3])
    ap.add_argument("--sources", type=int, default=3)
    ap.add_argument("--targets", type=int, nargs="*", default=[],
                    help="diffusion distances to this many targets instead of the heat columns")
    args = ap.parse_args(argv)
    name, lap = load(args.mesh, args.subdivide)
    sources = np.random.default_rng(0).choice(lap.n, args.sources, replace=False)
    print(f"# {platform.processor() or platform.machine()}, {datetime.date.today()}, "
          f"python {' '.join(sys.argv)}")
    print(f"# {name}: n = {lap.n}, unit area, sources {sources.tolist()}, tol = 1e-8; times / one Cholesky "
          "of B + tL; errors relative to the column's peak; B-norm bound / (tol ||B^-1 e_s||_B)")
    if args.targets:
        distance_rows(lap, args.times, int(sources[0]), args.targets)
        return
    print("| t | method | region | share of n | local | auto | auto's path | global | expm_multiply | "
          "Cholesky (s) | max error | max bound | B-norm bound / target | outside bound | expm_multiply error |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for t in args.times:
        chol = cholesky_seconds(lap, t)
        m, method, auto = row(lap, t, sources, chol)
        print(f"| {t:g} | {method} | {m['region']:.0f} | {100 * m['region'] / lap.n:.2f} % | "
              f"{m['local']:.3f} | {m['auto']:.3f} | {auto} | "
              f"{m['glob']:.2f} | {m['expm']:.2f} | {chol:.3f} | {m['err']:.1e} | {m['bound']:.1e} | "
              f"{m['bnorm']:.2f} | {m['bad']} | {m['expm_err']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
