"""Diffusion-time selection: does the chosen t beat t/10 and 10 t on the error to the clean signal?

Usage::

    python benchmarks/optimal_time.py [--quick]

Smooth signals plus per-vertex white noise (3% to 100% of the signal's RMS) on icosphere(3),
icosphere(4) and a 9x9x9 tetrahedral box, full and lumped mass, two noise seeds. For each
rule of :func:`spectral_igl.optimal_time` (``"risk"``, ``"lcurve"``) prints the fraction of
cases where the error to the clean signal at the chosen t is smaller than at t/10 and at
10 t, and the failures. Errors are measured with a dense eigendecomposition.
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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
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
