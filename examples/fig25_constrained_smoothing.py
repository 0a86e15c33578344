"""Fig. 25: smoothing with interpolating constraints (Patane et al. 2007).

A smooth function plus noise has many spurious critical points. The main features are
the extrema of the function after diffusion smoothing at the selected scale
(``optimal_time``); keeping the input's values there and minimising ||L f~|| elsewhere
(``smooth_constrained`` with a fidelity weight 1/t^2 matched to that scale) removes the
spurious critical points while the preserved maxima and minima stay where they were.
The first image shows the level sets and critical points of the input, the second those
of the smoothed function, with the constrained vertices as black dots.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from spectral_igl import critical_points

    V, F, name = C.surface(args)
    lap = sig.laplacian(V, F)
    c = V - V.mean(0)
    clean = np.sin(12 * c[:, 0]) + np.cos(10 * c[:, 1]) * np.sin(8 * c[:, 2])  # 4 minima, 4 maxima
    rng = np.random.default_rng(5)
    f = clean + 0.03 * np.ptp(clean) * rng.standard_normal(lap.n)
    # the features: extrema that survive diffusion smoothing at the selected scale
    t, _ = sig.optimal_time(lap, f)
    feat = critical_points(V, F, np.asarray(sig.diffusion_smooth(lap, f, t)))
    fixed = np.union1d(feat.minima, feat.maxima)
    # fidelity weight matched to the diffusion scale: eps/(lambda^2 + eps) halves at 1/t
    eps = 1.0 / t ** 2
    g = np.asarray(sig.smooth_constrained(lap, f, fixed, eps=eps))
    cp0, cp1 = critical_points(V, F, f), critical_points(V, F, g)
    count = lambda cp: int(cp.n_minima + cp.n_maxima + cp.n_saddles)  # noqa: E731
    span = float(np.ptp(f))
    images = [
        C.render(out / "fig25_input.png", (V, F), f, kind="auto", critical=cp0, sources=fixed,
                 title=f"input: {count(cp0)} critical points", zoom=1.3),
        C.render(out / "fig25_constrained_smoothing.png", (V, F), g, kind="auto", critical=cp1,
                 sources=fixed, title=f"smoothed, {fixed.size} constraints: {count(cp1)} critical points",
                 zoom=1.3),
    ]
    result = {"n": lap.n, "t": float(t), "eps": float(eps), "constraints": int(fixed.size),
              "critical_before": count(cp0), "critical_after": count(cp1),
              "extrema_after": int(cp1.n_minima + cp1.n_maxima),
              "constraint_error": float(np.max(np.abs(g[fixed] - f[fixed]))),
              # extrema of the result that are not constrained vertices
              "free_extrema": int(np.setdiff1d(np.union1d(cp1.minima, cp1.maxima), fixed).size),
              "linf_error_input": float(np.max(np.abs(g - f)) / span),
              "linf_error_clean": float(np.max(np.abs(g - clean)) / span),
              "images": images}
    return C.summary("fig25", result)


if __name__ == "__main__":
    main()
