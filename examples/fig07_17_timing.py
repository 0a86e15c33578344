"""Figs. 7 and 17: time versus n -- k eigenpairs against the spectrum-free evaluation.

For spheres of growing resolution, the time to compute k = 100 (and 500) eigenpairs with
shift-invert Lanczos (then one heat-kernel column from them) is compared with one
spectrum-free evaluation as "auto" chooses it (here shift-invert Lanczos on
(I + gamma L~)^-1: one Cholesky factorization and a few dozen solves), factorization
included. The spectrum-free rational column is checked against the dense ground truth on
the smallest shape. The picture shows the heat kernel from the source on the largest shape.
With ``--mesh``, the mesh (scaled to unit area) is the largest shape, after two spheres,
and only k = 100 is timed.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import icosphere

    levels = [2, 3] if args.quick else [3, 4, 5, 6]
    ks = [50] if args.quick else [100, 500]
    shapes = [icosphere(lev) for lev in levels]
    if args.mesh:  # the given mesh (unit area) is the largest shape, after two spheres
        V, F, _ = C.surface(args)
        shapes = shapes[:2] + [(V, F)]
        ks = ks[:1]
    t = 1e-2
    ns, t_sf, t_eig = [], [], {k: [] for k in ks}
    for V, F in shapes:
        lap = sig.laplacian(V, F)
        ns.append(lap.n)
        with C.Timer() as tm:
            sig.heat_kernel(lap, t, 0)  # what "auto" picks: shift-invert Lanczos here
        t_sf.append(tm.seconds)
        for k in ks:
            if k >= lap.n // 2 or k * lap.n > 6_000_000:  # (k=500 at n=40962: ~7 minutes)
                t_eig[k].append(np.nan)
                continue
            with C.Timer() as tm:
                evals, X = sig.eigs(lap, k)
                C.kernel_from_eigs(evals, X, lambda s: np.exp(-t * s), 0)
            t_eig[k].append(tm.seconds)
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(ns, t_sf, "o-", color="tab:orange", label="spectrum-free (auto)")
    for k in ks:
        ax.loglog(ns, t_eig[k], "s--", label=f"eigsh, k={k}")
    ax.set_xlabel("number of vertices n")
    ax.set_ylabel("seconds")
    ax.set_title(f"heat kernel column, t={t:g}")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", lw=0.3)
    images = [C.savefig(fig, out / "fig07_17_time_vs_n.png")]
    k0 = sig.heat_kernel(lap, t, 0)
    images.append(C.render(out / "fig07_heat_kernel.png", (V, F), k0, kind="sequential",
                           sources=[0], title=f"heat kernel, t={t:g}, n={lap.n}"))
    # the spectrum-free column is the exact one of the discrete operator: compare on the
    # smallest shape with the dense eigendecomposition
    lap0 = sig.laplacian(*icosphere(levels[0]))
    evals, X = sig.dense_eigs(lap0)
    exact = C.kernel_from_eigs(evals, X, lambda s: np.exp(-t * s), 0)
    sf_error = float(np.max(np.abs(sig.heat_kernel(lap0, t, 0, method="rational") - exact)) / exact.max())
    k = ks[0]
    result = {"relative_error_vs_dense": sf_error, "n": ns, "seconds_spectrum_free": t_sf, f"seconds_eigs_{k}": t_eig[k],
              "largest_n": ns[-1], "speedup_at_largest_n": t_eig[k][-1] / t_sf[-1],
              "images": images}
    return C.summary("fig07_17", result)


if __name__ == "__main__":
    main()
