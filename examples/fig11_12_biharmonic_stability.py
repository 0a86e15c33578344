"""Figs. 11-12: the biharmonic distance across resolution, Laplacian weights, noise and holes.

On the unit sphere the biharmonic distance has a closed form (a Legendre series); the
spectrum-free distance converges to it as the mesh is refined. On a generated shape the
level sets from one source barely change with the weights, with noise and with holes.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import icosphere

    # convergence on the sphere against the analytic distance
    levels = [1, 2, 3] if args.quick else [2, 3, 4, 5]
    errors, ns = [], []
    for lev in levels:
        V, F = icosphere(lev)
        lap = sig.laplacian(V, F)
        d = C.biharmonic_distance(lap, 0)
        theta = np.arccos(np.clip(V @ V[0] / np.linalg.norm(V, axis=1) / np.linalg.norm(V[0]), -1, 1))
        truth = C.sphere_biharmonic_distance(theta, lmax=1000 if args.quick else 4000)
        errors.append(float(np.max(np.abs(d - truth)) / truth.max()))
        ns.append(lap.n)
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.loglog(ns, errors, "o-")
    ax.set_xlabel("number of vertices n")
    ax.set_ylabel("relative l-inf error")
    ax.set_title("biharmonic distance on the unit sphere vs analytic")
    ax.grid(True, which="both", lw=0.3)
    images = [C.savefig(fig, out / "fig11_sphere_convergence.png")]

    # stability on a generated shape (or --mesh)
    V, F, name = C.surface(args, level_quick=2)
    i = C.extreme_vertex(V, 0)
    panels, fs, labels = [], [], []
    for weights in ("cotan", "intrinsic_delaunay"):
        lap = sig.laplacian(V, F, weights=weights)
        panels.append((V, F)); fs.append(C.biharmonic_distance(lap, i)); labels.append(weights)
    Vn = C.add_noise(V, F, 0.3)
    panels.append((Vn, F)); fs.append(C.biharmonic_distance(sig.laplacian(Vn, F), i))
    labels.append("noise")
    holes = [C.far_vertex(V, i), C.extreme_vertex(V, 2)]
    Vh, Fh, index = C.cut_holes(V, F, holes, 0.08)
    dh = C.biharmonic_distance(sig.laplacian(Vh, Fh), int(index[i]))
    panels.append((Vh, Fh)); fs.append(dh); labels.append("holes")
    images.append(C.render(out / "fig12_biharmonic_stability.png", panels, fs, kind="distance",
                           sources=[[i], [i], [i], [int(index[i])]], labels=labels, shared_scale=True,
                           window_size=(1600, 420)))
    ref = fs[0] / fs[0].max()
    kept = index >= 0
    result = {"n": ns, "sphere_relative_error": errors,
              "weights_difference": float(np.max(np.abs(fs[1] / fs[1].max() - ref))),
              "noise_difference": float(np.max(np.abs(fs[2] / fs[2].max() - ref))),
              "holes_difference": float(np.max(np.abs(dh / dh.max() - ref[kept]))),
              "images": images}
    return C.summary("fig11_12", result)


if __name__ == "__main__":
    main()
