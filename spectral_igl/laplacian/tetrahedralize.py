"""A volume from a closed surface: tetrahedral meshing through fTetWild (pytetwild)."""
from __future__ import annotations

import numpy as np

from .._extras import require
from .._validate import as_cells, as_flag, as_mesh_arrays, as_points, as_positive, as_real_in
from .elements import element_measures

__all__ = ["tetrahedralize"]


#: smallest target edge length, relative to the bounding-box diagonal (about 1e7 tetrahedra)
MIN_EDGE_FAC = 5e-3


def tetrahedralize(V, F=None, edge_length_fac: float = 0.05, edge_length_abs: float | None = None,
                   epsilon: float = 1e-3, optimize: bool = True, quiet: bool = True,
                   timeout: float | None = 600.0):
    r"""Tetrahedral mesh of the volume enclosed by a surface, through fTetWild.

    fTetWild is robust to imperfect input (small gaps, self-intersections, several
    components); its output boundary stays within ``epsilon`` of the input surface.

    Parameters
    ----------
    V : (n, 3) float, or a pyvista/trimesh/meshio mesh with ``F`` omitted
    F : (m, 3) int, optional
        A closed (or nearly closed) triangle surface.
    edge_length_fac : float in [0.005, 1]
        Target tetrahedron edge length as a fraction of the bounding-box diagonal.
    edge_length_abs : float or None
        Absolute target edge length (at least 0.005 x the diagonal); overrides
        ``edge_length_fac``.
    epsilon : float in [1e-6, 1]
        Envelope size relative to the bounding-box diagonal.
    optimize : bool
        Improve element quality (slower).
    timeout : float or None
        Seconds fTetWild may run (default 600; None: no limit). It runs in a child
        process with its own scratch directory, so a surface it cannot finish (some
        self-intersecting inputs) ends in a ``ValueError`` instead of a hang, a crash inside
        it cannot take the caller down, and the caller's working directory is never changed.
    quiet : bool
        Silence fTetWild's log.

    Returns
    -------
    V : (p, 3) float
    T : (q, 4) int, positively oriented tetrahedra (every vertex referenced).

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> Vt, T = sig.tetrahedralize(*icosphere(2), edge_length_fac=0.2)
    >>> T.shape[1]
    4
    """
    V, F = as_mesh_arrays(V, F)
    V = as_points(V, "V", dims=(3,), min_rows=4)
    F = as_cells(F, V.shape[0], "F", sizes=(3,))
    edge_length_fac = as_real_in(edge_length_fac, "edge_length_fac", MIN_EDGE_FAC, 1.0)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    if edge_length_abs is not None:
        edge_length_abs = as_positive(edge_length_abs, "edge_length_abs")
        if edge_length_abs < MIN_EDGE_FAC * diag:
            raise ValueError(f"edge_length_abs = {edge_length_abs:g} is below {MIN_EDGE_FAC:g} x the bounding-box "
                             f"diagonal ({diag:.3g}): about {(1 / MIN_EDGE_FAC) ** 3:.0e} tetrahedra or more")
    epsilon = as_real_in(epsilon, "epsilon", 1e-6, 1.0)
    optimize, quiet = as_flag(optimize, "optimize"), as_flag(quiet, "quiet")
    if element_measures(V, F).max() <= 0:
        raise ValueError("F has no face of positive area")
    # fTetWild is given only the vertices the faces use (unreferenced ones stall it)
    used = np.unique(F)
    if used.size < V.shape[0]:
        remap = np.full(V.shape[0], -1, dtype=np.int64)
        remap[used] = np.arange(used.size)
        V, F = np.ascontiguousarray(V[used]), remap[F]
    if timeout is not None:
        timeout = as_positive(timeout, "timeout")
    Vt, T = _run_tetwild(V, F.astype(np.int32), timeout,
                         dict(edge_length_fac=edge_length_fac, edge_length_abs=edge_length_abs,
                              epsilon=epsilon, optimize=bool(optimize), quiet=bool(quiet)))
    Vt = np.ascontiguousarray(Vt, dtype=np.float64)
    T = np.ascontiguousarray(T, dtype=np.int64)
    if T.size == 0:
        raise ValueError("fTetWild produced no tetrahedra: is the surface closed?")
    # orient positively, drop unreferenced vertices
    e1, e2, e3 = (Vt[T[:, k]] - Vt[T[:, 0]] for k in (1, 2, 3))
    neg = np.einsum("ij,ij->i", np.cross(e1, e2), e3) < 0
    T[neg] = T[neg][:, [0, 2, 1, 3]]
    used = np.unique(T)
    remap = np.full(Vt.shape[0], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return Vt[used], remap[T]


def _tetwild_child(conn, V, F, kwargs):
    """Run fTetWild in a scratch directory of this (child) process; send (Vt, T, error)."""
    import os
    import tempfile

    try:
        import pytetwild

        with tempfile.TemporaryDirectory() as scratch:
            os.chdir(scratch)      # fTetWild writes __tracked_surface.stl into the working directory
            Vt, T = pytetwild.tetrahedralize(V, F, **kwargs)
        conn.send((np.asarray(Vt), np.asarray(T), None))
    except BaseException as exc:  # reported to the parent, which raises
        conn.send((None, None, f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def _run_tetwild(V, F, timeout, kwargs):
    """fTetWild in a child process: (Vt, T), or a ValueError after ``timeout`` seconds."""
    import multiprocessing as mp

    require("pytetwild", "tet", "tetrahedralize")  # here, not in the child: one clear line
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_tetwild_child, args=(send, V, F, kwargs), daemon=True)
    proc.start()
    send.close()
    try:
        if not recv.poll(timeout):
            proc.kill()
            raise ValueError(f"fTetWild did not finish in {timeout:g} s: the surface may self-intersect "
                             "or be far from closed; repair it, or pass a larger timeout (None: no limit)")
        try:
            Vt, T, err = recv.recv()
        except EOFError:
            proc.join(5)
            raise ValueError(f"fTetWild stopped without a result (exit code {proc.exitcode}); "
                             "the surface is probably degenerate") from None
    finally:
        recv.close()
        proc.join(5)
        if proc.is_alive():
            proc.kill()
    if err is not None:
        raise ValueError(f"fTetWild failed: {err}")
    return Vt, T
