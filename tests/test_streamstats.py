import numpy as np
import pytest

from gyrofilter.streamstats import Envelope, RunningMoments


def _chunks(x, rng):
    cuts = np.sort(rng.choice(np.arange(1, len(x)), size=20, replace=False))
    return np.split(x, cuts)


def test_running_moments_equal_numpy_two_pass_even_on_a_large_mean():
    rng = np.random.default_rng(0)
    # a sum of squares would lose the 1e-3 spread under a 1e6 mean (cancellation: ~1e-4 relative)
    x = np.array([1e6, -2.0, 5.0]) + rng.normal(0, [1e-3, 0.1, 2.0], (5000, 3))
    m = RunningMoments(3)
    for chunk in _chunks(x, rng):
        m.add(chunk)
    assert m.count == 5000
    np.testing.assert_allclose(m.mean, x.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(m.std, x.std(axis=0, ddof=1), rtol=1e-6)


def test_running_moments_undefined_below_two_rows():
    m = RunningMoments(3)
    m.add(np.ones((1, 3)))
    assert np.isnan(m.std).all() and m.mean.tolist() == [1, 1, 1]


def test_a_constant_column_has_a_std_of_exactly_zero():
    """Issue 37: -3.3 is no binary fraction; the chunks' rounded means left a std of ~1e-15."""
    rng = np.random.default_rng(7)
    x = np.column_stack([np.full(3000, -3.3), np.full(3000, 3 / 131), rng.normal(0, 1e-12, 3000)])
    m = RunningMoments(3)
    for chunk in _chunks(x, rng):
        m.add(chunk)
    assert m.std[:2].tolist() == [0.0, 0.0] and m.std[2] == pytest.approx(x[:, 2].std(ddof=1), rel=1e-6)


@pytest.mark.parametrize("n", [1, 7, 100, 10_007])
def test_envelope_buckets_hold_the_min_and_max_of_consecutive_rows(n):
    rng = np.random.default_rng(n)
    x = rng.normal(size=(n, 2))
    t = np.arange(n) * 0.1
    env = Envelope(2, max_buckets=16)
    cuts = np.sort(rng.integers(0, n + 1, 6))
    for part in np.split(np.arange(n), cuts):
        env.add(t[part], x[part])
    b = env.bucket
    assert len(env.t_s) <= 16 and (n <= 16 or len(env.t_s) >= 8)
    starts = np.arange(0, n, b)
    np.testing.assert_array_equal(env.t_s, t[starts])
    np.testing.assert_array_equal(env.low, np.minimum.reduceat(x, starts, axis=0))
    np.testing.assert_array_equal(env.high, np.maximum.reduceat(x, starts, axis=0))
