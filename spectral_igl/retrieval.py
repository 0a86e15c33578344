r"""Distance matrices over a collection: signatures stored by :func:`spectral_igl.collection.run`.

A collection run of :meth:`~spectral_igl.collection.Job.heat_trace` or
:meth:`~spectral_igl.collection.Job.shape_dna` stores one signature per shape with the bound
of every entry; :func:`collection_distance_matrix` reads them back through
:func:`spectral_igl.collection.load`, compares them (:func:`spectral_igl.shape_distance_matrix`,
with a bound of every distance) and keeps the matrix beside the store, in
``<store>.distances.npz``, with what it was computed from. The store itself holds one group
per shape, and :func:`~spectral_igl.collection.load` reads every group as a shape, so a
matrix over all shapes has no place inside it.
"""
from __future__ import annotations

import datetime
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ._validate import as_flag, describe
from ._version import __version__
from .accuracy import info as bound_info, weakest
from .applications.compare import shape_distance_matrix
from .collection import Job, load

__all__ = ["collection_distance_matrix", "SIGNATURE_JOBS"]

#: the jobs whose stored results can be compared, and the array each stores
SIGNATURE_JOBS = ("heat_trace", "shape_dna")


def _job_of(results, job):
    """``(kind, params)`` of the signature job: ``job``'s, or the one every stored result shares."""
    if job is not None:
        if not isinstance(job, Job):
            raise TypeError(f"job must be a Job (Job.heat_trace(...) or Job.shape_dna(k)) or None, got "
                            f"{describe(job)}")
        kind, params = job.kind, json.loads(json.dumps(job.params))
    elif not results:
        raise ValueError("the store holds no completed result to compare")
    else:
        found = {json.dumps([r.meta.get("job"), r.meta.get("params")], sort_keys=True) for r in results.values()}
        if len(found) != 1:
            raise ValueError(f"the store holds results of {len(found)} different jobs; name the one to "
                             "compare with job=Job.heat_trace(...) or job=Job.shape_dna(k)")
        kind, params = json.loads(found.pop())
    if kind not in SIGNATURE_JOBS:
        raise ValueError(f"job must compute a signature, one of {SIGNATURE_JOBS}, got the job {kind!r}")
    return kind, params


def _provenance(store, kind, params, chosen):
    """What the matrix is computed from; its ``digest`` identifies it (names, arrays, job)."""
    sums = {name: [r.meta["checksums"].get(kind), r.meta["checksums"].get(kind + "_abs_error")]
            for name, r in chosen.items()}
    ident = {"job": kind, "params": params, "signatures": sums}
    return {"store": str(Path(store).resolve()), "job": kind, "params": params,
            "job_key": Job(kind, params).key(), "names": list(chosen),
            "input_hash": {n: r.meta.get("input_hash") for n, r in chosen.items()},
            "mesh_hash": {n: r.meta.get("mesh_hash") for n, r in chosen.items()},
            "digest": hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()}


def _read_saved(path, digest):
    """``(D, abs_error, meta)`` saved at ``path`` for ``digest``, or None."""
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["provenance"]))
            if meta.get("digest") != digest:
                return None
            return np.array(z["distances"]), np.array(z["abs_error"]), meta
    except (OSError, KeyError, ValueError):
        return None


def _write(path, D, abs_error, meta):
    """Save atomically: a temporary file beside ``path``, then a rename."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.savez(fh, distances=D, abs_error=abs_error, names=np.array(meta["names"], dtype=str),
                 provenance=np.array(json.dumps(meta)))
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def collection_distance_matrix(store, job=None, path=None, force: bool = False,
                               return_info: bool = False):
    r"""The distances between the signatures stored in a collection, kept beside the store.

    Reads the results of :meth:`~spectral_igl.collection.Job.heat_trace` or
    :meth:`~spectral_igl.collection.Job.shape_dna` that :func:`spectral_igl.collection.run`
    wrote into ``store`` (failed and damaged shapes are left out and listed in ``info``),
    compares them with :func:`spectral_igl.shape_distance_matrix` and saves the matrix, its
    bound and its provenance in ``path``. A later call over the same stored signatures (the
    same names, the same SHA-256 of every signature and bound, the same job) reads the
    saved matrix instead of computing it.

    Parameters
    ----------
    store : str or os.PathLike
        The collection's Zarr store.
    job : Job, optional
        The signature job whose results to compare; default: the one job that every stored
        result comes from. Results of other jobs are left out (``info["other_jobs"]``).
    path : str or os.PathLike, optional
        Where the matrix is kept; default ``<store>.distances.npz`` beside the store. Holds
        ``distances`` (m, m), ``abs_error`` (m, m), ``names`` (m,) and ``provenance``
        (JSON: store, job, params, job_key, names, input and mesh hashes, digest, version,
        date, bound_kind).
    force : bool
        Recompute although a current matrix is saved.
    return_info : bool
        Also return ``info``: ``abs_error`` (m, m), a bound of every distance from the
        stored bounds of the signatures; ``bound_kind`` (the weakest stored kind);
        ``method``; ``path``; ``recomputed`` (False when the saved matrix was current);
        ``left_out`` (failed or damaged shapes); ``other_jobs``; ``provenance``.

    Returns
    -------
    D : (m, m) float
        Symmetric, zero on the diagonal; rows in the order of ``names``.
    names : list of str
        The compared shapes, sorted.
    info : dict, only with ``return_info``

    Notes
    -----
    For the heat trace :math:`D_{ij} = (\frac1T\sum_k(\log Z_i(t_k) - \log Z_j(t_k))^2)^{1/2}`,
    for ShapeDNA :math:`D_{ij} = \lVert (s\lambda^{(i)}_l - s\lambda^{(j)}_l)/l \rVert_2`
    (:func:`spectral_igl.shape_distance`). The bound of :math:`D_{ij}` is
    :math:`\lVert e_i\rVert + \lVert e_j\rVert` with :math:`e_i` the bound of shape i's
    features (triangle inequality), from the stored per-entry bounds.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from spectral_igl.collection import Job, run
    >>> from spectral_igl.data_generators import icosphere, torus
    >>> V, F = icosphere(2)
    >>> shapes = {"sphere": (V, F), "big-sphere": (5 * V, F), "torus": torus(1.0, 0.4, 24, 12)}
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "dna.zarr"
    >>> from distributed import Client
    >>> with Client(processes=False, dashboard_address=None) as client:   # or a cluster's address
    ...     _ = run(shapes, Job.shape_dna(10), store, scheduler=client, progress=False)
    >>> D, names, info = collection_distance_matrix(store, return_info=True)
    >>> names, bool(D[0, 1] < 1e-6 < D[0, 2]), info["bound_kind"], info["recomputed"]
    (['big-sphere', 'sphere', 'torus'], True, 'proof', True)
    >>> collection_distance_matrix(store, return_info=True)[2]["recomputed"]
    False
    """
    force = as_flag(force, "force")
    results, failures = load(store)
    kind, params = _job_of(results, job)
    chosen, other = {}, []
    for name in sorted(results):
        r = results[name]
        if r.meta.get("job") == kind and r.meta.get("params") == params and kind in r.arrays:
            chosen[name] = r
        else:
            other.append(name)
    if len(chosen) < 1:
        raise ValueError(f"store {str(store)!r} holds no result of the job {kind!r} with params {params}")
    path = Path(path) if path is not None else Path(store).with_name(Path(store).name + ".distances.npz")
    meta = _provenance(store, kind, params, chosen)
    saved = None if force else _read_saved(path, meta["digest"])
    if saved is not None:
        D, E, meta = saved
    else:
        S = np.stack([chosen[n].arrays[kind] for n in chosen])
        errors = np.stack([chosen[n].abs_error(kind) for n in chosen])
        kinds = [chosen[n].bound_kind for n in chosen]
        if np.all(np.isfinite(errors)):
            D, dinfo = shape_distance_matrix(S, kind, abs_error=errors, return_info=True)
            E = dinfo["abs_error"]
        else:
            D, E, kinds = shape_distance_matrix(S, kind), np.full((len(chosen),) * 2, np.inf), [None]
        meta.update(version=__version__, bound_kind=weakest(*kinds),
                    date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"))
        _write(path, D, E, meta)
    names = list(meta["names"])
    if not as_flag(return_info, "return_info"):
        return D, names
    return D, names, bound_info(E, meta["bound_kind"], kind, path=str(path), recomputed=saved is None,
                                left_out=[f["name"] for f in failures], other_jobs=other,
                                provenance=meta)
