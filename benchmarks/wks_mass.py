"""Cost of the spectrum-free WKS with the full mass matrix, against the lumped one.

For each mesh and mass, one ``wks(lap, energies, method="auto", return_info=True)`` call on a
fresh Laplacian (wall seconds; the energy grid is computed before the clock starts): either
one energy in the middle of the band of the first 100 eigenvalues (``--energies 1``) or the
default grid of ``wks_energies`` (100 energies, common poles). Printed with each result: its
``bound_kind`` and the largest ``abs_error`` relative to the largest signature value.

    OPENBLAS_NUM_THREADS=1 python benchmarks/wks_mass.py --energies default ../shared/data/meshes/cow.obj
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import spectral_igl as sig
from spectral_igl.data_generators import icosphere
from spectral_igl.io import read_mesh


def one_call(V, F, mass, energies):
    """(seconds, bound_kind, largest relative bound) of one wks call."""
    lap = sig.laplacian(V, F, mass=mass)
    if energies == "default":
        E, sigma = sig.wks_energies(lap)
    else:
        lo, hi, _ = sig.spectral_band(lap, 100)
        E = np.linspace(np.log(lo), np.log(hi), int(energies) + 4)[2:-2]
        sigma = 7.0 * (E[1] - E[0]) if E.size > 1 else 0.5
    t0 = time.perf_counter()
    W, info = sig.wks(lap, E, sigma=sigma, method="auto", return_info=True)
    seconds = time.perf_counter() - t0
    return seconds, info["bound_kind"], float(np.max(info["abs_error"] / np.abs(W).max(axis=0)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--energies", default="1", help="'default' (the 100-energy grid) or a count")
    args = ap.parse_args()
    sig.wks(sig.laplacian(*icosphere(2), mass="full"), [2.0, 3.0], sigma=0.5, method="auto")  # warm-up
    print("| mesh | n | energies | lumped s | full s | full / lumped | kind (lumped, full) | max bound / max value (lumped, full) |")
    print("|---|---|---|---|---|---|---|---|")
    for path in args.meshes:
        V, F = read_mesh(path)[:2]
        (tl, kl, el), (tf, kf, ef) = (one_call(V, F, m, args.energies) for m in ("lumped", "full"))
        print(f"| {path.split('/')[-1]} | {len(V)} | {args.energies} | {tl:.2f} | {tf:.2f} | {tf / tl:.2f} | "
              f"{kl}, {kf} | {el:.1e}, {ef:.1e} |", flush=True)


if __name__ == "__main__":
    main()
