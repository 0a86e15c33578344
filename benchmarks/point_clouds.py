"""Point-cloud Laplacians beside robust_laplacian, in one run: accuracy, sparsity, heat-kernel cost.

1. Unit sphere sampled four ways (Fibonacci, uniformly random, density ratio 3, jittered
   grid), at two sizes: largest relative error of the first 16 nonzero eigenvalues
   against l(l+1), and nonzeros per row of L.
2. Vertices of real shapes (unit area) against the spectrum of their own surface: median
   and largest relative error of the first 20 nonzero eigenvalues (after one zero per connected
   component of each operator). The reference is linear FEM on the mesh midpoint-subdivided
   to at least 40,000 vertices (the same piecewise-linear surface, converged: full and
   lumped mass agree there to 0.02--0.16%); FEM on the unrefined mesh is printed beside it,
   as it is itself several percent off on coarse meshes (suzanne 12%, beetle 7%).
3. What the points cannot see (``glued``): seams, where the mesh is cut along a curve whose
   two sides carry coincident vertices or lie within half an edge (the points sample the
   surface without the cut), and parts that touch. Median and largest error of the first
   20 eigenvalues against the mesh; against the mesh welded (coincident vertices merged);
   and of the default whose stars take only neighbours on their own sheet (a path along
   mesh edges at most 3 times their straight distance): an oracle no point-cloud operator
   has, which says how much of an error is surface that the points glue.
4. The same surfaces sampled finer (``refined``): the vertices of the meshes where
   robust_laplacian is ahead, midpoint-subdivided once and twice (the same surface and
   reference), ours beside robust_laplacian.
5. Accuracy against nonzeros: k swept for each method on the random sphere.
6. One heat-kernel column (``sig.heat_kernel``, tol 1e-8) on the vertices of a mesh with
   the point-cloud operator against the same on the mesh, with ``--heat-n`` vertices
   (the mesh is loop-subdivided until it has at least that many).

Usage::

    python benchmarks/point_clouds.py                 # 4k and 16k points, real shapes, 134k heat
    python benchmarks/point_clouds.py --quick         # 2k and 8k, two shapes, no heat timing
    python benchmarks/point_clouds.py --sections shapes --json-dir docs/results   # docs/results/point_clouds.json
    python benchmarks/point_clouds.py --sections glued                              # what points glue
    python benchmarks/point_clouds.py --sections refined --json-dir docs/results    # finer samplings
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla
from _results import Table  # beside this script

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from data_generators import midpoint_subdivide, sphere_eigenvalues, sphere_points  # noqa: E402
from spectral_igl.io import read_mesh  # noqa: E402

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "meshes"
EX16 = sphere_eigenvalues(17)[1:]


def fibonacci(n):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    return np.c_[r * np.cos(phi), r * np.sin(phi), z]


def jittered(n, seed=0):
    """Fibonacci points moved by a random fraction (0.3) of the spacing, back on the sphere."""
    P = fibonacci(n)
    h = np.sqrt(4 * np.pi / n)
    P = P + 0.3 * h * np.random.default_rng(seed).standard_normal(P.shape)
    return P / np.linalg.norm(P, axis=1, keepdims=True)


SAMPLINGS = {"fibonacci": fibonacci, "random": lambda n: sphere_points(n, seed=3),
             "density x3": lambda n: sphere_points(n, seed=4, nonuniform=1.0),
             "jittered": jittered}


def operator(P, method, k=None):
    if method == "robust_laplacian":
        import robust_laplacian

        kw = {} if k is None else {"n_neighbors": k}
        return robust_laplacian.point_cloud_laplacian(P, **kw)
    lap = sig.point_cloud_laplacian(P, method=method, k=k)
    return lap.L, lap.B


def smallest(L, M, k):
    return np.sort(spla.eigsh(L.tocsc(), k, M.tocsc(), sigma=-1e-4)[0])


def spheres(sizes, methods):
    print("## unit sphere: max rel. error of eigenvalues 1..16 (nnz per row of L)")
    for name, gen in SAMPLINGS.items():
        for n in sizes:
            P = gen(n)
            cells = []
            for m in methods:
                L, M = operator(P, m)
                ev = smallest(L, M, 17)
                cells.append(f"{m} {np.max(np.abs(ev[1:] - EX16) / EX16):.4f} ({L.nnz / n:.0f})")
            print(f"{name:11s} {n:6d} | " + " | ".join(cells), flush=True)


def components(L):
    """Connected components of the graph of the off-diagonal entries of L."""
    from scipy.sparse.csgraph import connected_components

    return connected_components(L != 0, directed=False)[0]


def nonzero_eigs(L, M, k, c):
    """The k smallest eigenvalues after the c zero ones (one per component)."""
    return smallest(L, M, k + c)[c:]


def surface_spectrum(V, F, k=20, target=40_000):
    """First k nonzero eigenvalues of the piecewise-linear surface (V, F): linear FEM (full
    mass) on the mesh midpoint-subdivided until it has ``target`` vertices, which leaves
    the surface unchanged; and the gap to the lumped mass there (the reference's own error)."""
    Vr, Fr = midpoint_subdivide(V, F)
    while len(Vr) < target:
        Vr, Fr = midpoint_subdivide(Vr, Fr)
    # components from the faces: cotan weights can be exactly 0 on right angles
    n = len(Vr)
    E = np.r_[Fr[:, [0, 1]], Fr[:, [1, 2]], Fr[:, [2, 0]]]
    import scipy.sparse as sp

    c = components(sp.coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        full = sig.laplacian(Vr, Fr, weights="cotan", mass="full")
        lumped = sig.laplacian(Vr, Fr)
    ref = nonzero_eigs(full.L, full.B, k, c)
    gap = np.median(np.abs(nonzero_eigs(lumped.L, lumped.B, k, c) / ref - 1))
    return ref, gap, n, c


def percent(x):
    return f"{100 * x:#.3g}%"


def shapes(names, methods, json_dir=None):
    print("## vertices of real shapes: median / max rel. error of the first 20 nonzero eigenvalues against "
          "the spectrum of the mesh's surface (FEM on the mesh midpoint-subdivided to >= 40k "
          "vertices: ref n, its full-lumped gap); 'mesh' is full-mass FEM on the mesh itself")
    table = Table("point_clouds", ["shape", "vertices", "reference n", "reference full/lumped gap",
                                   "mesh (FEM)", *methods], json_dir)
    for name in names:
        if not (MESHES / name).is_file():
            print(f"{name}: not found, skipped")
            continue
        V, F = _unit_shape(name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            own = sig.laplacian(V, F, weights="cotan", mass="full")
        ref, gap, nr, c = surface_spectrum(V, F)
        cells = [percent(np.median(np.abs(nonzero_eigs(own.L, own.B, 20, c) / ref - 1)))]
        cells += [_errors(*operator(V, m), ref) for m in methods]
        table.add(Path(name).stem, f"{len(V):,}", f"{nr:,}", percent(gap), *cells)
    table.close()


GLUE = 3.0  # a neighbour is on another sheet where the mesh path is longer than this many straight lengths


def one_sheet_operator(V, F, k=20, spare=100):
    """The default operator (``k`` neighbours, rims read as by default) with each point's
    star made of its ``k`` nearest neighbours *on its own sheet*: among the ``k + spare``
    nearest, those whose shortest path along mesh edges (an upper bound of the geodesic
    distance) is at most ``GLUE`` times the straight distance come first. An oracle no
    point cloud has: the mesh tells which points lie across a seam or on a part that
    touches another."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    from spectral_igl.laplacian.points import _knn, delaunay_from_neighbours

    n = len(V)
    E = np.unique(np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1), axis=0)
    G = sp.csr_matrix((np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1), (E[:, 0], E[:, 1])), shape=(n, n))
    rows = np.arange(n)
    d, J = _knn(cKDTree(V), V, rows, min(k + spare, n - 1))
    same = np.ones(J.shape, bool)
    for chunk in np.array_split(rows, max(1, n // 256)):
        D = dijkstra(G, directed=False, indices=chunk, limit=GLUE * d[chunk].max() * 1.0001)
        same[chunk] = D[np.arange(len(chunk))[:, None], J[chunk]] <= GLUE * d[chunk]
    first = np.argsort(~same, axis=1, kind="stable")[:, :k]   # own sheet first, nearest first
    lap = delaunay_from_neighbours(V, np.take_along_axis(d, first, axis=1), np.take_along_axis(J, first, axis=1),
                                   "auto")
    return lap.L, lap.B


def _unit_shape(name):
    V, F = read_mesh(MESHES / name)
    used = np.unique(F)
    V, F = V[used], np.searchsorted(used, F)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return V / np.sqrt(sig.laplacian(V, F).area()), F


def _errors(L, M, ref):
    e = np.abs(nonzero_eigs(L, M, 20, components(L)) / ref - 1)
    return f"{percent(np.median(e))} / {percent(e.max())}"


def welded(V, F, eps):
    """(V, F) with vertices closer than ``eps`` merged and collapsed faces dropped."""
    import igl

    W, _, _, G = igl.remove_duplicate_vertices(V, F, eps)
    G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 2] != G[:, 0])]
    used = np.unique(G)
    return W[used], np.searchsorted(used, G)


def glued(names, json_dir=None):
    from scipy.spatial import cKDTree

    print("## what the points cannot see: seams and touching parts. Median / max error of the first "
          "20 eigenvalues against the mesh's surface, and against the mesh welded (vertices closer "
          "than 1e-3 of the median edge merged: the surface its points sample); the default with "
          f"stars of one sheet (neighbours whose mesh path is <= {GLUE:g}x their distance: an oracle)")
    table = Table("point_clouds_glued", ["shape", "boundary vertices", "... with a point within h/2",
                                         "mesh components (welded)", "delaunay", "robust_laplacian",
                                         "delaunay, welded ref", "robust_laplacian, welded ref",
                                         "delaunay, stars of one sheet", "the same, k=30"], json_dir)
    for name in names:
        V, F = _unit_shape(name)
        E = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
        edges, count = np.unique(E, axis=0, return_counts=True)
        boundary = np.zeros(len(V), bool)
        boundary[edges[count == 1].ravel()] = True
        h = np.median(np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1))
        near = cKDTree(V).query(V, 2)[0][:, 1] < 0.5 * h
        ref, _, _, c = surface_spectrum(V, F)
        Vw, Fw = welded(V, F, 1e-3 * h)
        ref_w, _, _, cw = surface_spectrum(Vw, Fw)
        ops = [operator(V, m) for m in ("delaunay", "robust_laplacian")]
        cells = [_errors(L, M, r) for r in (ref, ref_w) for L, M in ops]
        table.add(Path(name).stem, f"{boundary.sum():,}", f"{np.sum(boundary & near):,}", f"{c} ({cw})",
                  *cells, *(_errors(*one_sheet_operator(V, F, k=k), ref) for k in (20, 30)))
    table.close()


def refined(names, levels=(1, 2), json_dir=None):
    """The same surfaces sampled more finely: the vertices of each mesh midpoint-subdivided
    ``levels`` times (points on the same piecewise-linear surface, so the reference spectrum
    is the same), median / largest error of the first 20 eigenvalues, ours beside
    robust_laplacian on the same points."""
    from data_generators import midpoint_subdivide

    print("## the same surfaces, sampled finer: the vertices of the mesh midpoint-subdivided 0, 1, 2 "
          "times (median / max error of the first 20 eigenvalues against the surface's spectrum)")
    table = Table("point_clouds_refined", ["shape", "points", "delaunay", "robust_laplacian"], json_dir)
    for name in names:
        V, F = _unit_shape(name)
        ref, _, _, _ = surface_spectrum(V, F)
        for level in range(max(levels) + 1):
            if level:
                V, F = midpoint_subdivide(V, F)
            if level == 0 or level in levels:
                table.add(Path(name).stem, f"{len(V):,}",
                          *(_errors(*operator(V, m), ref) for m in ("delaunay", "robust_laplacian")))
    table.close()


def knee(n, ks):
    print(f"## accuracy against nonzeros, random sphere n={n}: k, nnz/row, max rel. error 1..16")
    P = sphere_points(n, seed=3)
    for m, kk in ks.items():
        for k in kk:
            L, M = operator(P, m, k)
            ev = smallest(L, M, 17)
            print(f"{m:16s} k={k:3d} nnz/row {L.nnz / n:6.1f} err {np.max(np.abs(ev[1:] - EX16) / EX16):.4f}",
                  flush=True)


def heat(n_target, mesh="stanford-bunny.obj"):
    import igl

    path = MESHES / mesh
    if not path.is_file():
        print(f"{mesh}: not found, heat timing skipped")
        return
    V, F = read_mesh(path)
    used = np.unique(F)
    V, F = V[used], np.searchsorted(used, F)
    while len(V) < n_target:
        V, F = igl.upsample(V, F)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh_lap = sig.laplacian(V, F)
    V = V / np.sqrt(mesh_lap.area())
    mesh_lap = sig.laplacian(V, F)
    i, t = int(np.argmax(V[:, 2])), 1e-3
    print(f"## one heat-kernel column, t={t} (unit area), {len(V)} vertices of {mesh} (upsampled)")
    for name, build in [("mesh (cotan)", lambda: mesh_lap),
                        ("points delaunay", lambda: sig.point_cloud_laplacian(V)),
                        ("points belkin", lambda: sig.point_cloud_laplacian(V, method="belkin"))]:
        t0 = time.perf_counter()
        lap = build()
        tb = time.perf_counter() - t0
        t0 = time.perf_counter()
        sig.heat_kernel(lap, t, i, tol=1e-8)
        th = time.perf_counter() - t0
        print(f"{name:16s} nnz/row {lap.L.nnz / lap.n:5.1f} build {tb:6.2f} s  heat column {th:6.2f} s", flush=True)


SECTIONS = ("spheres", "shapes", "glued", "refined", "knee", "heat")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--heat-n", type=int, default=134_000)
    p.add_argument("--sections", nargs="*", choices=SECTIONS, default=list(SECTIONS), help="parts to run")
    p.add_argument("--json-dir", help="also write the real shapes' table as point_clouds.json in this folder")
    a = p.parse_args(argv)
    methods = ["delaunay", "robust_laplacian", "belkin", "liu"]
    if a.quick:
        spheres([2000, 8000], methods)
        shapes(["spot.obj", "fertility.off"], methods)
        return
    if "spheres" in a.sections:
        spheres([4000, 16000], methods)
    if "shapes" in a.sections:
        shapes(["spot.obj", "cow.obj", "fertility.off", "rocker-arm.obj", "cheburashka.obj",
                "fandisk.obj", "homer.obj", "armadillo.obj", "stanford-bunny.obj", "suzanne.obj",
                "beetle.obj", "circle.obj", "camel_b.obj", "teapot.obj", "truck.obj"], methods[:3], a.json_dir)
    if "glued" in a.sections:
        glued(["circle.obj", "cow.obj", "homer.obj", "cheburashka.obj", "suzanne.obj", "beetle.obj",
               "camel_b.obj", "teapot.obj", "truck.obj"], a.json_dir)
    if "refined" in a.sections:
        refined(["circle.obj", "suzanne.obj", "beetle.obj", "cow.obj", "homer.obj", "cheburashka.obj"],
                json_dir=a.json_dir)
    if "knee" in a.sections:
        knee(16000, {"delaunay": [8, 12, 20, 30], "robust_laplacian": [12, 30],
                     "belkin": [16, 32, 64]})
    if "heat" in a.sections:
        heat(a.heat_n)


if __name__ == "__main__":
    main()
