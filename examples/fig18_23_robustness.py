"""Figs. 18-23: robustness of the spectrum-free heat kernel and diffusion distance.

The same source, with (a) a different sampling of the surface, (b) noise on the
vertices, (c) a point set sampled from the surface with holes (drawn as spheres), and
(d) a topological cut. Differences are measured after normalising each distance by its
maximum, at the points common to both shapes (nearest vertices).
"""
from __future__ import annotations

import numpy as np

import _common as C


def nearest(P, Q):
    """Index of the point of ``Q`` nearest to each point of ``P``."""
    from scipy.spatial import cKDTree

    return cKDTree(Q).query(P)[1]


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig

    if args.mesh:
        V, F, name = C.surface(args, level_quick=2)
        V2, F2 = V, F
    else:
        lev = 2 if args.quick else 3
        V, F = C.blob(lev)
        V2, F2 = C.blob(lev + 1)
        s = np.sqrt(sum(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)) / 2)
        V, V2 = V / s, V2 / s
    i = C.extreme_vertex(V, 0)
    t = 0.02
    base = C.diffusion_distance(sig.laplacian(V, F), t, i)
    base = base / base.max()
    # (a) sampling
    j = nearest(V[i][None], V2)[0]
    d2 = C.diffusion_distance(sig.laplacian(V2, F2), t, j)
    d2 = d2 / d2.max()
    sampling = float(np.max(np.abs(d2[nearest(V, V2)] - base)))
    # (b) noise
    Vn = C.add_noise(V, F, 0.4)
    dn = C.diffusion_distance(sig.laplacian(Vn, F), t, i)
    dn = dn / dn.max()
    noise = float(np.max(np.abs(dn - base)))
    # heat kernel on the noisy surface, same source
    kn = sig.heat_kernel(sig.laplacian(Vn, F), t / 4, i)
    # (c) point set with holes
    rng = np.random.default_rng(1)
    P = V2[rng.permutation(len(V2))[: len(V2) // 2]]
    P = np.vstack([V[i][None], P])
    holes = [C.far_vertex(V, i), C.extreme_vertex(V, 2)]
    keep = np.all([np.linalg.norm(P - V[h], axis=1) > 0.12 for h in holes], axis=0)
    keep[0] = True
    P = P[keep]
    lap_p = sig.point_cloud_laplacian(P)
    dp = C.diffusion_distance(lap_p, t, 0)
    dp = dp / dp.max()
    points = float(np.max(np.abs(dp - base[nearest(P, V)])))
    # (d) topological cut: a thin slit of removed faces next to the source
    centre = C.far_vertex(V, i)
    Vc, Fc, index = C.cut_holes(V, F, [centre], 0.05)
    dc = C.diffusion_distance(sig.laplacian(Vc, Fc), t, int(index[i]))
    dc = dc / dc.max()
    cut = float(np.max(np.abs(dc - base[index >= 0])))
    images = [C.render(out / "fig18_23_robustness.png",
                       [(V, F), (V2, F2), (Vn, F), P, (Vc, Fc)], [base, d2, dn, dp, dc],
                       kind="distance", sources=[[i], [j], [i], [0], [int(index[i])]],
                       labels=["input", "resampled", "noise", "point set, holes", "cut"],
                       window_size=(1800, 380)),
              C.render(out / "fig20_heat_kernel_noisy.png", (Vn, F), kn, kind="sequential",
                       sources=[i], title=f"heat kernel, noisy surface, t={t / 4:g}",
                       window_size=(500, 500))]
    result = {"n": len(V), "sampling_difference": sampling, "noise_difference": noise,
              "point_set_difference": points, "cut_difference": cut, "images": images}
    return C.summary("fig18_23", result)


if __name__ == "__main__":
    main()
