"""Heat diagonals and diffusion distances on components where the heat has mixed.

truck.obj has 50 components, most of a few vertices: at t comparable to the mesh's area the
heat on those is the constant 1/V_c to many digits (t lambda_2 up to 8e4), and the partial
fractions' rounding there outgrew their a-priori allowance (3.3e-7 off 2550.85 against a
"proof" bound of 1.0e-7 on a 7-vertex part; up to 6.75 times the bound at 2 x area). The truth
is the heat kernel of each small component's stored L and B in 60-digit arithmetic, with the
rows of L made to sum to exactly 0 (the package's ker L).
"""
import numpy as np
import pytest
from conftest import read_shared_mesh

import spectral_igl as sig
from spectral_igl.approx.common import mixed_heat

mpmath = pytest.importorskip("mpmath")


@pytest.fixture(scope="module")
def truck():
    V, F = read_shared_mesh("truck.obj")
    lap = sig.laplacian(V, F)
    comp, mass = lap.components, lap.mass
    parts = []
    with mpmath.workdps(60):
        for c in np.unique(comp):
            idx = np.flatnonzero(comp == c)
            if not 1 < len(idx) <= 12:
                continue
            Lc = lap.L[idx][:, idx].toarray()
            n = len(idx)
            S = mpmath.matrix(n)
            for a in range(n):
                for b in range(n):
                    if a != b:
                        S[a, b] = mpmath.mpf(Lc[a, b])
                S[a, a] = -mpmath.fsum(S[a, b] for b in range(n) if b != a)
            for a in range(n):
                for b in range(n):
                    S[a, b] /= mpmath.sqrt(mpmath.mpf(mass[idx[a]]) * mpmath.mpf(mass[idx[b]]))
            ev, U = mpmath.eigsy(S)
            parts.append((idx, ev, U))
    return lap, parts


def heat_diagonal_truth(lap, parts, t):
    """{vertex: K_t(i, i)} on the small components, in 60 digits."""
    out = {}
    with mpmath.workdps(60):
        for idx, ev, U in parts:
            w = [mpmath.exp(-t * e) for e in ev]
            for a, i in enumerate(idx):
                out[i] = float(mpmath.fsum(w[l] * U[a, l] ** 2 for l in range(len(idx))) / lap.mass[i])
    return out


def test_heat_diagonals_of_mixed_components_within_their_bounds(truck):
    lap, parts = truck
    times = np.geomspace(1e-3, 2.0, 16)          # x area: 16 times take the common-pole path
    many, info = sig.hks(lap, times, time_unit="shape", return_info=True)
    bounds = np.broadcast_to(info["abs_error"], many.shape)
    replaced = 0
    for k, t in enumerate(info["times"]):
        truth = heat_diagonal_truth(lap, parts, t)
        idx = np.fromiter(truth, int)
        exact = np.fromiter(truth.values(), float)
        assert np.all(np.abs(many[idx, k] - exact) <= bounds[idx, k]), (t, np.max(np.abs(many[idx, k] - exact) / bounds[idx, k]))
        if k in (0, 12, 15):                      # the one-time path (a selected inversion)
            one, one_info = sig.hks(lap, [t], return_info=True)
            assert np.all(np.abs(one[idx, 0] - exact) <= np.broadcast_to(one_info["abs_error"], one.shape)[idx, 0])
        replaced += int(mixed_heat(lap, t, 1e-10)[0][idx].sum())
    assert replaced > 0                          # the projection was taken somewhere


def test_mixed_heat_needs_the_decay_proved_below_eps(truck):
    lap, parts = truck
    t = 0.5 * lap.area()
    mask, decay = mixed_heat(lap, t, 1e-10)
    for idx, ev, _ in parts:
        lam2 = float(ev[1])                      # ev ascending; ev[0] = 0 exactly (rows sum to 0)
        if mask[idx].all():
            assert np.all(decay[idx] >= np.exp(-t * lam2) * (1 - 1e-12)) and np.all(decay[idx] <= 1e-10)
    assert not mask[lap.components == np.argmax(np.bincount(lap.components))].any()


def test_diffusion_distance_between_mixed_components(truck):
    lap, parts = truck
    t = 1.0 * lap.area()
    src = int(parts[0][0][0])
    d, info = sig.diffusion_distance(lap, t, src, return_info=True)
    truth = heat_diagonal_truth(lap, parts, t)
    bound = np.broadcast_to(info["abs_error"], d.shape)
    comp = lap.components
    for idx, _, _ in parts[1:]:
        for j in idx:                            # other components: K_t(src, j) = 0
            exact = np.sqrt(truth[src] + truth[j])
            assert abs(d[j] - exact) <= bound[j], (j, d[j], exact, bound[j])
    assert comp[src] != comp[parts[1][0][0]]
