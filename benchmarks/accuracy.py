"""Per-method accuracy of e^{-tL̃}f against the dense ground truth (the survey's Fig. 13-14, redone).

Unit-area icosphere (n = 2562 by default), f = a discrete delta B⁻¹e_i (a heat-kernel column)
and a random signal; relative B-norm error and the certified bound of every method and
setting at t = 1e-5, 1e-4, ..., 10. Then wave and singular filters against dense, and the
semigroup and scale-covariance identities. Prints markdown tables.

Usage::

    python benchmarks/accuracy.py            # n = 2562
    python benchmarks/accuracy.py --level 3  # n = 642, quick
    python benchmarks/accuracy.py --json-dir docs/results   # also write the three tables as JSON
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import Table  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl import filters  # noqa: E402

HEAT_SETTINGS = [
    ("rational", {}), ("rational", {"degree": 6}), ("rational", {"degree": 14}), ("contour", {}),
    ("contour", {"nodes": 32}), ("gauss_legendre", {}), ("shift_invert", {}), ("shift_invert", {"steps": 60}),
    ("chebyshev", {}), ("krylov", {"steps": 30}), ("taylor", {}), ("power", {}),
    ("euler", {"steps": 1}), ("euler", {"steps": 10}), ("taylor1", {}),
    ("eigen", {"k": 100}), ("eigen", {"k": 500}),
]


def bnorm(lap, x):
    return np.sqrt(np.maximum(np.real(np.sum(np.conj(x) * (lap.B @ x), axis=0)), 0))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--level", type=int, default=4)
    p.add_argument("--times", nargs="*", type=float,
                   default=[1e-8, 1e-5, 1e-3, 1e-1, 1.0, 10.0, 1e4, 1e12, 1e300])
    p.add_argument("--mass", default="lumped", choices=("lumped", "full"))
    p.add_argument("--json-dir", help="also write the tables as accuracy_heat.json, "
                   "accuracy_filters.json and accuracy_identities.json in this folder")
    p.add_argument("--methods", nargs="*", default=None, help="only these heat methods (default: all)")
    p.add_argument("--filter-methods", nargs="*", default=["auto"],
                   help="methods of the other-filters table (default: auto)")
    args = p.parse_args(argv)

    V, F = icosphere(args.level)
    lap0 = sig.laplacian(V, F, mass=args.mass)
    V = V / np.sqrt(lap0.area())
    lap = sig.laplacian(V, F, mass=args.mass)
    ev, X = sig.dense_eigs(lap)
    n = lap.n
    g = np.zeros(n)
    g[0] = 1.0
    print(f"unit-area icosphere, n = {n}, lambda_max = {ev[-1]:.4g} (bound used: {sig.lambda_max(lap):.4g})\n")
    print("Heat-kernel column e^{-tL̃}B⁻¹e_0: relative B-norm error [bound; P = proof, E = estimate] "
          "(tol 1e-8)\n")
    table = Table("accuracy_heat", ["method", "settings"] + [f"t = {t:.0e}" for t in args.times],
                  args.json_dir)
    for method, opts in HEAT_SETTINGS:
        if args.methods is not None and method not in args.methods:
            continue
        cells = []
        for t in args.times:
            ref = X @ (np.exp(-t * ev) * X[0])
            try:
                op = sig.SpectralOperator(lap, filters.heat(t), method=method, **opts)
                u = op.apply_inverse_mass(g)
                e = bnorm(lap, u - ref) / bnorm(lap, ref)
                b = "" if op.error_bound is None else \
                    f" [{op.error_bound / bnorm(lap, ref):.1e} {op.bound_kind[0].upper()}]"
                cells.append(f"{e:.1e}{b}")
            except ValueError as exc:
                cells.append("refused")
        table.add(method, ", ".join(f"{k} = {v}" for k, v in opts.items()), *cells)
    table.close()

    rng = np.random.default_rng(0)
    f = rng.standard_normal(n)
    print("\nOther filters, random f (tol 1e-8): relative B-norm error [bound]\n")
    table = Table("accuracy_filters", ["filter", "method", "error", "bound", "kind", "solves"],
                  args.json_dir)
    for filt, fm in [(filt, fm) for filt in [
            filters.wave(1e-3), filters.wave(1e-2), filters.biharmonic(), filters.commute_time(),
            filters.polyharmonic(3), filters.polyharmonic(4), filters.mexican_hat(1e-3),
            filters.multiscale(1e-2, 1, 1.0)] for fm in args.filter_methods]:
        ref = X @ (filt(ev) * (X.T @ (lap.B @ f)))
        try:
            op = sig.SpectralOperator(lap, filt, method=fm)
        except ValueError as exc:
            table.add(f"`{filt!r}`", fm, f"refused: {exc}", "", "", "")
            continue
        u = op.apply(f)
        e = bnorm(lap, u - ref) / bnorm(lap, ref)
        table.add(f"`{filt!r}`", op.method, f"{e:.1e}", f"{op.error_bound / bnorm(lap, ref):.1e}",
                  op.bound_kind, op.n_solves)
    table.close()

    print("\nIdentities (method auto, tol 1e-12)\n")
    table = Table("accuracy_identities", ["identity", "relative error"], args.json_dir)
    s, t = 1e-3, 1e-2
    a = sig.apply_filter(lap, filters.heat(s), sig.apply_filter(lap, filters.heat(t), f, tol=1e-12), tol=1e-12)
    b = sig.apply_filter(lap, filters.heat(s + t), f, tol=1e-12)
    table.add(f"semigroup K_s K_t f = K_(s+t) f, s = {s}, t = {t}", f"{bnorm(lap, a - b) / bnorm(lap, b):.1e}")
    alpha = 3.0
    lap2 = sig.laplacian(alpha * V, F, mass=args.mass)
    u2 = sig.apply_filter(lap2, filters.heat(t), f, tol=1e-12)
    u1 = sig.apply_filter(lap, filters.heat(t / alpha ** 2), f, tol=1e-12)
    table.add(f"scale covariance e^(−t L̃(aV)) f = e^(−(t/a²) L̃(V)) f, a = {alpha}",
              f"{np.linalg.norm(u2 - u1) / np.linalg.norm(u1):.1e}")
    table.close()


if __name__ == "__main__":
    main()
