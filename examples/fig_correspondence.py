"""Shape correspondence: a colouring carried from one shape to a remeshed, stretched copy.

The target is the source split irregularly (a random 1-to-3 split of half the triangles),
stretched by (1.15, 1, 0.9), rotated and with its vertices scrambled. ``sig.match_shapes``
finds the point map (spectrum-free WKS on each shape's own grid and the heat kernels of three
matched landmarks, a functional map with Laplacian and descriptor commutativity, ZoomOut);
the first picture shows a colouring of the
source (the geodesic distance from one vertex) and its transfer to the target side by side,
the second the geodesic error of every target vertex (on the source, over sqrt(area)).
"""
from __future__ import annotations

import numpy as np

import _common as C


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from scipy.spatial import cKDTree
    from spectral_igl.data_generators import resample

    V, F, name = C.surface(args, level_quick=3, level_full=4)
    W, G = resample(V, F, 0.5, seed=1)
    truth = cKDTree(V).query(W)[1]                # the source vertex each target vertex comes from
    rng = np.random.default_rng(0)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    perm = rng.permutation(len(W))
    W, G, truth = (W * [1.15, 1.0, 0.9] @ R.T)[perm], np.argsort(perm)[G], truth[perm]

    # the blob is mirror-symmetric (z -> -z), which no intrinsic descriptor can tell apart:
    # three matched landmarks (their heat kernels at 16 times) decide the orientation
    picked = rng.choice(len(W), 3, replace=False)
    res = sig.match_shapes((V, F), (W, G), k=20 if args.quick else 30,
                           k_final=50 if args.quick else 100, n_descriptors=20 if args.quick else 100,
                           landmarks=np.c_[truth[picked], picked])
    source = C.extreme_vertex(V, 0)
    geo = sig.HeatGeodesics(sig.laplacian(V, F))
    colour = geo.compute(source)
    # the error of each target vertex: the distance on the source from its true to its found vertex
    ids = np.unique(truth)
    D = geo.compute_each(ids)
    err = np.maximum(D[res.p2p, np.searchsorted(ids, truth)], 0.0) / np.sqrt(sig.laplacian(V, F).area())
    shown = W @ R                                  # the target drawn unrotated, to compare
    images = [C.render(out / "fig_correspondence.png", [(V, F), (shown, G)], [colour, colour[res.p2p]],
                       kind="distance", sources=[[source], None], shared_scale=True,
                       labels=["source: distance from a vertex", "target: the same, transferred"],
                       window_size=(1200, 600)),
              C.render(out / "fig_correspondence_error.png", (shown, G), err, kind="distance", n_levels=0,
                       title="target: geodesic error / sqrt(area)", window_size=(600, 600))]
    result = {"n_source": len(V), "n_target": len(W),
              "mean_error": sig.map_error(V, F, res.p2p, truth, samples=None),
              "mean_error_heat": float(err.mean()),
              "random_error": sig.map_error(V, F, rng.integers(0, len(V), len(W)), truth, samples=200),
              "seconds": {k: round(v, 2) for k, v in res.seconds.items()}, "images": images}
    return C.summary("fig_correspondence", result)


if __name__ == "__main__":
    main()
