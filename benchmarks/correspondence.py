"""Shape correspondence against pyFM, on pairs with a known map, one row per class of deformation.

Every pair is two remeshings of one parent mesh (a random 1-to-3 split of half the faces,
then edge collapses to a different size each: different connectivity and vertex count),
the target's vertices scrambled and the target rotated, and then one of:

* ``isometric``: nothing more;
* ``stretch``: the target scaled by (1.3, 1, 0.75) before the rotation;
* ``noise``: the target displaced along its normals by N(0, (0.2% of its diagonal)^2);
* ``topology``: the target glued at a few places (vertices close in space and far along the
  surface merged into one);
* ``partial``: a limb cut off the target (the faces within a ball around its most eccentric vertex);
  two more such rows: ``partial-2`` cuts the parent's second extremity (the most eccentric vertex
  away from the first), ``partial-cow`` the first extremity of cow.obj (pair of 5000 / 6500 faces).

The true map sends each target vertex to the source vertex nearest to it on the parent (before
the rotation, stretch and noise). The error is the mean exact geodesic distance on the source
between the found and the true vertex, over sqrt(area), on 200 sampled target vertices (the
same for both methods).

Both methods use 100 WKS energies, a 30 x 30 functional map and ZoomOut to 100:

* ``ours``: :func:`spectral_igl.match_shapes` (certified eigenpairs, spectrum-free WKS on each
  shape's own grid, the map with Laplacian commutativity, ZoomOut);
* ``pyFM``: ``FunctionalMapping.preprocess(n_descr=100, descr_type="WKS", subsample_step=5)``,
  ``fit(K=(30, 30), w_descr=1, w_lap=1e-2, w_dcomm=1e-1)``, ``zoomout_refine(nit=70)``,
  ``get_p2p`` (the usual pipeline of pyFM's example notebook, its default weighting);

with the time of each stage. A second table measures the landmark heat-kernel descriptors
(5 matched landmarks x 16 times) spectrum-free against the same kernels from the 200-eigenpair
expansion: accuracy of the kernel against a dense eigendecomposition, time, and the map error
each gives; and the HKS/WKS on each shape's own grid against one common grid.

    OPENBLAS_NUM_THREADS=1 python benchmarks/correspondence.py [--mesh PATH] [--only CLASS ...]
"""
from __future__ import annotations

import argparse
import datetime
import platform
import sys
import time
from pathlib import Path

import igl
import numpy as np
from scipy.spatial import cKDTree

import spectral_igl as sig
from spectral_igl.data_generators import normal_noise, resample
from spectral_igl.io import read_mesh

HERE = Path(__file__).resolve().parent
MESH = HERE.parent.parent / "shared" / "data" / "meshes" / "homer.obj"
CLASSES = ("isometric", "stretch", "noise", "topology", "partial", "partial-2", "partial-cow")
#: rows other than a class of the parent mesh: (kind, parent mesh or None for --mesh, extremity,
#: faces of source and target)
ROWS = {"partial-2": ("partial", None, 1, (6000, 7800)),
        "partial-cow": ("partial", MESH.parent / "cow.obj", 0, (5000, 6500))}
K, K_FINAL, N_DESCR, SAMPLES = 30, 100, 100, 200


# ----------------------------------------------------------------------------- pairs

def remesh(V, F, faces, seed):
    """A remeshing of (V, F) with about ``faces`` faces: random 1-to-3 splits, then collapses."""
    Vr, Fr = resample(V, F, 0.5, seed=seed)
    U, G, _, _ = igl.decimate(np.asfortranarray(Vr), np.asfortranarray(Fr.astype(np.int32)), faces)
    U, G = np.asarray(U, float), np.asarray(G, np.int64)
    G = G[np.ptp(np.sort(G, axis=1), axis=1) > 0]
    return compact(U, G)


def compact(V, F):
    """Drop unreferenced vertices; returns (V, F, kept old indices)."""
    used = np.unique(F)
    new = np.full(len(V), -1)
    new[used] = np.arange(used.size)
    return V[used], new[F], used


def largest_component(V, F):
    """The largest connected component; returns (V, F, kept old indices)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = len(V)
    A = sp.coo_matrix((np.ones(3 * len(F)), (F.ravel(), np.roll(F, 1, axis=1).ravel())), (n, n))
    _, lab = connected_components(A, directed=False)
    big = np.argmax(np.bincount(lab[np.unique(F)]))
    F = F[lab[F[:, 0]] == big]
    return compact(V, F)


def glue(V, F, places=4, seed=0):
    """Merge vertices close in space (< 1.5 edges) but far along the surface (> 20 edges) at a
    few places; returns (V, F, kept old indices, old index -> kept representative)."""
    h = float(np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)))
    pairs = np.array(sorted(cKDTree(V).query_pairs(1.5 * h)))
    lap = sig.laplacian(V, F)
    heat = sig.HeatGeodesics(lap)
    rng = np.random.default_rng(seed)
    rep = np.arange(len(V))
    done = 0
    for i, j in pairs[rng.permutation(len(pairs))]:
        if done == places:
            break
        if rep[i] != i or rep[j] != j:
            continue
        d_i = heat.compute(int(i))
        if d_i[j] > 20 * h:
            # weld the neighbourhoods: every vertex within 1.5 h of j joins its nearest one near i
            near_i = np.flatnonzero(np.linalg.norm(V - V[i], axis=1) < 1.5 * h)
            near_j = np.flatnonzero(np.linalg.norm(V - V[j], axis=1) < 1.5 * h)
            near_j = near_j[d_i[near_j] > 10 * h]
            rep[near_j] = near_i[cKDTree(V[near_i]).query(V[near_j])[1]]
            done += 1
    G = rep[F]
    G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 0] != G[:, 2])]
    U, G, kept = compact(V, G)
    return U, G, kept, done


def cut_limb(V, F, extremity=0):
    """The target without a limb: faces within a ball around an extremity. Extremity 0 is the
    vertex farthest from the centre, extremity j the farthest among those more than two ball
    radii from extremities 0 .. j-1."""
    c = V.mean(axis=0)
    dist = np.linalg.norm(V - c, axis=1)
    allowed = np.ones(len(V), bool)
    for _ in range(extremity + 1):
        tip = np.argmax(np.where(allowed, dist, -np.inf))
        r = 0.35 * dist[tip]
        allowed &= np.linalg.norm(V - V[tip], axis=1) > 2 * r
    far = np.linalg.norm(V - V[tip], axis=1) > r
    return largest_component(V, F[np.all(far[F], axis=1)])


def rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def make_pair(V, F, kind, faces=(6000, 7800), seed=0, extremity=0):
    """(V1, F1, V2, F2, truth): truth[y] is the source vertex of target vertex y; ``extremity``
    chooses the limb a partial pair loses (:func:`cut_limb`)."""
    V1, F1, _ = remesh(V, F, faces[0], seed=1)
    V2, F2, _ = remesh(V, F, faces[1], seed=2)
    rest = V2.copy()
    if kind == "topology":
        V2, F2, kept, _ = glue(V2, F2, seed=seed)
        rest = rest[kept]
    if kind == "partial":
        V2, F2, kept = cut_limb(V2, F2, extremity)
        rest = rest[kept]
    truth = cKDTree(V1).query(rest)[1]
    if kind == "stretch":
        V2 = V2 * np.array([1.3, 1.0, 0.75])
    if kind == "noise":
        diag = np.linalg.norm(np.ptp(V2, axis=0))
        V2 = normal_noise(V2, F2, 0.002 * diag, seed=seed)
    V2 = V2 @ rotation(seed + 7).T
    perm = np.random.default_rng(seed + 3).permutation(len(V2))
    inv = np.argsort(perm)
    return V1, F1, V2[perm], inv[F2], truth[perm]


# ----------------------------------------------------------------------------- methods

def run_ours(V1, F1, V2, F2, **kw):
    res = sig.match_shapes((V1, F1), (V2, F2), k=K, k_final=K_FINAL, n_descriptors=N_DESCR, **kw)
    return res.p2p, res.seconds


def run_pyfm(V1, F1, V2, F2):
    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    sec = {}
    t = time.perf_counter()
    model = FunctionalMapping(TriMesh(V1, F1), TriMesh(V2, F2))
    model.preprocess(n_descr=N_DESCR, descr_type=None, k_process=K_FINAL)
    sec["eigs"] = time.perf_counter() - t
    t = time.perf_counter()
    model.compute_spectral_descriptors(n_descr=N_DESCR, descr_type="WKS", subsample_step=5)
    sec["descriptors"] = time.perf_counter() - t
    t = time.perf_counter()
    model.fit(K=(K, K), w_descr=1.0, w_lap=1e-2, w_dcomm=1e-1)
    sec["fit"] = time.perf_counter() - t
    t = time.perf_counter()
    FM = model.zoomout_refine(nit=K_FINAL - K, step=1)
    p2p = model.get_p2p(FM)
    sec["zoomout"] = time.perf_counter() - t
    return np.asarray(p2p), sec


def error(V1, F1, p2p, truth):
    return sig.map_error(V1, F1, p2p, truth, samples=SAMPLES)


def fmt(sec):
    return " / ".join(f"{sec[s]:.1f}" for s in ("eigs", "descriptors", "fit", "zoomout"))


# ----------------------------------------------------------------------------- landmarks

def landmark_study(V, F):
    """Landmark heat kernels spectrum-free vs from 200 eigenpairs: kernel accuracy on a small
    remeshing (dense truth), then time and map error on the isometric pair."""
    rows = []
    Vs, Fs, _ = remesh(V, F, 3000, seed=5)
    lap = sig.laplacian(Vs, Fs)
    lm = np.random.default_rng(0).choice(lap.n, 5, replace=False)
    times = sig.hks_times(lap, 16)
    ev, X = sig.dense_eigs(lap)
    exact = np.einsum("nl,ml,lt->nmt", X, X[lm], np.exp(-np.outer(ev, times)))
    free = sig.heat_kernels(lap, times, lm)
    evk, Xk = sig.eigs(lap, 200)
    trunc = np.einsum("nl,ml,lt->nmt", Xk, Xk[lm], np.exp(-np.outer(evk, times)))
    scale = np.abs(exact).max(axis=0)
    rows.append(("kernel max error / max (n=%d, 16 times)" % lap.n,
                 f"{(np.abs(free - exact).max(axis=0) / scale).max():.1e}",
                 f"{(np.abs(trunc - exact).max(axis=0) / scale).max():.1e}"))
    V1, F1, V2, F2, truth = make_pair(V, F, "isometric")
    l1, l2 = sig.laplacian(V1, F1), sig.laplacian(V2, F2)
    ids = np.random.default_rng(1).choice(l2.n, 5, replace=False)
    pairs = np.c_[truth[ids], ids]
    t = time.perf_counter()
    D1 = sig.landmark_descriptors(l1, pairs[:, 0])
    D2 = sig.landmark_descriptors(l2, pairs[:, 1])
    t_free = time.perf_counter() - t
    t = time.perf_counter()
    b1, b2 = sig.eigs(l1, 200), sig.eigs(l2, 200)
    t_eig = time.perf_counter() - t
    t = time.perf_counter()
    E = []
    for lap_, (e, X_), p in ((l1, b1, pairs[:, 0]), (l2, b2, pairs[:, 1])):
        T = sig.hks_times(lap_, 16)
        Kt = np.einsum("nl,ml,lt->nmt", X_, X_[p], np.exp(-np.outer(e, T))).reshape(lap_.n, -1)
        E.append(Kt / np.sqrt(np.einsum("ij,ij->j", Kt, lap_.B @ Kt) / lap_.area()))
    t_trunc = time.perf_counter() - t + t_eig
    rows.append(("landmark descriptors, both shapes, s", f"{t_free:.1f}",
                 f"{t_trunc:.1f} (200 pairs {t_eig:.1f})"))
    small1, small2 = (b1[0][:K], b1[1][:, :K]), (b2[0][:K], b2[1][:, :K])
    errs = []
    for A, B in ((D1, D2), (E[0], E[1])):
        C = sig.functional_map(l1, l2, A, B, small1, small2)
        p2p = sig.point_map(C, b1[1], b2[1])
        errs.append(error(V1, F1, p2p, truth))
    rows.append(("map error, landmarks only, 30x30 map, no ZoomOut", f"{errs[0]:.4f}", f"{errs[1]:.4f}"))
    return rows


def grid_study(V, F):
    """Each shape's own grid against one common grid, on the stretched pair, after ZoomOut."""
    V1, F1, V2, F2, truth = make_pair(V, F, "stretch")
    V2 = V2 * 1.5                                   # and not at the same scale
    rows = []
    for kind in ("wks", "hks"):
        errs = [error(V1, F1, run_ours(V1, F1, V2, F2, descriptors=kind, grid=g)[0], truth)
                for g in ("own", "common")]
        rows.append((kind, f"{errs[0]:.4f}", f"{errs[1]:.4f}"))
    return rows


# ----------------------------------------------------------------------------- main

def unit_mesh(path):
    """The mesh at ``path`` scaled to unit area."""
    V, F = read_mesh(str(path))
    return V / np.sqrt(sig.laplacian(V, F).area()), F


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default=str(MESH), help="the parent mesh (default homer.obj)")
    ap.add_argument("--only", nargs="+", choices=CLASSES)
    ap.add_argument("--skip-studies", action="store_true", help="only the table against pyFM")
    args = ap.parse_args(argv)
    V, F = unit_mesh(args.mesh)
    print(f"# correspondence: {platform.processor() or platform.machine()}, {datetime.date.today()}, "
          f"OPENBLAS_NUM_THREADS=1 python {' '.join(sys.argv)}")
    print(f"parent {Path(args.mesh).name} ({len(V)} vertices); k = {K} -> {K_FINAL}, {N_DESCR} WKS energies\n")
    print("| class | n1 / n2 | ours error | pyFM error | random map | ours s: eigs / descr / fit / zoomout "
          "| pyFM s: eigs / descr / fit / zoomout |")
    print("|---|---|---|---|---|---|---|")
    for row in args.only or CLASSES:
        kind, mesh, extremity, faces = ROWS.get(row, (row, None, 0, (6000, 7800)))
        V0, F0 = (V, F) if mesh is None else unit_mesh(mesh)
        V1, F1, V2, F2, truth = make_pair(V0, F0, kind, faces=faces, extremity=extremity)
        ours, s_ours = run_ours(V1, F1, V2, F2)
        pyfm, s_pyfm = run_pyfm(V1, F1, V2, F2)
        rand = np.random.default_rng(0).integers(0, len(V1), len(V2))
        print(f"| {row} | {len(V1)} / {len(V2)} | {error(V1, F1, ours, truth):.4f} | "
              f"{error(V1, F1, pyfm, truth):.4f} | {error(V1, F1, rand, truth):.3f} | {fmt(s_ours)} | "
              f"{fmt(s_pyfm)} |", flush=True)
    if args.skip_studies:
        return
    print("\n| landmark heat kernels (5 landmarks x 16 times) | spectrum-free | 200 eigenpairs |")
    print("|---|---|---|")
    for row in landmark_study(V, F):
        print("| " + " | ".join(row) + " |", flush=True)
    print("\n| descriptor, stretched pair x1.5 | own grids | common grid |")
    print("|---|---|---|")
    for row in grid_study(V, F):
        print("| " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
