"""Fig. 8: volumetric heat kernel on a tetrahedral mesh.

The heat kernel K_t(:, i) of the linear-FEM tetrahedral Laplacian, shown on the boundary
with a cut-away quarter; iso-values are uniformly sampled in its range on the boundary.
Heat is conserved (1^T B K_t(:, i) = 1) and the kernel is symmetric.
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from data_generators import box_tets

    V = T = None
    if args.mesh:
        from spectral_igl.io import read_mesh

        V, T = read_mesh(args.mesh)
        if T.shape[1] != 4:  # a surface: the other figures use it, this one the generated box
            print(f"fig08: {args.mesh} is not a tetrahedral mesh; drawing the generated box")
            V = T = None
    if V is None:
        V, T = box_tets((10, 8, 6) if args.quick else (24, 18, 12))
    lap = sig.laplacian(V, T)
    i = int(np.argmin(np.linalg.norm(V - (V.min(0) + 0.3 * (V.max(0) - V.min(0))), axis=1)))
    j = int(np.argmin(np.linalg.norm(V - (V.min(0) + 0.7 * (V.max(0) - V.min(0))), axis=1)))
    diam2 = float(np.sum((V.max(0) - V.min(0)) ** 2))
    t = 0.01 * diam2
    K = sig.heat_kernel(lap, t, [i, j])
    mass = lap.B @ np.ones(lap.n)
    conservation = float(np.max(np.abs(K.T @ mass - 1.0)))
    symmetry = float(abs(K[j, 0] - K[i, 1]) / max(abs(K[j, 0]), 1e-300))
    images = [C.render(out / "fig08_volumetric_heat_kernel.png", (V, T), K[:, 0], kind="sequential",
                       sources=[i], volume="clip", title=f"volumetric heat kernel, t={t:.3g}"),
              C.render(out / "fig08_volumetric_heat_slices.png", (V, T), K[:, 0], kind="sequential",
                       sources=[i], volume="slices", title="slices")]
    result = {"n": lap.n, "t": t, "conservation_error": conservation,
              "symmetry_error": symmetry, "min": float(K[:, 0].min()), "images": images}
    return C.summary("fig08", result)


if __name__ == "__main__":
    main()
