"""Diffusion-time selection: does the chosen t beat t/10 and 10 t on the error to the clean signal?

Usage::

    python benchmarks/optimal_time.py [--quick] [--real cow,fandisk,spot,rocker-arm] [--cost rocker-arm]

Smooth signals plus per-vertex white noise (3% to 100% of the signal's RMS) on icosphere(3),
icosphere(4) and a 9x9x9 tetrahedral box, full and lumped mass, two noise seeds. For each
rule of :func:`spectral_igl.optimal_time` (``"risk"``, ``"lcurve"``) prints the fraction of
cases where the error to the clean signal at the chosen t is smaller than at t/10 and at
10 t, and the failures. Errors are measured with a dense eigendecomposition.

``--real``: unit-area real meshes from ``../shared/data/meshes`` (beside the checkout): two smooth functions
plus white noise (10%, 30%, 100% of their RMS) with ``optimal_time``, and the noisy shape
itself (i.i.d. or normal noise of 0.1, 0.3, 1 mean edge length h) with
``optimal_shape_time``; errors against the clean signal or shape with the engine's heat
filter (tol 1e-10). ``--cost``: CPU time of one ``optimal_time`` call in units of one
cholespy factorization of B + tL of the same mesh.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import spectral_igl as sig  # noqa: E402
from data_generators import box_tets, icosphere  # noqa: E402
from spectral_igl.applications import optimal_time  # noqa: E402


def sphere_signals(V):
    x, y, z = V.T
    return {"deg1": x, "deg2": x + 0.5 * y * z, "deg3": 5 * x * y * z + z,
            "deg5": 3 * np.real((x + 1j * y) ** 5) + x,
            "deg8": 4 * np.real((x + 1j * y) ** 8) + np.cos(3 * z),
            "bump": np.exp(-np.sum((V - V[0]) ** 2, axis=1) / 0.1)}


def box_signals(V):
    x, y, z = V.T
    return {"cos1": np.cos(np.pi * x) + 0.5 * np.cos(np.pi * y),
            "cos3": np.cos(3 * np.pi * x) * np.cos(np.pi * z) + np.cos(np.pi * y),
            "cos5": np.cos(5 * np.pi * x) + np.cos(2 * np.pi * y) * np.cos(2 * np.pi * z)}


def domains(quick):
    out = []
    levels = (3,) if quick else (3, 4)
    for lev in levels:
        V, F = icosphere(lev)
        for mass in ("full", "lumped"):
            out.append((f"icosphere({lev}) {mass}", sig.laplacian(V, F, mass=mass), sphere_signals(V)))
    V, T = box_tets((9, 9, 9), (1.0, 1.0, 1.0))
    for mass in ("full", "lumped"):
        out.append((f"tet box 9^3 {mass}", sig.laplacian(V, T, mass=mass), box_signals(V)))
    return out


MESHES = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"   # ../shared beside the checkout


def unit_mesh(name):
    import igl

    V, F = igl.read_triangle_mesh(str(MESHES / f"{name}.obj"))[:2]
    return V / np.sqrt(igl.doublearea(V, F).sum() / 2.0), F


def real(names):
    from data_generators.perturb import normal_noise
    from spectral_igl.applications import optimal_shape_time

    ok_all = []
    for name in names:
        V, F = unit_mesh(name)
        h = float(np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)))
        c = V - V.mean(0)
        cases = []
        lap = sig.laplacian(V, F)
        for sname, clean in (("smooth", np.sin(4 * c[:, 0]) + 3 * np.cos(3 * c[:, 1]) * c[:, 2]),
                             ("lowfreq", c[:, 0] + 0.5 * c[:, 1] * c[:, 2])):
            rms = np.sqrt(clean @ (lap.B @ clean) / lap.area())
            for nl in (0.1, 0.3, 1.0):
                f = clean + nl * rms * np.random.default_rng(1).standard_normal(lap.n)
                cases.append((f"{sname} noise {nl:g} rms", lap, f, clean, optimal_time(lap, f)[0]))
        for kind in ("iid", "normal"):
            for nl in (0.1, 0.3, 1.0):
                rng = np.random.default_rng(1)
                Vn = V + nl * h * rng.standard_normal(V.shape) if kind == "iid" else normal_noise(V, F, nl * h, seed=1)
                lapn = sig.laplacian(Vn, F)
                cases.append((f"shape {kind} {nl:g} h", lapn, Vn, V, optimal_shape_time(lapn)[0]))
        for label, lp, f, clean, t in cases:
            def err(s):
                d = np.real(sig.apply_filter(lp, sig.filters.heat(s), f, tol=1e-10)) - clean
                return float(np.sqrt(np.sum(d * (lp.B @ d))))
            e = [err(t / 10), err(t), err(10 * t)]
            ok = e[1] < e[0] and e[1] < e[2]
            ok_all.append(ok)
            print(f"{name:11s} {label:22s} t={t / h / h:7.3f} h^2  e(t/10)/e(t)={e[0] / e[1]:.2f} "
                  f"e(10t)/e(t)={e[2] / e[1]:.2f}  {'ok' if ok else 'MISS'}", flush=True)
    print(f"real shapes: {sum(ok_all)}/{len(ok_all)} beat t/10 and 10 t")


def cost(name):
    import time

    from cholespy import CholeskySolverD, MatrixType

    V, F = unit_mesh(name)
    lap = sig.laplacian(V, F)
    C = (lap.B + 1e-4 * lap.L).tocoo()
    t0 = time.process_time()
    for _ in range(3):
        CholeskySolverD(lap.n, C.row.astype(np.int32), C.col.astype(np.int32), C.data, MatrixType.COO)
    chol = (time.process_time() - t0) / 3
    f = V[:, 0] + 0.01 * np.random.default_rng(0).standard_normal(lap.n)
    t0 = time.process_time()
    optimal_time(lap, f)
    el = time.process_time() - t0
    print(f"{name} n={lap.n}: optimal_time {el:.2f} s CPU = {el / chol:.1f} Cholesky ({1e3 * chol:.0f} ms each)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--real", default=None)
    ap.add_argument("--cost", default=None)
    args = ap.parse_args(argv)
    if args.cost:
        return cost(args.cost)
    if args.real:
        return real(args.real.split(","))
    noises = (0.03, 0.1, 0.3, 1.0)
    seeds = (0,) if args.quick else (0, 1)
    total = {"risk": [], "lcurve": []}
    for name, lap, sigs in domains(args.quick):
        lam, X = sig.dense_eigs(lap)
        B = lap.B
        tally = {"risk": [], "lcurve": []}
        for sname, c in sigs.items():
            rms = np.sqrt(c @ (B @ c) / lap.area())
            for nl in noises:
                for sd in seeds:
                    f = c + nl * rms * np.random.default_rng(sd).standard_normal(lap.n)
                    a = X.T @ (B @ f)

                    def err(t):
                        u = X @ (np.exp(-lam * t) * a) - c
                        return np.sqrt(u @ (B @ u))

                    for rule in tally:
                        t, _ = optimal_time(lap, f, rule=rule)
                        ok = err(t) < err(t / 10) and err(t) < err(10 * t)
                        tally[rule].append(ok)
                        if not ok:
                            print(f"  fail {rule:6s} {name} {sname} noise {nl:g} seed {sd}: t={t:.2e} "
                                  f"e(t/10)/e(t)={err(t / 10) / err(t):.3f} e(10t)/e(t)={err(10 * t) / err(t):.3f}",
                                  flush=True)
        for rule, v in tally.items():
            total[rule] += v
            print(f"{name:26s} {rule:6s} {sum(v)}/{len(v)}", flush=True)
    for rule, v in total.items():
        print(f"all {rule:6s} {sum(v)}/{len(v)} ({100 * sum(v) / len(v):.0f}%)")


if __name__ == "__main__":
    main()
