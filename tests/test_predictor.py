import numpy as np
import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.predictor import extrapolation_weights, weight_table


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


def test_weight_table_rows_match_and_bad_args():
    table = weight_table(10, 2)
    for k in range(1, 11):
        np.testing.assert_allclose(table[k - 1, :k], extrapolation_weights(k, 2))
        assert not table[k - 1, k:].any()
    with pytest.raises(SettingsError):
        extrapolation_weights(0, 2)
