"""Every example script in quick mode: its images exist and are not blank, its key numbers hold.

The scripts are imported and their ``main(argv)`` called, so they cannot rot.
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from _needs import VIZ

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SCRIPTS = [
    "fig02_harmonic", "fig03_eigenfunctions", "fig04_anisotropic_heat", "fig05_lcurve",
    "fig06_conditioning", "fig07_17_timing", "fig08_volumetric_heat", "fig09_distances",
    "fig10_filters", "fig11_12_biharmonic_stability", "fig13_14_accuracy", "fig15_gibbs",
    "fig16_tradeoff", "fig18_23_robustness", "fig24_26_smoothing", "fig25_constrained_smoothing",
    "fig26_truncated_smoothing", "fig_mcf", "fig_retrieval", "fig_correspondence",
]


pytestmark = [VIZ, pytest.mark.usefixtures("one_blas_thread")]   # every script draws its pictures


def scripts():
    return sorted(p.stem for p in EXAMPLES.glob("fig*.py"))


def load(name):
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def image_ok(path, min_std=8.0, min_colors=40):
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB"))
    colours = len(np.unique(img.reshape(-1, 3), axis=0))
    return float(img.std()) > min_std and colours > min_colors, (float(img.std()), colours)


def run(name, tmp_path):
    result = load(name).main(["--quick", "--out", str(tmp_path)])
    assert isinstance(result, dict) and result.get("images"), f"{name} returned no images"
    for path in result["images"]:
        assert Path(path).is_file(), path
        ok, stats = image_ok(path)
        assert ok, f"{path} looks blank (pixel std, colours) = {stats}"
        assert Path(path).stat().st_size < 400_000, f"{path} is too large"
    return result


def test_every_script_is_listed():
    assert scripts() == sorted(SCRIPTS)


def test_fig02_harmonic(tmp_path):
    r = run("fig02_harmonic", tmp_path)
    assert r["euler_characteristic"] == [2, 2, 2]
    assert r["extrema_only_at_constraints"]
    assert [m + M for m, M, s in r["critical_counts"]] == [2, 4, 6]


def test_fig03_eigenfunctions(tmp_path):
    r = run("fig03_eigenfunctions", tmp_path)
    assert all(e == 2 for e in r["euler_characteristic"])
    # the first non-constant eigenfunction of this genus-0 blob: one minimum, one maximum
    assert r["critical_counts"][0] == (1, 1, 0)
    # cancelling low-persistence pairs only removes points, and keeps m - s + M
    for (m, M, s), (m0, M0, s0) in zip(r["critical_counts"], r["raw_critical_counts"]):
        assert m <= m0 and M <= M0 and s <= s0 and m0 - s0 + M0 == 2
    assert 0 < r["eigenvalues"][0] and np.all(np.diff(r["eigenvalues"]) > 0)
    # higher eigenfunctions oscillate more: more critical points
    totals = [sum(c) for c in r["critical_counts"]]
    assert totals[-1] > totals[0]


def test_persistent_critical_points_cancel_a_spurious_pair():
    """z on a sphere plus a dent: the dent is a minimum and a saddle of tiny persistence."""
    from data_generators import icosphere

    load("fig02_harmonic")  # puts examples/ on the path
    import _common as C

    V, F = icosphere(3)
    f = V[:, 2].copy()
    k = int(np.argmin(np.abs(V[:, 2]) + np.abs(V[:, 0] - 1.0)))  # a vertex on the equator
    nbrs = np.unique(F[np.any(F == k, axis=1)])
    f[k] = f[nbrs[nbrs != k]].min() - 1e-3  # below all its neighbours: a local minimum
    cp = C.persistent_critical_points(V, F, f, fraction=0.02)
    m0, M0, s0 = cp["raw"]
    assert m0 == 2 and M0 == 1 and s0 == 1  # the dent adds a minimum and a saddle
    assert (cp["n_minima"], cp["n_maxima"], cp["n_saddles"]) == (1, 1, 0)
    assert cp["minimum"].tolist() == [int(np.argmin(V[:, 2]))]  # the south pole remains
    # with no threshold nothing is cancelled
    cp0 = C.persistent_critical_points(V, F, f, fraction=0.0)
    assert (cp0["n_minima"], cp0["n_maxima"], cp0["n_saddles"]) == (2, 1, 1)


def test_fig04_anisotropic_heat(tmp_path):
    r = run("fig04_anisotropic_heat", tmp_path)
    # cylinder: the anisotropic kernel's axes have the ratio sqrt(1 + alpha / r); isotropic: 1
    assert r["elongation_isotropic"] == pytest.approx(1.0, abs=0.02)
    assert r["elongation_anisotropic"] == pytest.approx(r["elongation_expected"], rel=0.05)


def test_fig05_lcurve(tmp_path):
    r = run("fig05_lcurve", tmp_path)
    assert r["error_smoothed"] < 0.5 * r["error_noisy"]
    # the risk minimum is (nearly) the best time on the curve
    assert r["error_smoothed"] <= 1.25 * r["error_best_on_curve"]


def test_fig25_constrained_smoothing(tmp_path):
    r = run("fig25_constrained_smoothing", tmp_path)
    assert r["constraint_error"] == 0.0  # the constrained values are kept exactly
    assert r["constraints"] >= 4 and r["critical_after"] < r["critical_before"] / 2
    assert r["linf_error_input"] < 0.15 and r["linf_error_clean"] < 0.15


def test_fig26_truncated_smoothing(tmp_path):
    r = run("fig26_truncated_smoothing", tmp_path)
    assert r["linf_rational"] < r["linf_noisy"] and r["l2_rational"] < r["l2_noisy"]
    # the truncated result approaches the spectrum-free one as k grows
    assert r["diff_to_rational_k400"] < r["diff_to_rational_k100"] < r["diff_to_rational_k20"]


def test_fig06_conditioning(tmp_path):
    r = run("fig06_conditioning", tmp_path)
    assert r["bound_holds"]  # kappa(sL - zB) <= kappa(B) max|s lambda - z| / min|s lambda - z|
    assert 1.0 <= r["max_condition"] < 100.0


def test_fig07_17_timing(tmp_path):
    r = run("fig07_17_timing", tmp_path)
    assert r["relative_error_vs_dense"] < 1e-7
    assert np.all(np.asarray(r["seconds_spectrum_free"]) > 0)  # timings are reported, not asserted


def test_fig08_volumetric_heat(tmp_path):
    r = run("fig08_volumetric_heat", tmp_path)
    assert r["conservation_error"] < 1e-8  # 1^T B K_t(:, i) = 1
    assert r["symmetry_error"] < 1e-6  # K_t(j, i) = K_t(i, j)


def test_fig09_distances(tmp_path):
    r = run("fig09_distances", tmp_path)
    assert r["source_value_max"] == 0.0 and r["min_elsewhere"] > 0
    assert r["relative_error_vs_dense"] < 1e-6


def test_fig10_filters(tmp_path):
    r = run("fig10_filters", tmp_path)
    assert r["heat_filter_error"] < 1e-14 and r["biharmonic_filter_error"] < 1e-12
    assert r["lambda_2"] == pytest.approx(2.0, rel=0.02)  # unit sphere: l(l+1) at l = 1


def test_fig11_12_biharmonic_stability(tmp_path):
    r = run("fig11_12_biharmonic_stability", tmp_path)
    errs = r["sphere_relative_error"]
    assert errs[-1] < errs[0] and errs[-1] < 0.05
    assert r["weights_difference"] < 0.02
    assert r["noise_difference"] < 0.1 and r["holes_difference"] < 0.1


def test_fig13_14_accuracy(tmp_path):
    r = run("fig13_14_accuracy", tmp_path)
    assert r["spectrum_free_max_error"] < 1e-6
    # truncation with 100 of 162 eigenpairs is far less accurate at small t
    assert r["truncated_error_k_max"][1e-3] > 1e3 * r["spectrum_free_max_error"]
    assert max(r["sampling_errors"]["spectrum-free"]) < 1e-6


def test_fig15_gibbs(tmp_path):
    r = run("fig15_gibbs", tmp_path)
    assert r["truncated_min"] < -1e-3  # Gibbs oscillation of the truncated expansion
    assert r["spectrum_free_min_plus_bound"] >= 0  # non-negative up to the certified bound


def test_fig16_tradeoff(tmp_path):
    r = run("fig16_tradeoff", tmp_path)
    assert r["bound_holds"]  # each certified bound covers the true error
    assert r["spectrum_free_errors"][1e-10] < 1e-9
    assert r["best_spectrum_free_error"] < 1e-6 * r["best_truncated_error"]


def test_fig18_23_robustness(tmp_path):
    r = run("fig18_23_robustness", tmp_path)
    assert r["sampling_difference"] < 0.1
    assert r["noise_difference"] < 0.2


def test_fig24_26_smoothing(tmp_path):
    r = run("fig24_26_smoothing", tmp_path)
    assert r["critical_after"] < 0.5 * r["critical_before"]
    assert r["error_smoothed"] < r["error_noisy"]


def test_fig_mcf(tmp_path):
    r = run("fig_mcf", tmp_path)
    # the conformalized flow rounds the blob, keeps its area and every triangle
    assert np.all(np.diff(r["roundness"]) < 0) and r["roundness"][-1] < 0.5 * r["roundness"][0]
    assert r["area_change"] < 1e-12
    assert r["min_area_ratio_conformal"] > 1e-3


def test_fig_retrieval(tmp_path):
    r = run("fig_retrieval", tmp_path)
    assert r["shapes"] == 16 and r["classes"] == 4 and r["done"] == 16
    # the stored matrix is the one of ShapeDNA computed here, and a rerun recomputes nothing
    assert r["difference_to_direct"] == 0.0 and r["bound_kind"] == "proof" and r["largest_bound"] < 1e-8
    assert r["rerun_skipped"] == 16 and not r["matrix_recomputed_on_rerun"] and r["rerun_equal"]
    assert r["nn_accuracy"] == 1.0 and r["map"] == 1.0


def test_fig_correspondence(tmp_path):
    r = run("fig_correspondence", tmp_path)
    assert r["n_target"] > r["n_source"]                 # a different, finer mesh
    assert r["mean_error"] < 0.02 and r["random_error"] > 0.3
