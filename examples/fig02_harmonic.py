"""Fig. 2: level sets and critical points of harmonic functions with 2, 4 and 6 constraints.

Dirichlet values alternate between 0 and 1 at well-spread vertices; the harmonic
interpolant (L f = 0 elsewhere) has its extrema only at the constraints (discrete maximum
principle with non-negative weights) and saddles in between, with
#minima - #saddles + #maxima = 2 on a closed genus-0 surface.
"""
from __future__ import annotations

import numpy as np

import _common as C


def spread(V, count, first=0):
    """``count`` well-spread vertices (farthest-point sampling in space)."""
    chosen = [first]
    d = np.linalg.norm(V - V[first], axis=1)
    while len(chosen) < count:
        j = int(np.argmax(d))
        chosen.append(j)
        d = np.minimum(d, np.linalg.norm(V - V[j], axis=1))
    return np.array(chosen)


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from spectral_igl import critical_points, harmonic

    V, F, name = C.surface(args)
    lap = sig.laplacian(V, F, weights="intrinsic_delaunay")
    images, counts, euler, extrema_at_constraints = [], [], [], []
    for count in (2, 4, 6):
        fixed = spread(V, count, C.extreme_vertex(V, 0))
        values = (np.arange(count) % 2).astype(float)
        f = np.asarray(harmonic(lap, fixed, values))
        cp = critical_points(V, F, f)
        m, M, s = cp.n_minima, cp.n_maxima, cp.n_saddles
        counts.append((m, M, s))
        euler.append(m - s + M)
        extrema = set(np.asarray(cp.minima).tolist()) | set(np.asarray(cp.maxima).tolist())
        extrema_at_constraints.append(extrema <= set(fixed.tolist()))
        images.append(C.render(out / f"fig02_harmonic_{count}.png", (V, F), f, kind="sequential",
                               critical=cp, title=f"{count} constraints: m={m} M={M} s={s}",
                               window_size=(500, 500)))
    result = {"n": lap.n, "critical_counts": counts, "euler_characteristic": euler,
              "extrema_only_at_constraints": all(extrema_at_constraints), "images": images}
    return C.summary("fig02", result)


if __name__ == "__main__":
    main()
