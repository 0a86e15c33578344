"""Figs. 24-26: smoothing noisy scalar functions and shapes.

A smooth function plus noise has hundreds of spurious critical points; diffusion
smoothing f_t = e^(-t L~) f (spectrum-free) removes them and brings f back towards the
clean function. The same on the vertex coordinates smooths a noisy shape.
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
    clean = np.sin(4 * c[:, 0]) + np.cos(3 * c[:, 1]) * c[:, 2] * 3
    rng = np.random.default_rng(7)
    noisy = clean + 0.1 * np.ptp(clean) * rng.standard_normal(lap.n)
    h = float(np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)))
    t = 4 * h ** 2
    smoothed = np.asarray(sig.diffusion_smooth(lap, noisy, t))
    cp0, cp1 = critical_points(V, F, noisy), critical_points(V, F, smoothed)
    n0 = cp0.n_minima + cp0.n_maxima + cp0.n_saddles
    n1 = cp1.n_minima + cp1.n_maxima + cp1.n_saddles
    images = [C.render(out / "fig24_smoothing.png", [(V, F), (V, F), (V, F)],
                       [clean, noisy, smoothed], kind="diverging", n_levels=[12, 0, 12],
                       critical=None, labels=["clean", f"noisy: {n0} critical points",
                                              f"smoothed: {n1} critical points"],
                       window_size=(1500, 500))]
    # Fig. 26: smoothing a noisy shape (the coordinates)
    Vn = C.add_noise(V, F, 0.5, seed=3)
    Vs = np.asarray(sig.diffusion_smooth(sig.laplacian(Vn, F), Vn, t))
    dev = [np.linalg.norm(W - V, axis=1) for W in (Vn, Vs)]
    images.append(C.render(out / "fig26_shape_smoothing.png", [(Vn, F), (Vs, F)], dev,
                           kind="distance", labels=["noisy shape", "smoothed"], n_levels=[0, 12],
                           window_size=(1000, 500)))
    err = lambda g: float(np.max(np.abs(g - clean)) / np.ptp(clean))  # noqa: E731
    result = {"n": lap.n, "t": t, "critical_before": n0, "critical_after": n1,
              "error_noisy": err(noisy), "error_smoothed": err(smoothed),
              "shape_error_noisy": float(dev[0].max()), "shape_error_smoothed": float(dev[1].max()),
              "images": images}
    return C.summary("fig24_26", result)


if __name__ == "__main__":
    main()
