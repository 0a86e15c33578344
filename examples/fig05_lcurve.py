"""Fig. 5: the L-curve and volumetric diffusion smoothing at the optimal scale.

A smooth function on a tetrahedral box plus noise is smoothed by e^(-t L~) f for a range
of t. The L-curve plots the residual ||f_t - f||_B against the roughness
(f_t^T L f_t)^(1/2); its corner gives t_opt (``optimal_time``), where the smoothed
function is closest to the clean one.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import box_tets

    V, T = box_tets((10, 8, 6) if args.quick else (20, 15, 10))
    lap = sig.laplacian(V, T)
    c = V - V.mean(0)
    clean = np.cos(4 * c[:, 0]) * np.sin(5 * c[:, 1] + 1) + 2 * c[:, 2]
    rng = np.random.default_rng(3)
    noisy = clean + 0.15 * np.ptp(clean) * rng.standard_normal(lap.n)
    times = np.logspace(-5, -1, 9 if args.quick else 17)
    residual, roughness = [], []
    for t in times:
        g = np.asarray(sig.diffusion_smooth(lap, noisy, t))
        r = g - noisy
        residual.append(float(np.sqrt(r @ (lap.B @ r))))
        roughness.append(float(np.sqrt(max(g @ (lap.L @ g), 0.0))))
    t_opt = sig.optimal_time(lap, noisy)
    t_opt = float(t_opt[0] if isinstance(t_opt, tuple) else t_opt)
    smoothed = np.asarray(sig.diffusion_smooth(lap, noisy, t_opt))
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.loglog(residual, roughness, "o-")
    for t, x, y in zip(times[::2], residual[::2], roughness[::2]):
        ax.annotate(f"{t:.0e}", (x, y), fontsize=7)
    g = smoothed - noisy
    ax.loglog([np.sqrt(g @ (lap.B @ g))], [np.sqrt(max(smoothed @ (lap.L @ smoothed), 0))], "r*",
              ms=14, label=f"t_opt = {t_opt:.2e}")
    ax.set_xlabel("residual ||f_t - f||_B")
    ax.set_ylabel("roughness (f_t^T L f_t)^1/2")
    ax.legend()
    images = [C.savefig(fig, out / "fig05_lcurve.png"),
              C.render(out / "fig05_volumetric_smoothing.png", [(V, T), (V, T)], [noisy, smoothed],
                       kind="cyclic", volume="clip", labels=["noisy", f"smoothed, t={t_opt:.2e}"],
                       window_size=(1000, 500))]
    err = lambda f: float(np.sqrt((f - clean) @ (lap.B @ (f - clean))))  # noqa: E731
    result = {"n": lap.n, "t_opt": t_opt, "error_noisy": err(noisy), "error_smoothed": err(smoothed),
              "images": images}
    return C.summary("fig05", result)


if __name__ == "__main__":
    main()
