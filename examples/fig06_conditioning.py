"""Fig. 6: conditioning of the shifted systems (t L - z_i B) of the rational heat approximation.

The rational (Carathéodory-Fejér / Padé-Chebyshev type) approximation of
e^(-ts) has complex poles z_i; each term needs one solve with t L - z_i B. Their 2-norm
condition numbers stay moderate at every t because the poles are away from the real
axis: kappa_2(t L - z B) <= kappa_2(B) * max|t lambda - z| / min|t lambda - z|.
"""
from __future__ import annotations

import numpy as np

import _common as C


def heat_poles(lap, t, tol=1e-8):
    """``(sigma, poles)`` of the systems sigma L - z_i B that the engine solves for e^(-t s).

    Read from the plan of a :class:`spectral_igl.SpectralOperator` with the rational
    method, after one application (the degree is chosen for ``tol``).
    """
    import spectral_igl as sig

    op = sig.SpectralOperator(lap, sig.filters.heat(t), method="rational", tol=tol)
    op.apply(np.ones(lap.n))
    pf = op.plan.pf
    return float(pf.sigma), np.asarray(pf.poles)


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import icosphere

    V, F = icosphere(1 if args.quick else 2)
    lap = sig.laplacian(V, F)
    L, B = lap.L.toarray(), lap.B.toarray()
    evals, _ = sig.dense_eigs(lap)
    kB = np.linalg.cond(B)
    times = [1e-3, 1e-2, 1e-1, 1.0]
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    conds, holds = [], True
    degrees = []
    for t in times:
        row = []
        sigma, poles = heat_poles(lap, t)
        degrees.append(len(poles))
        for z in poles:
            kappa = np.linalg.cond(sigma * L - z * B)
            gaps = np.abs(sigma * evals - z)
            holds &= bool(kappa <= kB * gaps.max() / gaps.min() * (1 + 1e-8))
            row.append(kappa)
        conds.append(row)
        ax.semilogy(np.arange(1, len(poles) + 1), row, "o-", label=f"t={t:g}")
    ax.set_xlabel("index i of the pole z_i")
    ax.set_ylabel("condition number kappa_2(tL - z_i B)")
    ax.set_title(f"rational heat approximation (degree {max(degrees)}), n={lap.n}")
    ax.legend(fontsize=8)
    images = [C.savefig(fig, out / "fig06_conditioning.png")]
    result = {"n": lap.n, "degree": max(degrees), "kappa_B": float(kB), "max_condition": float(np.max(conds)),
              "bound_holds": holds, "images": images}
    return C.summary("fig06", result)


if __name__ == "__main__":
    main()
