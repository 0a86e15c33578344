"""Shape retrieval by global signatures: the heat trace and ShapeDNA, against LaPy's ShapeDNA.

A labelled set built from closed public models: each model (decimated to about 2000 vertices)
gives five variants, each rotated at random and scaled by 10^U(-2, 2):

    decimate      the model decimated to 4000 faces (libigl's ``decimate``)
    remesh        decimated to 3000 faces, then half the faces split at random points
                  (``data_generators.resample``)
    subdivide     decimated to 1200 faces, midpoint-subdivided once, 30% of the faces split
    gauss         the 4000-face mesh with Gaussian noise, sigma = 0.1 mean edge length
    normal        the 4000-face mesh, 30% of the faces split, normal noise of 0.2 mean edge length

Signatures, each compared by :func:`spectral_igl.shape_distance_matrix`:

    heat trace        ``sig.heat_trace`` on its default grid (31 times, 1e-3..1 x area),
                      spectrum-free, certified; and the same traces on the part of the grid
                      from 1e-2 x area (21 times)
    ShapeDNA (ours)   ``sig.shape_dna(lap, 50)``: certified eigenvalues x area
    ShapeDNA (LaPy)   LaPy's method: linear FEM (cotan stiffness, consistent mass), scipy
                      ``eigsh`` shift-invert at -0.01, 50 eigenvalues x area, reweighted by 1/i

and measured by leave-one-out nearest-neighbour accuracy and mean average precision (each
shape a query against all others; relevant: the other variants of its model).

    OPENBLAS_NUM_THREADS=1 python benchmarks/shape_retrieval.py [--meshes DIR] [--only NAME ...]
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
import scipy.sparse.linalg as spla
from scipy.stats import special_ortho_group

import spectral_igl as sig
from data_generators.perturb import gaussian_noise, mean_edge_length, midpoint_subdivide, normal_noise, resample
from spectral_igl.applications.compare import TRACE_TIMES
from spectral_igl.io import read_mesh

MODELS = ["spot.obj", "cow.obj", "homer.obj", "cheburashka.obj", "fertility.off", "rocker-arm.obj",
          "fandisk.obj", "armadillo.obj"]
K = 50


def decimated(V, F, faces):
    """libigl's edge-collapse decimation to at most ``faces`` faces (the mesh itself if smaller)."""
    if len(F) <= faces:
        return V, F
    out = igl.decimate(V, F, faces)
    U, G = (out[1], out[2]) if isinstance(out[0], (bool, np.bool_)) else (out[0], out[1])
    return np.asarray(U, float), np.asarray(G, np.int64)


def variants(V, F, seed):
    """The five (name, V, F) variants of one model."""
    rng = np.random.default_rng(seed)
    base = decimated(V, F, 4000)
    h = mean_edge_length(*base)
    out = [("decimate", *base)]
    out.append(("remesh", *resample(*decimated(V, F, 3000), 0.5, seed=seed)))
    out.append(("subdivide", *resample(*midpoint_subdivide(*decimated(V, F, 1200)), 0.3, seed=seed + 1)))
    out.append(("gauss", gaussian_noise(base[0], 0.1 * h, seed=seed + 2), base[1]))
    Vr, Fr = resample(*base, 0.3, seed=seed + 3)
    out.append(("normal", normal_noise(Vr, Fr, 0.2 * h, seed=seed + 4), Fr))
    shaped = []
    for name, W, G in out:
        R = special_ortho_group.rvs(3, random_state=rng)
        s = 10.0 ** rng.uniform(-2, 2)
        shaped.append((name, s * (W - W.mean(axis=0)) @ R.T, G))
    return shaped


def lapy_shape_dna(V, F, k):
    """LaPy's ShapeDNA: linear FEM eigenvalues (consistent mass) by shift-invert eigsh, x area."""
    A = (-igl.cotmatrix(V, F)).tocsc()
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL).tocsc()
    ev = np.sort(spla.eigsh(A, k, M, sigma=-0.01, which="LM")[0])
    return ev * M.sum()


def retrieval(D, labels):
    """(nearest-neighbour accuracy, mean average precision), each shape a query against the rest."""
    labels = np.asarray(labels)
    nn, aps = [], []
    for i in range(len(labels)):
        order = [j for j in np.argsort(D[i], kind="stable") if j != i]
        rel = labels[order] == labels[i]
        nn.append(rel[0])
        hits = np.cumsum(rel)
        aps.append(np.mean(hits[rel] / (np.nonzero(rel)[0] + 1)))
    return float(np.mean(nn)), float(np.mean(aps))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default="/work/shared/data/meshes")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--save", default=None, help="write the signatures and labels to this .npz")
    args = ap.parse_args(argv)
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, "
          f"{datetime.datetime.now().isoformat(timespec='minutes')}")
    print(f"# python {' '.join([Path(sys.argv[0]).as_posix()] + sys.argv[1:])}")
    names = args.only or MODELS
    labels, traces, bounds, ours, lapy = [], [], [], [], []
    cost = {"heat trace": 0.0, "ShapeDNA (ours)": 0.0, "ShapeDNA (LaPy)": 0.0}
    for m, name in enumerate(names):
        V, F = read_mesh(str(Path(args.meshes) / name))[:2]
        V, F = decimated(V, F, 20000)  # the source model itself at a modest size
        for kind, W, G in variants(V, F, seed=10 * m):
            lap = sig.laplacian(W, G)
            t0 = time.perf_counter()
            z, info = sig.heat_trace(lap, return_info=True)
            t1 = time.perf_counter()
            dna, dinfo = sig.shape_dna(lap, K, return_info=True)
            t2 = time.perf_counter()
            ref = lapy_shape_dna(W, G, K)
            t3 = time.perf_counter()
            cost["heat trace"] += t1 - t0
            cost["ShapeDNA (ours)"] += t2 - t1
            cost["ShapeDNA (LaPy)"] += t3 - t2
            labels.append(name)
            traces.append(z)
            bounds.append(float(np.max(info["abs_error"] / z)))
            ours.append(dna)
            lapy.append(ref)
            print(f"#   {name:16s} {kind:10s} n={lap.n:5d}  trace {t1 - t0:5.2f} s (rel. bound "
                  f"{bounds[-1]:.1e}, {info['bound_kind']})  dna {t2 - t1:5.2f} s ({dinfo['bound_kind']})"
                  f"  eigsh {t3 - t2:5.2f} s", flush=True)
    traces = np.array(traces)
    if args.save:
        np.savez(args.save, labels=labels, traces=traces, times=TRACE_TIMES, ours=ours, lapy=lapy)
    tail = TRACE_TIMES >= 1e-2 * (1 - 1e-12)
    rows = [("heat trace, 1e-3..1 x area (31)", sig.shape_distance_matrix(traces), cost["heat trace"]),
            ("heat trace, 1e-2..1 x area (21)", sig.shape_distance_matrix(traces[:, tail]), cost["heat trace"]),
            (f"ShapeDNA (ours, certified, k={K})", sig.shape_distance_matrix(ours, "shape_dna"),
             cost["ShapeDNA (ours)"]),
            (f"ShapeDNA (LaPy's method, eigsh, k={K})", sig.shape_distance_matrix(lapy, "shape_dna"),
             cost["ShapeDNA (LaPy)"])]
    print(f"\n{len(names)} models x 5 variants = {len(labels)} shapes; largest relative bound of a "
          f"heat-trace entry {max(bounds):.1e}\n")
    print(f"| {'signature':40s} | NN accuracy | mAP   | time (all shapes) |")
    print(f"|{'-' * 42}|-------------|-------|-------------------|")
    for label, D, secs in rows:
        acc, mAP = retrieval(D, labels)
        print(f"| {label:40s} | {acc:11.3f} | {mAP:.3f} | {secs:15.1f} s |")


if __name__ == "__main__":
    main()
