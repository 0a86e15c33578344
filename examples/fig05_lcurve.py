"""Fig. 5: the L-curve and volumetric diffusion smoothing at the selected scale.

A smooth function on a tetrahedral box plus noise is smoothed by e^(-t L~) f for a range
of t. The L-curve plots the residual ||f_t - f||_B against the roughness
(f_t^T L f_t)^(1/2). Two time selections are marked on it: its corner (the survey's rule,
``optimal_time(rule="lcurve")``) and the minimum of the estimated risk (the default,
``optimal_time(rule="risk")``), which is the one used for smoothing; the right panel shows
the error to the clean function along the curve.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import box_tets

    V, T = box_tets((8, 6, 4) if args.quick else (20, 15, 10))
    lap = sig.laplacian(V, T)
    c = V - V.mean(0)
    clean = np.cos(4 * c[:, 0]) * np.sin(5 * c[:, 1] + 1) + 2 * c[:, 2]
    rng = np.random.default_rng(3)
    noisy = clean + 0.15 * np.ptp(clean) * rng.standard_normal(lap.n)
    # the L-curve of the package: residual and energy at each tried time, its corner t_opt
    t_opt, curve = sig.optimal_time(lap, noisy, n_times=10 if args.quick else 32)
    t_corner = sig.optimal_time(lap, noisy, ts=curve["t"], rule="lcurve")[0]
    smoothed = np.asarray(sig.diffusion_smooth(lap, noisy, t_opt))
    err = lambda f: float(np.sqrt((f - clean) @ (lap.B @ (f - clean))))  # noqa: E731
    ts = np.asarray(curve["t"])
    # the error against the clean function along the curve (what t_opt should nearly minimise)
    errors = np.array([err(np.asarray(sig.diffusion_smooth(lap, noisy, t))) for t in ts])
    plt = C.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
    ax = axes[0]
    ax.loglog(curve["residual"], curve["energy"], "o-", ms=3)
    for t, x, y in list(zip(ts, curve["residual"], curve["energy"]))[::3]:
        ax.annotate(f"{t:.0e}", (x, y), fontsize=7)
    k = int(np.argmin(np.abs(np.log(ts / t_opt))))
    ax.loglog([curve["residual"][k]], [curve["energy"][k]], "r*", ms=14, label=f"risk minimum: t = {t_opt:.2e}")
    kc = int(np.argmin(np.abs(np.log(ts / t_corner))))
    ax.loglog([curve["residual"][kc]], [curve["energy"][kc]], "bs", ms=8, mfc="none",
              label=f"L-curve corner: t = {t_corner:.2e}")
    ax.set_xlabel("residual ||f_t - f||_B")
    ax.set_ylabel("energy")
    ax.set_title("L-curve of heat smoothing")
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.loglog(ts, errors, "o-", ms=3, color="tab:green")
    ax.axvline(t_opt, color="r", lw=1, label="risk minimum")
    ax.axvline(t_corner, color="b", lw=1, ls=":", label="L-curve corner")
    ax.axhline(err(noisy), color="gray", ls="--", lw=1, label="noisy input")
    ax.set_xlabel("diffusion time t")
    ax.set_ylabel("error ||f_t - clean||_B")
    ax.set_title("error against the clean function")
    ax.legend(fontsize=8)
    fig.tight_layout()
    images = [C.savefig(fig, out / "fig05_lcurve.png"),
              C.render(out / "fig05_volumetric_smoothing.png", [(V, T), (V, T)], [noisy, smoothed],
                       kind="auto", volume="clip", n_levels=[0, 12],
                       labels=["noisy", f"smoothed, t={t_opt:.2e} (risk)"],
                       window_size=(1000, 500))]
    result = {"n": lap.n, "t_opt": float(t_opt), "t_lcurve_corner": float(t_corner),
              "error_at_corner": err(np.asarray(sig.diffusion_smooth(lap, noisy, t_corner))), "error_noisy": err(noisy),
              "error_smoothed": err(smoothed), "error_best_on_curve": float(errors.min()),
              "t_best_on_curve": float(ts[np.argmin(errors)]), "images": images}
    return C.summary("fig05", result)


if __name__ == "__main__":
    main()
