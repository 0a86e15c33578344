"""Heat methods against the dense ground truth; the certified bound is never below the error."""
import numpy as np
import pytest
from engine_cases import HEAT_TIMES, SHAPES, bnorm, check, shape, truth  # noqa: F401

import spectral_igl as sig
from spectral_igl import filters


@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("method", ["rational", "contour", "shift_invert", "chebyshev", "krylov"])
def test_heat_accurate_and_bounded(name, method, rng):
    lap, ev, X = shape(name)
    f = rng.standard_normal((lap.n, 2))
    for t in HEAT_TIMES:
        if method == "krylov" and t * sig.lambda_max(lap) > 1e4:
            continue  # polynomial Krylov needs ~sqrt(t lambda_max) steps: covered at small t
        op, err, slack = check(lap, ev, X, filters.heat(t), method, f)
        assert np.all(err <= op.error_bound + slack), (t, err, op.error_bound)
        assert np.all(op.error_bound <= 1e-8 * bnorm(lap, f) + slack * 10), (t, op.error_bound)


@pytest.mark.parametrize("method, opts", [("euler", {"steps": 1}), ("euler", {"steps": 8}),
                                          ("taylor1", {}), ("power", {}), ("taylor", {}),
                                          ("rational", {"degree": 4}), ("contour", {"nodes": 6}),
                                          ("chebyshev", {"degree": 5}), ("krylov", {"steps": 4}),
                                          ("shift_invert", {"steps": 4})])
def test_heat_low_order_bound_holds(method, opts, rng):
    """Crude settings: the error is large, and the bound must still cover it."""
    lap, ev, X = shape("sphere")
    f = rng.standard_normal(lap.n)
    for t in HEAT_TIMES:
        # refused when it would need too many squarings, unless the heat has reached the
        # projection onto the constants within tol (then no squaring is needed)
        reached = (t * sig.lambda_max(lap) > sig.approx.LARGE_T
                   and np.exp(-t * sig.lambda_min_positive(lap)) <= 0.5e-8)
        if method == "power" and t * sig.lambda_max(lap) > 2 ** 14 and not reached:
            with pytest.raises(ValueError, match="squarings"):
                sig.SpectralOperator(lap, filters.heat(t), method="power")
            continue
        op, err, slack = check(lap, ev, X, filters.heat(t), method, f, **opts)
        assert err <= op.error_bound + slack, (t, err, op.error_bound)




@pytest.mark.parametrize("name", ["sphere", "two_spheres"])
def test_large_t_needs_no_lanczos_for_its_gap(name, monkeypatch, rng):
    """At large t a decaying heat filter is split at a lower bound of lambda_{c+1} proved by one
    inertia count, not by lambda_min_positive's Lanczos run: dropped (no solve) where e^(-ta) is
    below tol, else any proved a > 0 for the Caratheodory-Fejer fit; the bound covers the error."""
    import spectral_igl.approx.operator as operator_mod

    lap0, ev, X = shape(name)
    c = lap0.n_components
    f = rng.standard_normal(lap0.n)
    # (the meshes are too coarse for t * lambda_max > LARGE_T at such t: the threshold is lowered)
    for large_t, t, dropped in [(100.0, 30.0 / ev[c], True), (1.0, 0.3 / ev[c], False)]:
        monkeypatch.setattr(operator_mod, "LARGE_T", large_t)
        lap = SHAPES[name]()                                     # a cold cache
        assert t * sig.lambda_max(lap) > large_t
        op, err, slack = check(lap, ev, X, filters.heat(t), "rational", f)
        assert ("bound", "lambda_min_positive") not in lap.cache
        assert 0 < op.a <= ev[c], (op.a, ev[c])
        assert isinstance(op.plan, operator_mod.ZeroPlan) == dropped
        assert op.bound_kind == "proof"
        assert err <= op.error_bound + slack, (t, err, op.error_bound)
        assert op.error_bound <= 1e-8 * bnorm(lap, f) + 10 * slack
