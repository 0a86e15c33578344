"""Fig. 4: anisotropic heat kernel centred at a seed point.

With an anisotropic Laplacian (diffusion faster along one direction of the surface) the
heat kernel spreads into an elongated spot; the isotropic one is round. Elongation is
the ratio of the principal second moments of the kernel around the seed.
"""
from __future__ import annotations

import numpy as np

import _common as C


def elongation(V, k, i):
    w = np.maximum(k, 0)
    w = w / w.sum()
    X = V - V[i]
    M = (X * w[:, None]).T @ X
    ev = np.sort(np.linalg.eigvalsh(M))[::-1]
    return float(np.sqrt(ev[0] / ev[1]))


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig

    if args.mesh:
        V, F, name = C.surface(args)
    else:
        from data_generators import icosphere

        V, F = icosphere(3 if args.quick else 4)
    i = int(np.argmax(V[:, 2]))
    t = 0.01
    iso = sig.laplacian(V, F)
    aniso = sig.anisotropic_laplacian(V, F, direction=np.array([1.0, 0.0, 0.0]), ratio=8.0)
    k0, k1 = sig.heat_kernel(iso, t, i), sig.heat_kernel(aniso, t, i)
    images = [C.render(out / "fig04_anisotropic_heat.png", [(V, F), (V, F)], [k0, k1],
                       kind="cyclic", sources=[i], labels=["isotropic", "anisotropic"],
                       shared_scale=False, window_size=(1000, 500), zoom=1.3)]
    result = {"n": len(V), "elongation_isotropic": elongation(V, k0, i),
              "elongation_anisotropic": elongation(V, k1, i), "images": images}
    return C.summary("fig04", result)


if __name__ == "__main__":
    main()
