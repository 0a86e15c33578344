"""Fig. 10: the filters phi applied to the Laplacian eigenvalues (log-log axes).

Heat e^(-ts) at several t, commute time s^(-1/2), biharmonic s^(-1), poly-harmonic
s^(-k/2), and Mexican hat t s e^(-ts), each sampled at
the eigenvalues of the shape. On the unit sphere the eigenvalues are l(l+1).
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from spectral_igl import filters

    if args.mesh:
        V, F, name = C.surface(args)
    else:
        from data_generators import icosphere

        V, F = icosphere(3 if args.quick else 4)
        name = "unit sphere"
    lap = sig.laplacian(V, F)
    k = 60 if args.quick else 200
    evals, _ = sig.eigs(lap, k)
    s = evals[1:]  # the positive eigenvalues
    curves = [(f"heat t={t:g}", filters.heat(t)) for t in (1e-3, 1e-2, 1e-1)]
    curves += [("commute time", filters.commute_time()), ("biharmonic", filters.biharmonic()),
               ("poly-harmonic k=3", filters.polyharmonic(3)),
               ("Mexican hat t=0.05", filters.mexican_hat(0.05))]
    plt = C.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for lab, filt in curves:
        y = np.abs(np.asarray(filt(s)))
        axes[0].loglog(s, y, ".-", ms=3, lw=1, label=lab)
        y2 = np.abs(np.asarray(filt.square(s)))
        axes[1].loglog(s, y2, ".-", ms=3, lw=1, label=lab)
    axes[0].set_title("kernel filter phi(lambda)")
    axes[1].set_title("distance filter phi^2(lambda)")
    for ax in axes:
        ax.set_xlabel("Laplacian eigenvalue lambda")
        ax.grid(True, which="both", lw=0.3)
    axes[0].legend(fontsize=7)
    images = [C.savefig(fig, out / "fig10_filters.png")]
    # key numbers: the filters are the functions they claim to be, at the eigenvalues
    heat_err = float(np.max(np.abs(filters.heat(0.01)(s) - np.exp(-0.01 * s))))
    bih_err = float(np.max(np.abs(filters.biharmonic()(s) * s - 1.0)))
    result = {"n": lap.n, "lambda_2": float(s[0]), "heat_filter_error": heat_err,
              "biharmonic_filter_error": bih_err, "images": images}
    return C.summary("fig10", result)


if __name__ == "__main__":
    main()
