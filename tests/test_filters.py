"""Filters: values, squares, singularity flags, validation."""
import numpy as np
import pytest

from spectral_igl import filters

S = np.array([0.0, 0.5, 1.0, 7.0, 123.0])


@pytest.mark.parametrize("filt, ref", [
    (filters.heat(0.3), lambda s: np.exp(-0.3 * s)),
    (filters.wave(0.7), lambda s: np.exp(-0.7j * s)),
    (filters.mexican_hat(0.2), lambda s: 0.2 * s * np.exp(-0.2 * s)),
    (filters.multiscale(0.5, 2, 0.5), lambda s: 0.25 * np.sqrt(s) * np.exp(-0.5 * np.sqrt(s))),
])
def test_regular_filter_values_and_square(filt, ref):
    assert np.allclose(filt(S), ref(S), rtol=1e-14, atol=0)
    assert not filt.singular
    assert np.allclose(filt.square(S), np.abs(ref(S)) ** 2, rtol=1e-13, atol=1e-300)
    if filt.derivative is not None:
        h = 1e-6
        s = S[1:]
        fd = (filt(s + h) - filt(s - h)) / (2 * h)
        assert np.allclose(filt.derivative(s), fd, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("filt, p", [(filters.commute_time(), 0.5), (filters.biharmonic(), 1.0),
                                     (filters.polyharmonic(3), 1.5), (filters.polyharmonic(4), 2.0)])
def test_singular_filters_vanish_at_zero(filt, p):
    assert filt.singular and filt.kind == "power" and filt.params["p"] == p
    v = filt(S)
    assert v[0] == 0.0
    assert np.allclose(v[1:], S[1:] ** (-p), rtol=1e-14)
    assert filt.square.singular and np.allclose(filt.square(S[1:]), S[1:] ** (-2 * p), rtol=1e-14)


def test_heat_square_is_heat_at_double_time():
    sq = filters.heat(0.25).square
    assert sq.kind == "heat" and sq.params["t"] == 0.5


def test_wave_is_complex_with_unit_modulus():
    w = filters.wave(3.0)
    assert w.is_complex and np.allclose(w.square(S), 1.0)


def test_user_filter():
    g = filters.Filter(lambda s: 1.0 / (1.0 + s) ** 2, name="r2")
    assert np.allclose(g(S), 1 / (1 + S) ** 2)
    assert np.allclose(g.square(S), 1 / (1 + S) ** 4)
    with pytest.raises(ValueError, match="complex"):
        filters.Filter(lambda s: 1j * s)(S)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.inf, np.nan])
def test_time_must_be_positive_finite(bad):
    for make in (filters.heat, filters.wave, filters.mexican_hat):
        with pytest.raises(ValueError):
            make(bad)


def test_invalid_parameters():
    with pytest.raises(TypeError):
        filters.heat("1")
    with pytest.raises(ValueError):
        filters.polyharmonic(0)
    with pytest.raises(TypeError):
        filters.polyharmonic(1.5)
    with pytest.raises(ValueError):
        filters.multiscale(1.0, -1, 1.0)
    with pytest.raises(ValueError):
        filters.multiscale(1.0, 1, 0.0)
    with pytest.raises(TypeError):
        filters.Filter(3.0)


def test_mexican_hat_survey_form():
    s = np.array([0.0, 0.5, 1.0, 4.0, 30.0])
    f = filters.mexican_hat(0.2, form="survey")
    u = 0.2 * s
    assert np.allclose(f(s), np.sqrt(u) * np.exp(-u ** 2), rtol=1e-14, atol=0)
    assert np.allclose(f.square(s), f(s) ** 2, rtol=1e-12, atol=1e-300)
    assert np.allclose(filters.mexican_hat(0.2)(s), u * np.exp(-u), rtol=1e-14, atol=0)
    with pytest.raises(ValueError, match="form"):
        filters.mexican_hat(0.2, form="ricker")
