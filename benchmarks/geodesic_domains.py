"""Heat-method geodesics on polygon meshes and point clouds, beside potpourri3d.

Usage::

    python benchmarks/geodesic_domains.py [--sources 12] [--seed 0] [--noise 0.2] [--json-dir docs/results]
                                          [--by-distance]

Mean relative error |d - d*| / d* over all vertices (sources excluded), averaged over random
sources (``--seed`` draws another set), at unit area. d*: ``igl.exact_geodesic`` on the
triangle mesh the polygons or points come from (horse_quad's quads split along one diagonal;
the vertices of real meshes as point clouds), the great-circle distance for points on the
unit sphere. Peers on the same input:
potpourri3d's ``PolygonMeshHeatSolver`` and ``MeshHeatMethodDistanceSolver`` (on the split
quads), and its ``PointCloudHeatSolver``; ours on point clouds with the default step (the
tufted cover) and with ``step="euler"``. With ``--json-dir`` (and no noise) the table is
also written as ``geodesic_domains.json`` for ``docs/results.md``.

``--by-distance`` also prints, for each point cloud, where the error is: the mean relative
error of the default and of potpourri3d (and the signed error) by distance from the source in
median point spacings, and how consistent the points' local Delaunay fans are (the share of
their triangles listed by one fan only).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import igl  # noqa: E402
from _results import Table  # noqa: E402  (beside this script)

import spectral_igl as sig  # noqa: E402
from data_generators.surfaces import sphere_points  # noqa: E402
from spectral_igl.io import read_mesh  # noqa: E402

MESHES = ROOT.parent / "shared" / "data" / "meshes"
COLUMNS = ["input (n)", "ours (default)", 'ours, `step="euler"`', "potpourri3d"]


def pct(x) -> str:
    return f"{100 * x:.2f}%"


def rel_error(d, exact):
    m = exact > 1e-9 * exact.max()
    return float(np.mean(np.abs(d[m] - exact[m]) / exact[m]))


def mean_error(fn, sources, exact):
    return np.mean([rel_error(fn(s), e) for s, e in zip(sources, exact)])


#: ``--by-distance``: bin edges of the distance from the source, in median point spacings
BINS = (0, 2, 5, 10, 20, 40, np.inf)


def by_distance(name, P, sources, exact, solvers):
    """Print the mean (signed) relative error of each of ``solvers`` (label -> compute) by
    distance from the source, in median spacings of ``P``, and the consistency of the fans."""
    from scipy.spatial import cKDTree

    from spectral_igl.laplacian.points import local_triangles

    spacing = float(np.median(cKDTree(P).query(P, 2)[0][:, 1]))
    T = local_triangles(P)
    _, votes = np.unique(np.sort(T, axis=1), axis=0, return_counts=True)
    print(f"{name}: {100 * np.mean(votes == 1):.0f}% of the local fans' triangles are in one fan only")
    for label, fn in solvers.items():
        err = [[] for _ in BINS[:-1]]
        for s, e in zip(sources, exact):
            d, m = fn(s), e > 1e-9 * e.max()
            b = np.digitize(e[m] / spacing, BINS) - 1
            for i, r in enumerate(err):
                r.append(((d[m] - e[m]) / e[m])[b == i])
        cells = [f"[{BINS[i]:g}, {BINS[i + 1]:g}) {100 * np.mean(np.abs(np.concatenate(r))):.2f}% "
                 f"({100 * np.mean(np.concatenate(r)):+.2f}%)" for i, r in enumerate(err)]
        print(f"  {label:12s} " + "; ".join(cells))


def polygons(rng, n_sources, table):
    import potpourri3d as pp3d

    V, F = read_mesh(MESHES / "horse_quad.obj", polygons=True)
    F = np.asarray(F)
    Ft = np.r_[F[:, [0, 1, 2]], F[:, [0, 2, 3]]]
    V = V / np.sqrt(igl.doublearea(V, Ft).sum() / 2.0)
    src = rng.choice(len(V), n_sources, replace=False)
    exact = [igl.exact_geodesic(V, Ft, np.array([s]), VT=np.arange(len(V))) for s in src]
    ours = sig.HeatGeodesics(sig.polygon_laplacian(V, F))
    poly = pp3d.PolygonMeshHeatSolver(V, F)
    tri = pp3d.MeshHeatMethodDistanceSolver(V, Ft)
    table.add(f"horse_quad, quads ({len(V):,})", pct(mean_error(ours.compute, src, exact)), "",
              f"{pct(mean_error(lambda s: poly.compute_distance(np.array([s])), src, exact))} "
              f"(`PolygonMeshHeatSolver`); {pct(mean_error(tri.compute_distance, src, exact))} on the split quads")


def points(rng, n_sources, table, noise=0.0, bins=False):
    """Point clouds; with ``noise``, every point moved by a Gaussian of that many median
    nearest-neighbour spacings (the exact distances stay those of the clean surface); with
    ``bins``, the errors by distance from the source (:func:`by_distance`)."""
    import potpourri3d as pp3d
    from scipy.spatial import cKDTree

    cases = [("unit sphere, random points", sphere_points(4000, seed=1), None)]
    for name in ("spot.obj", "cow.obj", "homer.obj", "rocker-arm.obj", "fandisk.obj", "cheburashka.obj"):
        V, F = read_mesh(MESHES / name)
        cases.append((f"{name[:-4]}'s vertices", V / np.sqrt(igl.doublearea(V, F).sum() / 2.0), F))
    for name, P, F in cases:
        src = rng.choice(len(P), n_sources, replace=False)
        if F is None:
            exact = [np.arccos(np.clip(P @ P[s], -1.0, 1.0)) for s in src]
        else:
            exact = [igl.exact_geodesic(P, F, np.array([s]), VT=np.arange(len(P))) for s in src]
        if noise:
            spacing = float(np.median(cKDTree(P).query(P, 2)[0][:, 1]))
            P = P + noise * spacing * rng.standard_normal(P.shape)
        lap = sig.point_cloud_laplacian(P)
        ours = sig.HeatGeodesics(lap)                      # the tufted cover
        euler = sig.HeatGeodesics(lap, step="euler")       # the cloud's own heat step
        peer = pp3d.PointCloudHeatSolver(P)
        table.add(f"{name} ({len(P):,})", pct(mean_error(ours.compute, src, exact)),
                  pct(mean_error(euler.compute, src, exact)), pct(mean_error(peer.compute_distance, src, exact)))
        if bins:
            by_distance(name, P, src, exact, {"ours": ours.compute, "potpourri3d": peer.compute_distance})


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sources", type=int, default=12)
    p.add_argument("--seed", type=int, default=0, help="seed of the random sources")
    p.add_argument("--noise", type=float, default=0.0,
                   help="point clouds only, each point moved by a Gaussian of this many median spacings")
    p.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    p.add_argument("--by-distance", action="store_true",
                   help="point clouds: also print the errors by distance from the source")
    args = p.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    table = Table("geodesic_domains", COLUMNS, None if args.noise else args.json_dir)
    if not args.noise:
        polygons(rng, args.sources, table)
    points(rng, args.sources, table, args.noise, args.by_distance)
    table.close()


if __name__ == "__main__":
    main()
