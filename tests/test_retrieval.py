"""Retrieval over a collection: scores, and the distance matrix of stored signatures."""
from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg as sla

import spectral_igl as sig
from data_generators import icosphere, torus
from data_generators.perturb import normal_noise, resample
from spectral_igl.collection import Job, load, run

pytest.importorskip("zarr")
pytest.importorskip("distributed")

U = np.finfo(float).eps
TIMES = [1e-2, 3e-2, 0.1, 0.3]


@pytest.fixture(scope="module")
def client():
    """A scheduler in this process (threads): quick to start, the same code path as a cluster."""
    from distributed import Client

    with Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None) as c:
        yield c


def _shapes():
    V, F = icosphere(2)
    blob = resample(normal_noise(V * [1.0, 0.8, 0.6], F, 0.03, seed=3), F, 0.5, seed=4)
    return {"sphere": (V, F), "sphere-x7": (7.0 * V, F), "blob": blob, "torus": torus(1.0, 0.4, 24, 10)}


def _dense_trace(V, F):
    """Z(t) at TIMES (x area) from every eigenvalue of (L, B), and its rounding allowance."""
    lap = sig.laplacian(V, F)
    lam = np.maximum(sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True), 0.0)
    t = np.asarray(TIMES) * lap.B.sum()
    z = np.exp(-np.outer(t, lam)).sum(axis=1)
    return z, lap.n * t * 16 * lap.n * U * lam[-1] + 4 * lap.n * U * z


def test_retrieval_scores_by_hand_and_refusals():
    # two classes; query 2's nearest is of the other class, its class-mate comes third
    D = np.array([[0, 1, 4, 9], [1, 0, 2, 9], [4, 2, 0, 3], [9, 9, 3, 0]], float)
    nn, mAP = sig.retrieval_scores(D, ["a", "a", "b", "b"])
    # queries 0, 1: rank 1 relevant (AP 1); query 2: ranks (1:a, 3:b) -> AP 1/2; query 3: (2:b) -> 1/1
    assert nn == 0.75 and mAP == pytest.approx((1 + 1 + 1 / 2 + 1) / 4, abs=1e-15)
    with pytest.raises(ValueError, match="at least two"):
        sig.retrieval_scores(D, ["a", "a", "a", "b"])
    with pytest.raises(ValueError, match="D must be"):
        sig.retrieval_scores(D[:3], ["a", "a", "b", "b"])
    with pytest.raises(ValueError, match="finite"):
        sig.retrieval_scores(np.full((2, 2), np.nan), ["a", "a"])


def test_stored_matrix_is_the_matrix_of_the_stored_signatures(tmp_path, client):
    shapes = _shapes()
    store = tmp_path / "traces.zarr"
    first = run(shapes, Job.heat_trace(TIMES), store, scheduler=client, progress=False)
    assert sorted(first.done) == sorted(shapes) and first.ok
    D, names, info = sig.collection_distance_matrix(store, return_info=True)
    assert names == sorted(shapes) and info["recomputed"] and info["bound_kind"] == "proof"
    results = load(store).results
    S = np.stack([results[n]["heat_trace"] for n in names])
    assert np.array_equal(D, sig.shape_distance_matrix(S))
    # the same signatures computed here, without the collection
    direct = np.stack([sig.heat_trace(sig.laplacian(*shapes[n]), TIMES) for n in names])
    assert np.array_equal(S, direct)
    # against traces from every dense eigenvalue: within the stored bounds
    exact, allowance = zip(*(_dense_trace(*shapes[n]) for n in names))
    exact, allowance = np.array(exact), np.array(allowance)
    truth = sig.shape_distance_matrix(exact)
    slack = np.linalg.norm(allowance / exact, axis=1) / np.sqrt(len(TIMES)) * 2
    assert np.all(np.abs(D - truth) <= info["abs_error"] + slack[:, None] + slack[None, :])
    assert 0 < info["abs_error"].max() < 1e-6 * D.max()
    i, j = names.index("sphere"), names.index("sphere-x7")
    # one shape at two scales: zero within the bound; another shape: far beyond it
    k = names.index("torus")
    assert D[i, j] <= info["abs_error"][i, j] and D[i, k] > 1e6 * info["abs_error"][i, k]
    # what was kept beside the store: the matrix, its bound and where it comes from
    with np.load(info["path"]) as z:
        meta = json.loads(str(z["provenance"]))
        assert np.array_equal(z["distances"], D) and list(z["names"]) == names
    assert meta["job"] == "heat_trace" and meta["job_key"] == Job.heat_trace(TIMES).key()
    assert meta["input_hash"]["blob"] == results["blob"].meta["input_hash"]


def test_running_twice_recomputes_nothing_and_a_changed_shape_is_seen(tmp_path, client):
    shapes = _shapes()
    store = tmp_path / "dna.zarr"
    run(shapes, Job.shape_dna(12), store, scheduler=client, progress=False)
    D, names, info = sig.collection_distance_matrix(store, return_info=True)
    stamp = (tmp_path / "dna.zarr.distances.npz").stat().st_mtime_ns
    again = run(shapes, Job.shape_dna(12), store, scheduler=client, progress=False)
    assert sorted(again.skipped) == names and not again.done
    D2, names2, info2 = sig.collection_distance_matrix(store, Job.shape_dna(12), return_info=True)
    assert not info2["recomputed"] and np.array_equal(D2, D) and names2 == names
    assert np.array_equal(info2["abs_error"], info["abs_error"])
    assert (tmp_path / "dna.zarr.distances.npz").stat().st_mtime_ns == stamp
    # one shape changes: only it is recomputed, and the matrix with it
    shapes["blob"] = (1.1 * shapes["blob"][0] * [1.0, 1.0, 1.3], shapes["blob"][1])
    third = run(shapes, Job.shape_dna(12), store, scheduler=client, progress=False)
    assert third.done == ["blob"]
    D3, _, info3 = sig.collection_distance_matrix(store, return_info=True)
    b = names.index("blob")
    assert info3["recomputed"] and D3[b].max() != D[b].max()
    keep = [k for k in range(len(names)) if k != b]
    assert np.array_equal(D3[np.ix_(keep, keep)], D[np.ix_(keep, keep)])


def test_bad_jobs_are_refused(tmp_path, client):
    V, F = icosphere(1)
    store = tmp_path / "hks.zarr"
    run({"a": (V, F), "b": (2 * V, F)}, Job.hks([0.1, 1.0]), store, scheduler=client, progress=False)
    with pytest.raises(ValueError, match="signature"):
        sig.collection_distance_matrix(store)
    with pytest.raises(ValueError, match="no result of the job 'heat_trace'"):
        sig.collection_distance_matrix(store, Job.heat_trace(TIMES))
    with pytest.raises(TypeError, match="job must be a Job"):
        sig.collection_distance_matrix(store, "heat_trace")
    with pytest.raises(FileNotFoundError):
        sig.collection_distance_matrix(tmp_path / "nothing.zarr")
