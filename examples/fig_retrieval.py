"""Shape retrieval: a labelled collection through collection.run, its distance matrix, neighbours.

Each class is one generated shape under resampling, noise and a near-isometric bending,
every copy rotated and scaled at random. ``collection.run`` (dask) stores each shape's
ShapeDNA with its bound; ``sig.collection_distance_matrix`` compares them and keeps the
matrix beside the store (a second call reads it back). Pictured: the matrix with the
classes marked, and a few shapes with their nearest neighbours (green: same class).
"""
from __future__ import annotations

import shutil

import numpy as np

import _common as C


def collection(quick: bool):
    """``({name: (V, F)}, {name: class})``: every class under four variants, rotated and scaled."""
    from scipy.stats import special_ortho_group

    from data_generators import bend, cylinder, icosphere, torus
    from data_generators.perturb import mean_edge_length, normal_noise, resample

    level = 2 if quick else 3
    sphere = icosphere(level)
    classes = {"blob": C.blob(level), "ellipsoid": (sphere[0] * [1.0, 0.7, 0.5], sphere[1]),
               "cigar": (sphere[0] * [1.0, 0.35, 0.35], sphere[1]),
               "torus": torus(1.0, 0.4, 24 if quick else 48, 10 if quick else 20)}
    if not quick:
        classes["fat torus"] = torus(1.0, 0.65, 40, 24)
        classes["tube"] = cylinder(0.4, 2.0, 40, 30)
    rng = np.random.default_rng(0)
    shapes, label = {}, {}
    for c, (name, (V, F)) in enumerate(classes.items()):
        h = mean_edge_length(V, F)
        Vr, Fr = resample(V, F, 0.5, seed=c)
        for kind, W, G in [("base", V, F), ("resampled", Vr, Fr),
                           ("noisy", normal_noise(Vr, Fr, 0.1 * h, seed=c), Fr),
                           ("bent", bend(V, np.pi / 6), F)]:
            R = special_ortho_group.rvs(3, random_state=rng)
            key = f"{name}-{kind}".replace(" ", "_")
            shapes[key] = (10.0 ** rng.uniform(-1, 1) * (W - W.mean(axis=0)) @ R.T, G)
            label[key] = name
    return shapes, label


def draw_matrix(path, D, labels):
    """The distance matrix, rows grouped by class, class boundaries and names marked."""
    plt = C.pyplot()
    fig, ax = plt.subplots(figsize=(6.2, 5.2))
    im = ax.imshow(D, cmap="viridis")
    fig.colorbar(im, ax=ax, label="ShapeDNA distance")
    names, starts = np.unique(labels, return_index=True)
    order = np.argsort(starts)
    edges = list(np.sort(starts)) + [len(labels)]
    for e in edges[1:-1]:
        ax.axhline(e - 0.5, color="w", lw=1.2)
        ax.axvline(e - 0.5, color="w", lw=1.2)
    centres = [(edges[i] + edges[i + 1] - 1) / 2 for i in range(len(order))]
    ax.set_xticks(centres, names[order], rotation=30, ha="right")
    ax.set_yticks(centres, names[order])
    ax.set_title("distances between all shapes (blocks: classes)")
    return C.savefig(fig, path)


def draw_neighbours(path, shapes, names, labels, D, queries, k=3):
    """Each query (left) and its ``k`` nearest other shapes, titled green when of its class."""
    plt = C.pyplot()
    fig = plt.figure(figsize=(2.4 * (k + 1), 2.4 * len(queries)))
    for r, q in enumerate(queries):
        order = [j for j in np.argsort(D[q], kind="stable") if j != q][:k]
        for c, j in enumerate([q] + order):
            V, F = shapes[names[j]]
            ax = fig.add_subplot(len(queries), k + 1, r * (k + 1) + c + 1, projection="3d")
            ax.plot_trisurf(*V.T, triangles=F, color="0.75", edgecolor="none", shade=True)
            lim = np.abs(V - V.mean(axis=0)).max()
            for set_lim, m in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), V.mean(axis=0)):
                set_lim(m - lim, m + lim)
            ax.set_axis_off()
            same = labels[j] == labels[q]
            title = f"query\n{names[q]}" if c == 0 else f"{c}. {names[j]}\nd = {D[q, j]:.3f}"
            ax.set_title(title, fontsize=8, color="k" if c == 0 else ("tab:green" if same else "tab:red"))
    return C.savefig(fig, path)


def main(argv=None):
    args = C.parser(__doc__).parse_args(argv)
    out = C.out_dir(args)
    import spectral_igl as sig
    from spectral_igl.collection import Job, run

    shapes, label = collection(args.quick)
    k = 20 if args.quick else 40
    store = out / "fig_retrieval.zarr"
    shutil.rmtree(store, ignore_errors=True)
    job = Job.shape_dna(k)
    if args.quick:   # a scheduler in this process starts in a moment; the default is a local cluster
        from distributed import Client

        with Client(processes=False, dashboard_address=None) as client:
            summary = run(shapes, job, store, scheduler=client, progress=False)
    else:
        summary = run(shapes, job, store, progress=False)
    D, names, info = sig.collection_distance_matrix(store, job, return_info=True)
    again = run(shapes, job, store, workers=1, progress=False)         # a rerun: nothing to do
    D2, _, info2 = sig.collection_distance_matrix(store, job, return_info=True)
    labels = np.array([label[n] for n in names])
    nn, mAP = sig.retrieval_scores(D, labels)
    direct = sig.shape_distance_matrix([sig.shape_dna(shapes[n], k) for n in names],
                                       "shape_dna")
    bent = [i for i, n in enumerate(names) if n.endswith("-bent")]
    bent = [bent[i] for i in np.linspace(0, len(bent) - 1, 3).round().astype(int)]   # three classes apart
    images = [draw_matrix(out / "fig_retrieval_matrix.png", D, labels),
              draw_neighbours(out / "fig_retrieval_neighbours.png", shapes, names, labels, D, bent)]
    result = {"shapes": len(names), "classes": len(set(labels)), "nn_accuracy": nn, "map": mAP,
              "done": len(summary.done), "rerun_skipped": len(again.skipped),
              "matrix_recomputed_on_rerun": bool(info2["recomputed"]), "rerun_equal": bool(np.array_equal(D, D2)),
              "largest_bound": float(info["abs_error"].max()), "bound_kind": info["bound_kind"],
              "difference_to_direct": float(np.abs(D - direct).max()), "images": images}
    return C.summary("fig_retrieval", result)


if __name__ == "__main__":
    main()
