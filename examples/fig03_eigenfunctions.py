"""Fig. 3: level sets and critical points of Laplacian eigenfunctions (linear FEM weights).

The k-th eigenfunction oscillates more as k grows: more level sets and more critical
points. On a closed surface the critical points obey the Euler relation
#minima - #saddles + #maxima = 2 - 2g (the survey's m - s + M). The piecewise-linear
test also finds spurious minimum-saddle and saddle-maximum pairs where the function is
nearly flat; those of persistence below 2% of the range are cancelled in pairs (which
keeps m - s + M) before counting and drawing. Signed functions: a diverging colour map
centred at 0.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig

    V, F, name = C.surface(args)
    lap = sig.laplacian(V, F)
    which = [1, 4, 9, 19] if args.quick else [1, 4, 9, 19, 39]
    evals, X = sig.eigs(lap, max(which) + 1)
    counts, euler, raw = [], [], []
    shapes, fs, labels, crit = [], [], [], []
    for k in which:
        f = X[:, k]
        cp = C.persistent_critical_points(V, F, f, fraction=0.02)
        m, M, s = cp["n_minima"], cp["n_maxima"], cp["n_saddles"]
        counts.append((m, M, s))
        raw.append(cp["raw"])
        euler.append(m - s + M)
        shapes.append((V, F)); fs.append(f); crit.append(cp)
        labels.append(f"x_{k + 1}: m={m} M={M} s={s}")
    images = []
    for k, f, cp, label in zip(which, fs, crit, labels):
        path = out / f"fig03_eigenfunction_{k + 1:02d}.png"
        images.append(C.render(path, (V, F), f, kind="diverging", critical={k: cp[k] for k in ("minimum", "maximum", "saddle")},
                               sources=None, title=label,
                               window_size=(500, 500)))
    result = {"n": lap.n, "eigenvalues": evals[which].tolist(), "critical_counts": counts,
              "raw_critical_counts": raw,
              "euler_characteristic": euler, "images": images}
    return C.summary("fig03", result)


if __name__ == "__main__":
    main()
