import numpy as np
import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.filter.predictor import closed_loop_radius, extrapolation_weights, stable_gain_threshold, weight_table


@pytest.mark.parametrize("n,order", [(1, 2), (2, 2), (3, 2), (5, 1), (10, 2), (10, 0), (7, 3)])
def test_weights_equal_polyfit_extrapolation(n, order):
    rng = np.random.default_rng(n * 10 + order)
    for _ in range(20):
        x = rng.normal(size=n) * 3 + rng.normal()
        t = np.arange(n)
        expected = np.polyval(np.polyfit(t, x, min(order, n - 1)), n)
        assert extrapolation_weights(n, order) @ x == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_weights_reproduce_polynomials_and_noise_gain():
    w = extrapolation_weights(10, 2)
    t = np.arange(10.0)
    assert w @ (3 - 2 * t + 0.5 * t**2) == pytest.approx(3 - 2 * 10 + 0.5 * 100)
    assert w.sum() == pytest.approx(1.0)
    # white-noise gain of the 10-point quadratic extrapolation (issue 5 quotes ~1.38)
    assert (w**2).sum() == pytest.approx(1.3833, abs=1e-3)


@pytest.mark.parametrize("n,order", [(100, 10), (64, 9), (30, 10), (50, 8)])
def test_weights_reproduce_polynomials_at_the_largest_settings(n, order):
    """fifo_depth <= 100 and fit_order <= 10 are allowed settings: the weights must still reproduce a
    constant and every polynomial up to the order (attack pass 37b: the raw Vandermonde of t = 0..99
    to the 10th power lost them in pinv, sum(w) = 0.26 for (100, 10), 1.61 for (64, 9), so the
    paper preset at fifo_depth=64, fit_order=9 read a constant 10 deg/s as 10.12)."""
    w = extrapolation_weights(n, order)
    t = np.arange(n) / n  # scaled so that every power is of order 1
    for k in range(order + 1):
        assert w @ t**k == pytest.approx(1.0, abs=1e-9)


def test_weight_table_rows_match_and_bad_args():
    table = weight_table(10, 2)
    for k in range(1, 11):
        np.testing.assert_allclose(table[k - 1, :k], extrapolation_weights(k, 2))
        assert not table[k - 1, k:].any()
    with pytest.raises(SettingsError):
        extrapolation_weights(0, 2)


def _loop_growth(gain, steps=400):
    """|x| after ``steps`` of the constant-gain loop x_k = (1 - K) sum w_i x_(k-10+i) + K y_k, y = 0,
    started from a unit impulse: the oracle for the root modulus (grows as radius^steps)."""
    w = extrapolation_weights(10, 2)
    x = np.zeros(steps + 10)
    x[9] = 1.0
    for k in range(10, steps + 10):
        x[k] = (1.0 - gain) * (w @ x[k - 10 : k])
    return np.abs(x[-10:]).max()


@pytest.mark.parametrize("gain,radius", [(0.1, 1.048), (0.3, 1.009), (0.5, 0.950), (0.6, 0.914), (0.7, 0.871)])
def test_closed_loop_radius_of_the_quadratic_prior(gain, radius):
    r = closed_loop_radius(10, 2, gain)
    assert r == pytest.approx(radius, abs=1e-3)
    # a direct simulation of the loop grows or decays at that rate
    assert np.log(_loop_growth(gain, 800) / _loop_growth(gain, 400)) / 400 == pytest.approx(np.log(r), abs=2e-3)


def test_stable_gain_threshold():
    k = stable_gain_threshold(10, 2)
    assert k == pytest.approx(0.335, abs=1e-3)
    assert closed_loop_radius(10, 2, k - 1e-3) > 1 > closed_loop_radius(10, 2, k + 1e-3)
    # the quadratic extrapolation alone (K = 0) continues any quadratic: a triple root at z = 1
    assert closed_loop_radius(10, 2, 0.0) == pytest.approx(1.0, abs=1e-4)
