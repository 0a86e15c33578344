"""Shape retrieval by global signatures: the heat trace and ShapeDNA, against LaPy's ShapeDNA.

A labelled set of 24 classes, 5 shapes each. Sixteen classes are the public models of
``--meshes`` (``bunny.mesh`` by the boundary surface of its tetrahedra; ``stanford-bunny.obj``
is the same model and is left out so that no two classes are one shape; ``horse_quad`` read
as triangles; ``beetle``, ``suzanne`` and ``truck`` non-manifold, ``teapot``, ``truck``,
``suzanne`` several components, ``camel_b``, ``circle``, ``teapot`` with boundary), eight are
generated (sphere, ellipsoid, cigar, a thin and a fat torus, an open cylinder, two smooth
blobs). Each model, decimated to about 2000 vertices where libigl's ``decimate`` applies
(non-manifold meshes are kept as they are), gives five variants, each rotated at random and
scaled by 10^U(-2, 2):

    decimate      the model decimated to 4000 faces
    remesh        decimated to 3000 faces, then half the faces split at random points
                  (``data_generators.resample``: another connectivity, irregular)
    subdivide     decimated to 1200 faces, midpoint-subdivided once, 30% of the faces split
                  (resampling; meshes that cannot be decimated: 30% of the faces split)
    noise         the 4000-face mesh, 30% of the faces split, normal noise of 0.2 mean edge length
    bend          a near-isometric deformation of the 4000-face mesh (``data_generators.bend``):
                  the part beyond 60% of the principal axis turned by 30 degrees about the
                  second axis, the angle blended smoothly (smoothstep) over a band of half
                  the length; the output gives how much edge lengths and area change

Signatures, each compared by :func:`spectral_igl.shape_distance_matrix`:

    heat trace        ``sig.heat_trace`` on its default grid (``TRACE_TIMES``), spectrum-free,
                      certified; also shown on the part of the grid from 1e-2 x area, and
                      without the zero modes (``components=``: log(Z - b0) and log b0, b0 the
                      number of components) from 1e-2 to 0.3 x area
    ShapeDNA (ours)   ``sig.shape_dna((V, F), 50)``: certified eigenvalues x area, of the
                      finite-element Laplacian it builds from a mesh (cotan, consistent mass);
                      also of the default (lumped, intrinsic Delaunay) ``sig.laplacian``
    ShapeDNA (LaPy)   LaPy's ``compute_shapedna`` (linear FEM, consistent mass, eigsh
                      shift-invert) normalised by area (``normalize_ev(..., "geometry")``),
                      50 eigenvalues; without LaPy installed, the same computed here

timed in CPU seconds of this process (one BLAS thread; robust to other loads on the machine),
and measured by leave-one-out nearest-neighbour accuracy and mean average precision
(:func:`spectral_igl.retrieval_scores`; relevant: the other variants of its model).

    OPENBLAS_NUM_THREADS=1 python benchmarks/shape_retrieval.py [--meshes DIR] [--only NAME ...]
        [--json out.json] [--save signatures.npz]
"""
from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys
import time
from pathlib import Path

import igl
import numpy as np
import scipy.sparse.linalg as spla
from scipy.stats import special_ortho_group

import spectral_igl as sig
from data_generators import cylinder, icosphere, torus
from data_generators.perturb import bend, mean_edge_length, midpoint_subdivide, normal_noise, resample
from spectral_igl.applications.compare import TRACE_TIMES
from spectral_igl.io import read_mesh

MODELS = ["armadillo.obj", "beetle.obj", "bunny.mesh", "camel_b.obj", "cheburashka.obj", "circle.obj",
          "cow.obj", "fandisk.obj", "fertility.off", "homer.obj", "horse_quad.obj", "rocker-arm.obj",
          "spot.obj", "suzanne.obj", "teapot.obj", "truck.obj"]
GENERATED = ["sphere", "ellipsoid", "cigar", "thin-torus", "fat-torus", "open-cylinder", "blob-a", "blob-b"]
VARIANTS = ("decimate", "remesh", "subdivide", "noise", "bend")
K = 50


def compact(V, F):
    """``(V, F)`` without unreferenced vertices, as float and int64 arrays."""
    F = np.asarray(F, np.int64)
    used = np.unique(F)
    index = np.full(len(V), -1, np.int64)
    index[used] = np.arange(used.size)
    return np.asarray(V, float)[used], index[F]


def decimated(V, F, faces):
    """libigl's edge-collapse decimation to at most ``faces`` faces; the mesh itself when it is
    smaller or cannot be decimated (non-manifold)."""
    if len(F) <= faces:
        return V, F
    try:
        out = igl.decimate(V, F, faces)
    except Exception:  # noqa: BLE001 - libigl refuses non-manifold input in several ways
        return V, F
    ok = not isinstance(out[0], (bool, np.bool_)) or bool(out[0])
    U, G = (out[1], out[2]) if isinstance(out[0], (bool, np.bool_)) else (out[0], out[1])
    if not ok or len(G) == 0:
        return V, F
    return compact(U, G)


def blob(seed):
    """A smooth genus-0 blob: an icosphere with four random Gaussian bumps and dents."""
    V, F = icosphere(5)
    rng = np.random.default_rng(seed)
    r = np.ones(len(V))
    for c in rng.normal(size=(4, 3)):
        c /= np.linalg.norm(c)
        r += rng.uniform(-0.3, 0.5) * np.exp(-np.sum((V - c) ** 2, axis=1) / 0.3)
    return V * r[:, None], F


def generated(name):
    """A generated model at about 10000 vertices (decimated like the files)."""
    if name == "sphere":
        return icosphere(5)
    if name in ("ellipsoid", "cigar"):
        V, F = icosphere(5)
        return V * ([1.0, 0.7, 0.5] if name == "ellipsoid" else [1.0, 0.35, 0.35]), F
    if name == "thin-torus":
        return torus(1.0, 0.3, 160, 60)
    if name == "fat-torus":
        return torus(1.0, 0.6, 120, 80)
    if name == "open-cylinder":
        return cylinder(0.5, 2.0, 100, 100)
    return blob(1 if name == "blob-a" else 2)


def load_model(name, meshes):
    """The source model ``(V, F)`` of a class, at most 20000 faces."""
    if name in GENERATED:
        V, F = generated(name)
    else:
        V, F = read_mesh(str(Path(meshes) / name))[:2]
        F = np.asarray(F, np.int64)
        if F.shape[1] == 4:     # a tetrahedral mesh: its boundary surface
            B = igl.boundary_facets(F)
            F = np.asarray(B[0] if isinstance(B, tuple) else B, np.int64)
    V, F = compact(V, F)
    return decimated(V, F, 20000)


def distortion(V, W, F):
    """How far ``W`` is from an isometry of ``V``: (mean |dl|/l, max |dl|/l) over the edges, |dA|/A."""
    E = np.unique(np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1), axis=0)
    l0 = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    l1 = np.linalg.norm(W[E[:, 0]] - W[E[:, 1]], axis=1)
    rel = np.abs(l1 - l0) / np.maximum(l0, 1e-300)
    A0, A1 = igl.doublearea(V, F).sum(), igl.doublearea(W, F).sum()
    return float(rel.mean()), float(rel.max()), float(abs(A1 - A0) / A0)


def variants(V, F, seed):
    """The five (name, V, F) variants of one model, and the bending's distortion."""
    rng = np.random.default_rng(seed)
    base = decimated(V, F, 4000)
    h = mean_edge_length(*base)
    out = [("decimate", *base)]
    out.append(("remesh", *resample(*decimated(V, F, 3000), 0.5, seed=seed)))
    coarse = decimated(V, F, 1200)
    fine = midpoint_subdivide(*coarse) if len(coarse[1]) <= 1200 else coarse
    out.append(("subdivide", *resample(*fine, 0.3, seed=seed + 1)))
    Vr, Fr = resample(*base, 0.3, seed=seed + 3)
    out.append(("noise", normal_noise(Vr, Fr, 0.2 * h, seed=seed + 4), Fr))
    Vb = bend(base[0], np.pi / 6, at=0.6, band=0.5)
    out.append(("bend", Vb, base[1]))
    shaped = []
    for name, W, G in out:
        R = special_ortho_group.rvs(3, random_state=rng)
        s = 10.0 ** rng.uniform(-2, 2)
        shaped.append((name, s * (W - W.mean(axis=0)) @ R.T, np.asarray(G, np.int64)))
    return shaped, distortion(base[0], Vb, base[1])


def lapy_shape_dna(V, F, k):
    """LaPy's ShapeDNA of a triangle mesh, area-normalised (the real LaPy when installed)."""
    try:
        from lapy import TriaMesh
        from lapy.shapedna import compute_shapedna, normalize_ev
    except ImportError:
        A = (-igl.cotmatrix(V, F)).tocsc()
        M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL).tocsc()
        ev = np.sort(spla.eigsh(A, k, M, sigma=-0.01, which="LM")[0])
        return ev * M.sum(), "re-implementation (LaPy not installed)"
    import lapy

    mesh = TriaMesh(V, F)
    ev = compute_shapedna(mesh, k)["Eigenvalues"]
    return np.asarray(normalize_ev(mesh, ev, "geometry"), float), f"lapy {lapy.__version__}"


def separation_by_time(traces, labels):
    """Per time of the grid: the spread of log Z between the class means over its spread within
    the classes (root mean square of the within-class standard deviations). Where it is small,
    a time adds mostly what varies inside a class (resolution, noise) to the distance."""
    L, labels = np.log(traces), np.asarray(labels)
    classes = np.unique(labels)
    within = np.sqrt(np.mean([L[labels == c].var(axis=0) for c in classes], axis=0))
    between = np.std([L[labels == c].mean(axis=0) for c in classes], axis=0)
    return between / within


def header():
    """Machine, date and command of this run."""
    return {"machine": f"{platform.node()} {platform.processor() or platform.machine()}",
            "date": datetime.datetime.now().isoformat(timespec="minutes"),
            "command": "OPENBLAS_NUM_THREADS=1 python " + " ".join([Path(sys.argv[0]).as_posix()] + sys.argv[1:])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default="/work/shared/data/meshes")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--save", default=None, help="write the signatures and labels to this .npz")
    ap.add_argument("--json", default=None, help="write the table and the run's facts to this .json")
    args = ap.parse_args(argv)
    head = header()
    print(f"# {head['machine']}, {head['date']}\n# {head['command']}")
    names = args.only or MODELS + GENERATED
    labels, kinds, traces, bounds, ours, lapy, sizes, distortions = [], [], [], [], [], [], [], {}
    components = []
    cost = {"heat trace": 0.0, "ShapeDNA (ours)": 0.0, "ShapeDNA (lumped)": 0.0, "ShapeDNA (LaPy)": 0.0}
    lumped = []
    lapy_kind = None
    for m, name in enumerate(names):
        V, F = load_model(name, args.meshes)
        shaped, distortions[name] = variants(V, F, seed=10 * m)
        print(f"# {name}: bend changes edge lengths by {100 * distortions[name][0]:.1f}% on average "
              f"({100 * distortions[name][1]:.0f}% at most), the area by {100 * distortions[name][2]:.2f}%")
        for kind, W, G in shaped:
            lap = sig.laplacian(W, G)
            t0 = time.process_time()
            z, info = sig.heat_trace(lap, return_info=True)
            t1 = time.process_time()
            dna, dinfo = sig.shape_dna((W, G), K, return_info=True)
            t2 = time.process_time()
            ref, lapy_kind = lapy_shape_dna(W, G, K)
            t3 = time.process_time()
            lumped.append(sig.shape_dna(lap, K))
            cost["heat trace"] += t1 - t0
            cost["ShapeDNA (ours)"] += t2 - t1
            cost["ShapeDNA (LaPy)"] += t3 - t2
            cost["ShapeDNA (lumped)"] += time.process_time() - t3
            labels.append(name)
            kinds.append(kind)
            sizes.append(lap.n)
            components.append(lap.n_components)
            traces.append(z)
            bounds.append(float(np.max(info["abs_error"] / z)))
            ours.append(dna)
            lapy.append(ref)
            print(f"#   {name:16s} {kind:10s} n={lap.n:5d}  trace {t1 - t0:5.2f} s (rel. bound "
                  f"{bounds[-1]:.1e}, {info['bound_kind']})  dna {t2 - t1:5.2f} s ({dinfo['bound_kind']})"
                  f"  LaPy {t3 - t2:5.2f} s", flush=True)
    traces = np.array(traces)
    if args.save:
        np.savez(args.save, labels=labels, kinds=kinds, traces=traces, times=TRACE_TIMES, ours=ours,
                 lapy=lapy, components=components)
    tail = TRACE_TIMES >= 1e-2 * (1 - 1e-12)
    # where every mesh resolves the kernel and every nonzero mode is still far above the bounds
    mid = tail & (TRACE_TIMES <= 0.3 * (1 + 1e-12))
    m = len(labels)
    rows = [(f"heat trace, {TRACE_TIMES[0]:.0e}..{TRACE_TIMES[-1]:.0f} x area ({TRACE_TIMES.size})",
             sig.shape_distance_matrix(traces), cost["heat trace"]),
            (f"heat trace, 1e-2..{TRACE_TIMES[-1]:.0f} x area ({int(tail.sum())})",
             sig.shape_distance_matrix(traces[:, tail]), cost["heat trace"]),
            (f"heat trace, log(Z - b0), 1e-2..0.3 x area ({int(mid.sum())})",
             sig.shape_distance_matrix(traces[:, mid], components=np.array(components)), cost["heat trace"]),
            (f"ShapeDNA (ours, certified, k={K}, from the mesh)", sig.shape_distance_matrix(ours, "shape_dna"),
             cost["ShapeDNA (ours)"]),
            (f"ShapeDNA (ours, k={K}, default sig.laplacian)", sig.shape_distance_matrix(lumped, "shape_dna"),
             cost["ShapeDNA (lumped)"]),
            (f"ShapeDNA (LaPy, eigsh, k={K})", sig.shape_distance_matrix(lapy, "shape_dna"),
             cost["ShapeDNA (LaPy)"])]
    print(f"\n{len(names)} classes x {len(VARIANTS)} variants = {m} shapes ({min(sizes)}..{max(sizes)} "
          f"vertices); LaPy: {lapy_kind}; largest relative bound of a heat-trace entry {max(bounds):.1e}\n")
    print(f"| {'signature':46s} | NN accuracy | mAP   | time per shape |")
    print(f"|{'-' * 48}|-------------|-------|----------------|")
    table = []
    for label, D, secs in rows:
        acc, mAP = sig.retrieval_scores(D, labels)
        table.append({"signature": label, "nn_accuracy": acc, "map": mAP, "seconds_per_shape": secs / m})
        print(f"| {label:46s} | {acc:11.3f} | {mAP:.3f} | {secs / m:12.2f} s |")
    ratio = separation_by_time(traces, labels)
    print("\nheat trace, between-class / within-class spread of log Z per time (x area):")
    print("  " + "  ".join(f"{t:.0e}:{r:.1f}" for t, r in zip(TRACE_TIMES[::3], ratio[::3])))
    if args.json:
        doc = dict(head, classes=len(names), variants=list(VARIANTS), shapes=m, lapy=lapy_kind,
                   vertices=[min(sizes), max(sizes)], largest_relative_trace_bound=max(bounds),
                   bend_distortion={k: {"mean_edge": v[0], "max_edge": v[1], "area": v[2]}
                                    for k, v in distortions.items()},
                   separation_by_time=dict(zip([float(t) for t in TRACE_TIMES], map(float, ratio))),
                   table=table)
        Path(args.json).write_text(json.dumps(doc, indent=1))


if __name__ == "__main__":
    main()
