"""Hostile-input cases for ``test_fuzz.py`` and the worker process that runs them.

A case is JSON: a function name and keyword arguments written as *specs* that the worker
turns into objects (``{"lap": "small"}`` is a Laplacian of icosphere(2), ``{"signal":
"nan"}`` a signal with a NaN, ...). The worker (:func:`serve`) reads one case per line on
stdin and answers one JSON line: ``ok`` (a finite result), ``refused`` (ValueError or
TypeError, with its message) or ``bad`` (another exception, or NaN/inf in the result). A
crash or a hang shows up in the parent as a dead or silent worker.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
import traceback
import warnings

NAN, INF = float("nan"), float("inf")

# ---- hostile value pools, by kind of parameter ----------------------------------------------
POOLS = {
    "lap": [None, "lap", 3, {"mesh": "small"}, {"arr": [4, 4]}, {"lap": "medium"}, {"lap": "tet"},
            {"lap": "graph"}, {"lap": "unref"}],
    "int": [0, -1, 1, 2, 7, 10 ** 6, 10 ** 12, 2 ** 63, -2 ** 63, 2.5, 1.0, "5", None, True, NAN, INF, [3]],
    "pos": [0.0, -1.0, NAN, INF, -INF, 1e308, 1e-308, 5e-324, 1e-300, 1e300, 1e6, "1", None, True, [1.0]],
    "tol": [0.0, -1.0, NAN, INF, 1.0, 2.0, 0.5, 1e-300, 5e-324, "1e-8", None, True],
    "choice": ["", "foo", None, 5, "AUTO", " auto", ["auto"], "dense", "eigen", "rational", "selinv",
               "probing", "exact", "chebyshev", "contour", "euler", "krylov", "power", "taylor",
               "pypardiso", "cholespy", "superlu", "ldlt"],
    "index": [-1, "n", 10 ** 12, 1.5, "0", None, [], [[0]], True, NAN, 0, 5],
    "indices": [[], [-1], ["n"], [0, 0], [[0, 1]], "0", None, 10 ** 12, [1.5], {"all": True}, [0], [0, 5, 9]],
    "signal": [{"signal": k} for k in ("bumps", "cols0", "nan", "inf", "big", "tiny", "wrong_len", "3d", "complex",
                                        "empty", "int", "bool", "zeros", "ones", "str", "obj", "cols3",
                                        "scalar", "sparse")] + [None, "f", 1.0],
    "filter": [{"filter": k} for k in ("nan_fn", "inv_fn", "shape_fn", "raise_fn", "str_fn", "heat_huge",
                                        "wave_huge", "heat_tiny", "heat", "biharmonic", "wave",
                                        "poly_big", "mexican")] + [None, "heat", 3],
    # a yes/no option is True or False: every value here must be refused (see MUST_REFUSE)
    "bool": [None, "yes", "no", "False", 2, NAN, 0, 1, 0.0, [True]],
    "lap2": [None, {"lap": "two"}, {"lap": "small"}, {"lap": "unref"}],
    "values": [[1e308, -1e308], [1e101, 0.0], [NAN, 0.0], [INF, 1.0], [0.0], [[0.0, 1.0]], "x", None,
               [1e99, -1e99], [0.0, 1.0]],
    "matrix": [{"matrix": k} for k in ("L_complex", "B_asym", "B_complex", "L_dense", "str", "B_rounded")]
              + [None, 3],
    "mask": [{"mask": k} for k in ("huge", "huge_int", "ok", "empty", "float", "flat")] + [None, "m"],
    "cloud": [{"V": k} for k in ("nan", "huge", "tiny", "flat", "cols2", "empty", "str", "dup", "list")] + [None],
    "store": [{"store": k} for k in ("deleted_chunk", "truncated_meta", "zeroed_chunk", "extra_array",
                                      "missing_array", "empty_meta", "ok")],
    "V": [{"V": k} for k in ("nan", "huge", "tiny", "flat", "cols4", "cols2", "empty", "str", "int",
                              "unref_end", "unref_start", "unref_mid", "dup", "list")] + [None],
    "V_tet": [{"V": k} for k in ("nan", "huge", "tiny", "flat", "cols4", "cols2", "empty", "str", "int",
                                  "unref_end", "list")] + [None],
    "F": [{"F": k} for k in ("oob", "neg", "frac", "cols2", "quads", "empty", "dup", "degenerate",
                              "float_int", "str", "one", "huge_index")] + [None],
    "times": [[], [NAN], 1e308, [-1.0], "x", [[1.0]], {"range": 5000}, 0.0, -1e300, [1e-300], [1e300],
              [0.01, 0.1], 0.1, [1e6]],
    "path": [{"path": k} for k in ("missing", "dir", "trunc_obj", "huge_off", "bad_off", "empty_obj",
                                    "binary_junk", "bad_ext", "neg_obj", "ply_huge", "stl_huge", "ok_obj",
                                    "wrapped_off", "comment_off", "random_obj", "random_off", "garbage_obj",
                                    "continued_obj", "binary_off", "4d_off", "colour_off")]
            + [None, 3],
}


#: kinds whose every pool value is invalid: a drawn value must be refused, not taken
MUST_REFUSE = ("bool",)

# ---- the public functions, each with its parameters: (name, kind, valid spec) ------------------
LAP = ("lap", "lap", {"lap": "small"})
FILT = ("filt", "filter", {"filter": "heat"})
SRC = ("source", "index", 0)
SIG = ("f", "signal", {"signal": "randn"})
METHOD = ("method", "choice", "auto")
TOL = ("tol", "tol", 1e-8)

FUNCTIONS = {
    "laplacian": [("V", "V", {"V": "ok"}), ("F", "F", {"F": "ok"}), ("weights", "choice", "cotan"),
                  ("mass", "choice", "full")],
    "anisotropic_laplacian": [("V", "V", {"V": "ok"}), ("F", "F", {"F": "ok"}), ("alpha", "pos", 10.0),
                              ("mass", "choice", "full")],
    "point_cloud_laplacian": [("P", "cloud", {"V": "ok"}), ("k", "int", 12), ("method", "choice", "belkin"),
                              ("boundary", "choice", None)],
    "voxel_laplacian": [("mask", "mask", {"mask": "ok"}), ("spacing", "pos", 1.0)],
    "graph_laplacian": [("n", "int", 4), ("edges", "F", {"edges": "ok"}), ("weights", "signal", None)],
    "make_laplacian": [("L", "matrix", {"matrix": "L"}), ("B", "matrix", {"matrix": "B"})],
    # V_tet: fTetWild does not return on the self-intersecting surfaces that moving a few
    # vertices of the sphere makes (unref_start, unref_mid); tetrahedralize ends those with
    # a ValueError after its timeout (600 s by default, tested with 3 s in
    # test_laplacian_tetrahedralize.py), longer than a fuzz case may take
    "tetrahedralize": [("V", "V_tet", {"V": "ok"}), ("F", "F", {"F": "ok"}), ("edge_length_fac", "pos", 0.2)],
    "lambda_max": [LAP],
    "lambda_min_positive": [LAP],
    "eigs": [LAP, ("k", "int", 5), ("tol", "tol", 0.0), ("backend", "choice", "auto"),
             ("return_info", "bool", False)],
    "dense_eigs": [LAP, ("k", "int", 5), ("max_n", "int", 8000)],
    "apply_filter": [LAP, FILT, SIG, METHOD, TOL],
    "SpectralOperator.apply": [LAP, FILT, METHOD, TOL, ("x", "signal", {"signal": "randn"}),
                               ("k", "int", None), ("degree", "int", None), ("steps", "int", None),
                               ("nodes", "int", None)],
    "spectral_operator": [LAP, FILT, METHOD, TOL],
    "spectral_kernel": [LAP, FILT, ("sources", "indices", [0, 3]), ("delta", "choice", "mass"), METHOD, TOL],
    "heat_kernel": [LAP, ("t", "pos", 0.1), ("sources", "indices", 0), METHOD, TOL],
    "kernels.heat_kernels": [LAP, ("times", "times", [0.01, 0.1]), ("sources", "indices", [0, 3]), TOL,
                             ("return_bound", "bool", False), ("return_info", "bool", False)],
    "kernel_diagonal": [LAP, FILT, ("method", "choice", "auto"), ("k", "int", None),
                        ("distance", "int", None), ("samples", "int", 16), ("rtol", "tol", 1e-4),
                        ("max_colours", "int", None), TOL, ("engine_method", "choice", "auto"),
                        ("return_info", "bool", False)],
    "distance_colouring": [LAP, ("distance", "int", 2), ("order", "choice", "bfs")],
    "spectral_distance": [LAP, FILT, SRC, ("targets", "indices", None), METHOD, TOL,
                          ("diagonal", "choice", "auto"), ("k", "int", None), ("samples", "int", 16),
                          ("max_recompute", "int", None), ("delta", "choice", "mass")],
    "OneToAll.distance": [LAP, FILT, SRC, ("diagonal", "choice", "auto")],
    "pairwise_spectral_distance": [LAP, FILT, ("seeds", "indices", [0, 4, 9]), METHOD, TOL],
    "diffusion_distance": [LAP, ("t", "pos", 0.1), SRC, ("targets", "indices", None)],
    "commute_time_distance": [LAP, SRC, ("targets", "indices", [1, 2])],
    "biharmonic_distance": [LAP, SRC, ("targets", "indices", None)],
    "polyharmonic_distance": [LAP, ("k", "int", 3), SRC],
    "wave_distance": [LAP, ("t", "pos", 0.1), SRC, ("targets", "indices", [3])],
    "mexican_hat_distance": [LAP, ("t", "pos", 0.1), SRC],
    "spectral_descriptor": [LAP, FILT, ("method", "choice", "auto")],
    "hks": [LAP, ("times", "times", [0.01, 0.1]), ("method", "choice", "auto"),
            ("return_info", "bool", False)],
    "wks": [LAP, ("energies", "times", [1.0, 2.0, 3.0]), ("sigma", "pos", None), ("k", "int", 20),
            ("method", "choice", "eigen"), ("return_info", "bool", False)],
    "auto_diffusion_function": [LAP, ("t", "times", 0.5), ("method", "choice", "auto")],
    "eccentricity": [LAP, FILT, ("method", "choice", "auto")],
    "spectral_embedding": [LAP, FILT, ("k", "int", 5)],
    "critical_points": [("V", "V", {"V": "ok"}), ("F", "F", {"F": "ok"}), ("f", "signal", {"signal": "randn"})],
    "harmonic": [LAP, ("fixed", "indices", [0, 5]), ("values", "values", [0.0, 1.0]), ("k", "int", 1)],
    "smooth": [LAP, SIG, ("eps", "pos", 1.0)],
    "smooth_constrained": [LAP, SIG, ("fixed", "indices", [0, 5]), ("eps", "pos", 0.0)],
    "diffusion_smooth": [LAP, SIG, ("t", "pos", 0.01), METHOD, TOL],
    "optimal_time": [LAP, SIG, ("ts", "times", None), ("n_times", "int", 12), ("rule", "choice", "risk"),
                     ("probes", "int", 4), METHOD, TOL],
    "geodesic_distance": [("lap_or_mesh", "lap", {"lap": "small"}), SRC, ("method", "choice", "heat"),
                          ("t", "pos", None), ("step", "choice", "intrinsic_delaunay")],
    "varadhan_distance": [("lap_or_mesh", "lap", {"lap": "small"}), SRC, ("t", "pos", None),
                          ("normalize", "bool", True),
                          ("steps", "int", 64)],
    "wasserstein_distance": [("lap", "lap2", {"lap": "small"}), ("mu0", "signal", {"signal": "bump0"}),
                             ("mu1", "signal", {"signal": "bump1"}), ("gamma", "pos", 0.05),
                             ("max_iter", "int", 200), ("tol", "tol", 1e-6), ("steps", "int", 16),
                             ("return_info", "bool", False)],
    "wasserstein_barycenter": [("lap", "lap2", {"lap": "small"}), ("mus", "signal", {"signal": "bumps"}),
                               ("gamma", "pos", 0.05), ("max_iter", "int", 200), ("tol", "tol", 1e-5),
                               ("steps", "int", 8), ("return_info", "bool", False)],
    "polygon_laplacian": [("V", "V", {"V": "ok"}), ("faces", "F", {"F": "ok"}), ("mass", "choice", "full")],
    "pairwise_diffusion_distance": [LAP, ("t", "pos", 0.1), ("seeds", "indices", [0, 4, 9])],
    "pairwise_biharmonic_distance": [LAP, ("seeds", "indices", [0, 4, 9])],
    "pairwise_polyharmonic_distance": [LAP, ("k", "int", 3), ("seeds", "indices", [0, 4, 9])],
    "mean_curvature_flow": [("V", "V", {"V": "ok"}), ("F", "F", {"F": "ok"}), ("dt", "pos", 1e-3),
                            ("steps", "int", 3), ("mass", "choice", "lumped"), ("conformal", "bool", True),
                            ("normalize", "bool", True), ("history", "bool", False)],
    "diffusion_basis": [LAP, ("t", "pos", 0.05), ("centers", "indices", [0, 7]), METHOD, TOL],
    "feature_points": [LAP, ("n_eigenfunctions", "int", 4), ("t", "pos", 0.1),
                       ("source", "choice", "eigenfunctions"), ("persistence", "pos", 0.25)],
    "schrodinger": [LAP, ("h", "signal", {"signal": "randn"}), ("t", "pos", 0.1), METHOD, TOL],
    "schrodinger@0": [LAP, ("h", "signal", {"signal": "randn"}), ("t", "pos", 0.0), METHOD, TOL],
    "linalg.pseudo_solve": [LAP, ("g", "signal", {"signal": "randn"}), ("backend", "choice", "auto")],
    "linalg.mass_solve": [LAP, ("g", "signal", {"signal": "randn"}), ("backend", "choice", "auto")],
    "linalg.shifted_factor": [LAP, ("beta", "pos", 0.1), ("theta", "pos", 1.0), ("backend", "choice", "auto"),
                              ("keep", "bool", True)],
    "linalg.cached_eigs": [LAP, ("k", "int", 5)],
    "filters.heat": [("t", "pos", 0.1)],
    "filters.wave": [("t", "pos", 0.1)],
    "filters.polyharmonic": [("k", "int", 3)],
    "filters.mexican_hat": [("t", "pos", 0.1)],
    "filters.multiscale": [("t", "pos", 0.1), ("k", "int", 2), ("alpha", "pos", 1.0)],
    "filters.by_name": [("name", "choice", "heat"), ("t", "pos", 0.1), ("order", "int", 3)],
    "io.read_mesh": [("path", "path", {"path": "ok_obj"}), ("polygons", "bool", False)],
    "io.check_mesh_file": [("path", "path", {"path": "ok_obj"})],
    "collection.load": [("out", "store", {"store": "ok"})],
    "dg.icosphere": [("level", "int", 1), ("radius", "pos", 1.0)],
    "dg.torus": [("R", "pos", 1.0), ("r", "pos", 0.4), ("n_major", "int", 8), ("n_minor", "int", 4)],
    "dg.uv_sphere": [("n_lat", "int", 6), ("n_lon", "int", 8), ("radius", "pos", 1.0)],
    "dg.cylinder": [("radius", "pos", 1.0), ("height", "pos", 2.0), ("n_theta", "int", 8), ("n_z", "int", 4)],
    "dg.box_tets": [("shape", "times", [3, 3, 3]), ("size", "times", [1.0, 1.0, 1.0])],
    "dg.sphere_points": [("n", "int", 50), ("seed", "int", 0), ("nonuniform", "pos", 0.0)],
    "dg.flat_torus": [("a", "pos", 1.0), ("b", "pos", 1.0), ("nu", "int", 8), ("nv", "int", 8)],
    "dg.sphere_eigenvalues": [("k", "int", 10)],
    "dg.box_voxels": [("shape", "times", [4, 3, 3])],
    "cli": [("job", "choice", "distance"), ("mesh", "path", {"path": "ok_obj"}), ("out", "path", None),
            ("tol", "tol", 1e-8), ("source", "index", 0), ("time", "pos", None)],
}

#: functions that return inf, meaning unreachable, on components without a source
GEODESIC = ("geodesic_distance", "varadhan_distance")

#: generators that take no Laplacian, called by their plain name from ``data_generators``
GENERATORS = [n for n in FUNCTIONS if n.startswith("dg.")]


# ---- the worker --------------------------------------------------------------------------------
class _Build:
    """Turns specs into objects; the fixtures are built once per worker."""

    def __init__(self):
        import numpy as np

        import spectral_igl as sig
        from data_generators import box_tets, icosphere

        self.np, self.sig = np, sig
        self.V, self.F = icosphere(2)
        V3, F3 = icosphere(3)
        Vt, Tt = box_tets((3, 3, 3))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            Vu = np.vstack([self.V, np.ones((2, 3))])
            self.laps = {"small": sig.laplacian(self.V, self.F), "medium": sig.laplacian(V3, F3),
                         "tet": sig.laplacian(Vt, Tt),
                         "graph": sig.graph_laplacian(6, [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 0]]),
                         "unref": sig.laplacian(Vu, self.F, mass="lumped"),
                         "two": sig.laplacian(np.r_[self.V, self.V + 3.0], np.r_[self.F, self.F + len(self.V)])}
        self.laps["full"] = sig.laplacian(self.V, self.F, mass="full")
        self.tmp = tempfile.mkdtemp(prefix="sig_fuzz_")
        self.lap = self.laps["small"]

    def n(self):
        return self.lap.n

    def __call__(self, spec):
        np = self.np
        if isinstance(spec, list):
            return [self(s) for s in spec]
        if spec == "n":
            return self.n()
        if not isinstance(spec, dict):
            return spec
        (key, val), = spec.items()
        n = self.n()
        rng = np.random.default_rng(0)
        if key == "lap":
            return self.laps[val]
        if key == "mesh":
            return (self.V, self.F)
        if key == "arr":
            return np.zeros(val)
        if key == "all":
            return np.arange(n)
        if key == "range":
            return list(np.linspace(0.01, 1.0, val))
        if key == "signal":
            return {"randn": lambda: rng.standard_normal(n), "cols0": lambda: np.zeros((n, 0)),
                    "nan": lambda: np.r_[np.nan, np.ones(n - 1)], "inf": lambda: np.r_[np.inf, np.ones(n - 1)],
                    "big": lambda: np.full(n, 1e307), "tiny": lambda: np.full(n, 5e-324),
                    "wrong_len": lambda: np.ones(n + 1), "3d": lambda: np.ones((n, 2, 2)),
                    "complex": lambda: np.ones(n) * (1 + 1j), "empty": lambda: np.zeros(0),
                    "int": lambda: np.arange(n), "bool": lambda: np.ones(n, bool), "zeros": lambda: np.zeros(n),
                    "ones": lambda: np.ones(n), "str": lambda: "signal", "obj": lambda: np.array([None] * n),
                    "cols3": lambda: rng.standard_normal((n, 3)), "scalar": lambda: np.float64(1.0),
                    "sparse": lambda: __import__("scipy.sparse").sparse.eye(n).tocsr(),
                    "bump0": lambda: np.r_[np.ones(5), np.zeros(n - 5)],
                    "bump1": lambda: np.r_[np.zeros(n - 5), np.ones(5)],
                    "bumps": lambda: np.c_[np.r_[np.ones(5), np.zeros(n - 5)], np.r_[np.zeros(n - 5), np.ones(5)]]}[val]()
        if key == "mask":
            return {"ok": lambda: np.ones((3, 3, 3), bool),
                    "huge": lambda: np.broadcast_to(True, (3000, 3000, 3000)),
                    "huge_int": lambda: np.broadcast_to(np.int8(1), (2000, 2000, 2000)),
                    "empty": lambda: np.zeros((3, 3, 3), bool), "float": lambda: np.ones((3, 3, 3)) * 0.5,
                    "flat": lambda: np.ones((4, 4), bool)}[val]()
        if key == "matrix":
            import scipy.sparse as sparse

            full = self.laps["full"]
            return {"L": lambda: self.lap.L, "B": lambda: self.lap.B,
                    "L_complex": lambda: self.lap.L * (1 + 1j), "B_complex": lambda: self.lap.B.astype(complex),
                    "B_asym": lambda: full.B + 1e-3 * sparse.triu(full.B, 1),
                    "B_rounded": lambda: full.B + 1e-14 * sparse.triu(full.B, 1),
                    "L_dense": lambda: self.lap.L.toarray(), "str": lambda: "L"}[val]()
        if key == "store":
            return self._store(val)
        if key == "edges":
            return np.array([[0, 1], [1, 2], [2, 3]])
        if key == "filter":
            f = self.sig.filters
            return {"nan_fn": lambda: (lambda s: s * np.nan), "inv_fn": lambda: (lambda s: 1.0 / s),
                    "shape_fn": lambda: (lambda s: np.ones(3)), "raise_fn": lambda: (lambda s: 1 / 0),
                    "str_fn": lambda: (lambda s: "x"), "heat_huge": lambda: f.heat(1e300),
                    "wave_huge": lambda: f.wave(1e300), "heat_tiny": lambda: f.heat(1e-300),
                    "heat": lambda: f.heat(0.1), "biharmonic": lambda: f.biharmonic(),
                    "wave": lambda: f.wave(0.1), "poly_big": lambda: f.polyharmonic(400),
                    "mexican": lambda: f.mexican_hat(0.1)}[val]()
        if key == "V":
            V = self.V
            return {"ok": lambda: V, "nan": lambda: np.r_[V[:-1], [[np.nan, 0, 0]]], "huge": lambda: V * 1e200,
                    "tiny": lambda: V * 1e-200, "flat": lambda: np.c_[V[:, :2], np.zeros(len(V))],
                    "cols4": lambda: np.c_[V, V[:, :1]], "cols2": lambda: V[:, :2], "empty": lambda: V[:0],
                    "str": lambda: "V", "int": lambda: (V * 10).astype(int),
                    "unref_end": lambda: np.r_[V, np.ones((3, 3))],
                    "unref_start": lambda: np.r_[np.ones((3, 3)), V],
                    "unref_mid": lambda: np.r_[V[:5], np.ones((3, 3)), V[5:]],
                    "dup": lambda: np.r_[V, V], "list": lambda: V.tolist()}[val]()
        if key == "F":
            F = self.F
            return {"ok": lambda: F, "oob": lambda: np.r_[F, [[0, 1, 10 ** 6]]], "neg": lambda: np.r_[F, [[0, 1, -1]]],
                    "frac": lambda: F + 0.5, "cols2": lambda: F[:, :2], "quads": lambda: np.c_[F, F[:, :1]],
                    "empty": lambda: F[:0], "dup": lambda: np.r_[F, F], "degenerate": lambda: np.c_[F[:, :2], F[:, :1]],
                    "float_int": lambda: F.astype(float), "str": lambda: "F", "one": lambda: F[:1],
                    "huge_index": lambda: np.r_[F, [[0, 1, 2 ** 62]]]}[val]()
        if key == "path":
            return self._file(val)
        raise KeyError(key)

    def _file(self, kind):
        d = self.tmp
        write = {"trunc_obj": ("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3\n"),
                 "huge_off": ("h.off", "OFF\n1000000000 1 0\n0 0 0\n"),
                 "bad_off": ("b.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
                 "empty_obj": ("e.obj", ""), "binary_junk": ("j.obj", "\x00\x01\xff" * 50),
                 "bad_ext": ("x.xyz", "0 0 0\n"), "neg_obj": ("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9\n"),
                 "ply_huge": ("p.ply", "ply\nformat ascii 1.0\nelement vertex 999999999999\nproperty float x\n"
                                       "end_header\n0\n"),
                 "stl_huge": ("s.stl", None),
                 "ok_obj": ("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"),
                 "wrapped_off": ("w.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3\n0 1 2\n3 0 1\n 3\n"
                                          "3 0 2 3\n3\n1\n2\n3\n"),
                 "comment_off": ("c.off", "OFF # header\n4 2 0 # counts\n0 0 0 # v\n1 0 0\n1 1 0\n0 1 0\n"
                                          "3 0 1 2 # f\n3 0 2 3\n"),
                 "colour_off": ("k.off", "COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n0 1 0 1 0 0 1\n3 0 1 2 9 9 9\n"),
                 "4d_off": ("d.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n"),
                 "binary_off": ("b2.off", "OFF BINARY\n3 1 0\n"),
                 "garbage_obj": ("g.obj", "hello world\nthis is not a mesh\n" * 20),
                 "continued_obj": ("cc.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\n"),
                 "random_obj": ("r.obj", os.urandom(3000)), "random_off": ("r.off", os.urandom(3000))}
        if kind == "missing":
            return os.path.join(d, "missing.obj")
        if kind == "dir":
            p = os.path.join(d, "adir.obj")
            os.makedirs(p, exist_ok=True)
            return p
        name, text = write[kind]
        p = os.path.join(d, name)
        if isinstance(text, bytes):
            with open(p, "wb") as fh:
                fh.write(text)
        elif text is None:
            with open(p, "wb") as fh:
                fh.write(b"\0" * 80 + (10 ** 9).to_bytes(4, "little"))
        else:
            with open(p, "w", encoding="latin-1") as fh:
                fh.write(text)
        return p


    def _store(self, fault):
        """A store with two groups of known arrays, the first damaged by ``fault``."""
        import json
        import shutil
        from pathlib import Path

        from spectral_igl.collection.store import write_record

        out = Path(self.tmp) / "store.zarr"
        shutil.rmtree(out, ignore_errors=True)
        for name in ("a", "b"):
            write_record(out, name, {"status": "done"}, {"x": self.np.arange(1.0, 7.0).reshape(3, 2)})
        grp = out / "a"
        chunks = [c for c in (grp / "x").rglob("*") if c.is_file() and c.name != "zarr.json"]
        if fault == "deleted_chunk":
            for c in chunks:
                c.unlink()
        elif fault == "zeroed_chunk":
            for c in chunks:
                c.write_bytes(bytes(c.stat().st_size))
        elif fault == "truncated_meta":
            (grp / "zarr.json").write_text((grp / "zarr.json").read_text()[:50])
        elif fault == "empty_meta":
            (grp / "zarr.json").write_text("")
        elif fault == "missing_array":
            shutil.rmtree(grp / "x")
        elif fault == "extra_array":
            meta = json.loads((grp / "zarr.json").read_text())
            meta["attributes"]["arrays"].append("y")
            (grp / "zarr.json").write_text(json.dumps(meta))
        return str(out)


def _nonfinite(x, np) -> bool:
    if isinstance(x, (float, complex, np.floating, np.complexfloating)):
        return not np.isfinite(x)
    if isinstance(x, np.ndarray):
        return x.dtype.kind in "fc" and not np.all(np.isfinite(x))
    if isinstance(x, (tuple, list)) and len(x) and not isinstance(x[0], (str, dict)):
        return any(_nonfinite(y, np) for y in x[:3])
    if hasattr(x, "L") and hasattr(x, "B"):  # a Laplacian
        return not (np.all(np.isfinite(x.L.data)) and np.all(np.isfinite(x.B.data)))
    return False


def _call(build, name, kwargs):
    sig, np = build.sig, build.np
    spec = kwargs.get("lap", kwargs.get("lap_or_mesh"))
    lap_name = spec.get("lap") if isinstance(spec, dict) else None
    build.lap = build.laps.get(lap_name, build.laps["small"])    # sizes the other arguments
    kw = {k: build(v) for k, v in kwargs.items()}
    if name == "SpectralOperator.apply":
        x = kw.pop("x")
        kw = {k: v for k, v in kw.items() if not (k in ("k", "degree", "steps", "nodes") and v is None)}
        return sig.SpectralOperator(**kw).apply(x)
    if name == "OneToAll.distance":
        src = kw.pop("source")
        return sig.OneToAll(**kw).distance(src)
    if name == "cli":
        from spectral_igl.cli import main
        argv = [str(kw["job"]), str(kw["mesh"]), "--quiet", "--tol", str(kw["tol"]),
                "--source", str(kw["source"])]
        if kw.get("out") is not None:    # relative names land in the worker's scratch directory
            argv += ["--out", os.path.join(build.tmp, str(kw["out"])) + ".npy"]
        if kw.get("time") is not None:
            argv += ["--time", str(kw["time"])]
        import contextlib
        import io as _io
        err = _io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(_io.StringIO()):
            code = main(argv)
        msg = err.getvalue()
        if code not in (0, 1, 2, 3, 4) or (code == 1 and "failed:" in msg and not any(
                t in msg for t in ("ValueError", "TypeError"))):
            raise RuntimeError(f"CLI exit {code}: {msg.strip()[-300:]}")
        return np.zeros(1)
    if name == "collection.load":
        # a damaged group is never among the results, and every result holds what was written
        from spectral_igl.collection import load

        res, fails = load(kw["out"])
        for key, r in res.items():
            if not np.array_equal(r.arrays["x"], np.arange(1.0, 7.0).reshape(3, 2)):
                raise RuntimeError(f"group {key!r} read back as {r.arrays['x'].tolist()}")
        if len(res) + len(fails) != 2:
            raise RuntimeError(f"{2 - len(res) - len(fails)} group(s) in neither results nor failures")
        return np.zeros(1)
    if name == "schrodinger@0":
        name = "schrodinger"
    if name.startswith("dg."):
        import data_generators as dg
        return getattr(dg, name[3:])(**kw)
    if "." in name:
        mod, fn = name.split(".")
        module = __import__(f"spectral_igl.{mod}", fromlist=[fn])
        return getattr(module, fn)(**kw)
    return getattr(sig, name)(**kw)


def run_case(build, case) -> dict:
    np = build.np
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with np.errstate(all="ignore"):
                out = _call(build, case["name"], case["kwargs"])
    except (ValueError, TypeError, FileNotFoundError, IsADirectoryError) as err:
        # a missing file or a directory: the standard exceptions of file functions
        return {"outcome": "refused", "detail": f"{type(err).__name__}: {err}"[:300]}
    except ImportError as err:
        # a missing optional dependency: one line ending with the command that installs it
        if "\n" in str(err) or "pip install" not in str(err):
            return {"outcome": "bad", "detail": f"ImportError without its install command: {err}"[:300]}
        return {"outcome": "refused", "detail": f"ImportError: {err}"[:300]}
    except Exception as err:  # noqa: BLE001 - any other type is a finding
        tb = traceback.format_exc().strip().splitlines()[-3:]
        return {"outcome": "bad", "detail": f"{type(err).__name__}: {err}"[:300] + " | " + " / ".join(tb)[:300]}
    if case["name"] in GEODESIC and isinstance(out, np.ndarray) and not np.any(np.isnan(out)):
        # inf is the distance to the vertices of components that hold no source, and only there
        lap = build.lap
        src = np.atleast_1d(build(case["kwargs"].get("source", 0))).astype(int)
        reached = np.isin(lap.components, lap.components[src])
        out = np.where(reached, out, 0.0)
    if _nonfinite(out, np):
        return {"outcome": "bad", "detail": "NaN or inf returned without an exception"}
    return {"outcome": "ok", "detail": ""}


def serve():
    """Worker loop: a JSON case per line on stdin, a JSON answer per line on stdout."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # the protocol gets its own descriptor; anything else written to fd 1 (Python or C++
    # libraries) goes to stderr and cannot corrupt it
    out = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    build = _Build()
    out.write(json.dumps({"ready": True}) + "\n")
    out.flush()
    for line in sys.stdin:
        case = json.loads(line)
        try:
            res = run_case(build, case)
        except BaseException as err:  # noqa: BLE001 - the checks themselves failed: report it
            res = {"outcome": "bad", "detail": f"checking the result raised {type(err).__name__}: {err}"[:300]}
        out.write(json.dumps(res) + "\n")
        out.flush()


if __name__ == "__main__":
    serve()
