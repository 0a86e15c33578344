"""Fig. 6: conditioning of the shifted systems (t L - z_i B) of the rational heat approximation.

The degree-7 rational (Carathéodory-Fejér / Padé-Chebyshev type) approximation of
e^(-ts) has complex poles z_i; each term needs one solve with t L - z_i B. Their 2-norm
condition numbers stay moderate at every t because the poles are away from the real
axis: kappa_2(t L - z B) <= kappa_2(B) * max|t lambda - z| / min|t lambda - z|.
"""
from __future__ import annotations

import numpy as np

import _common as C


def heat_poles(degree):
    """Poles of the package's rational approximation of e^(-x) on [0, inf)."""
    from spectral_igl.approx import _rational

    return np.asarray(_rational.cf_exp(degree)[2])


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import icosphere

    V, F = icosphere(2 if args.quick else 3)
    lap = sig.laplacian(V, F)
    L, B = lap.L.toarray(), lap.B.toarray()
    evals, _ = sig.dense_eigs(lap)
    kB = np.linalg.cond(B)
    poles = heat_poles(7)
    times = [1e-3, 1e-2, 1e-1, 1.0]
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    conds, holds = [], True
    for t in times:
        row = []
        for z in poles:
            kappa = np.linalg.cond(t * L - z * B)
            gaps = np.abs(t * evals - z)
            holds &= bool(kappa <= kB * gaps.max() / gaps.min() * (1 + 1e-8))
            row.append(kappa)
        conds.append(row)
        ax.semilogy(np.arange(1, len(poles) + 1), row, "o-", label=f"t={t:g}")
    ax.set_xlabel("index i of the pole z_i")
    ax.set_ylabel("condition number kappa_2(tL - z_i B)")
    ax.set_title(f"rational heat approximation, degree 7, n={lap.n}")
    ax.legend(fontsize=8)
    images = [C.savefig(fig, out / "fig06_conditioning.png")]
    result = {"n": lap.n, "kappa_B": float(kB), "max_condition": float(np.max(conds)),
              "bound_holds": holds, "images": images}
    return C.summary("fig06", result)


if __name__ == "__main__":
    main()
