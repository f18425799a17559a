"""The Kalman kernels through GyroFilter: the adaptive filter's models and the divergence guard."""
import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.filter import adaptive_kalman

FS = 100.0
CAL = 200  # 2 s of calibration at 100 Hz


def still(n, seed, sigma=0.05):
    return np.random.default_rng(seed).normal(0.0, sigma, (n, 3))


def block_means(x, **settings):
    """The block means the Kalman stage sees (same calibration, bias and rejection)."""
    return GyroFilter(FS, preset="paper", tracker="block_mean", **settings).filter(x)


def test_adaptive_kalman_averages_at_rest_like_a_running_mean():
    # constant-rate model from P = R / n0 (n0 = 40 calibration blocks): x_k = mean of 0 (n0 times) and y_1..y_k
    x = still(CAL + 5 * 150, seed=1)
    f = GyroFilter(FS, preset="adaptive_kalman", backend="python")
    out = f.filter(x)
    y = block_means(x)
    n0 = CAL // 5
    expected = np.cumsum(y, axis=0) / (n0 + np.arange(1, len(y) + 1))[:, None]
    assert f._akf.switches == [0, 0, 0]
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)
    # far less noise than the block means (which the hold would also average)
    assert np.all(out[50:].std(axis=0) < y.std(axis=0) / 5)


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_adaptive_kalman_follows_a_25_dps_step_within_2_blocks(backend):
    x = still(CAL + 5 * 80, seed=2)
    k = 40  # the step starts exactly at block k
    x[CAL + 5 * k :] += 25.0
    out = GyroFilter(FS, preset="adaptive_kalman", backend=backend).filter(x)
    y = block_means(x)
    sigma_b = 0.05 / np.sqrt(5)
    assert np.all(np.abs(out[k - 1]) < 5 * sigma_b)  # still at rest before
    assert np.all(np.abs(out[k + 1] - y[k + 1]) < 5 * sigma_b)  # on the block means by the 2nd block
    assert np.all(np.abs(out[k:k + 2] - 25.0) < 1.0)


def test_the_guard_reseeds_the_filter_after_a_forced_divergence():
    # paper 001's noise statistics diverge on a 3-Hz, 150-deg/s sine (R from a window of moving
    # block means: the gain collapses and the quadratic extrapolation runs away)
    x = still(CAL + 5 * 400, seed=3)
    t = np.arange(len(x)) / FS
    x[CAL:, 0] += 150.0 * np.sin(2 * np.pi * 3.0 * (t[CAL:] - 2.0))
    y = block_means(x)
    sigma_b = 0.05 / np.sqrt(5)
    unguarded = GyroFilter(FS, preset="paper", backend="python").filter(x)
    f = GyroFilter(FS, preset="paper", guard_blocks=1, backend="python")
    guarded = f.filter(x)
    assert np.abs(unguarded[:, 0] - y[:, 0]).max() > 100  # it diverged
    assert f.guard_reseeds[0] > 0 and f.guard_reseeds[1:] == [0, 0]
    assert np.all(np.abs(guarded[:, 0] - y[:, 0]) < 10 * sigma_b)
    assert (guarded[:, 0] == y[:, 0]).sum() == f.guard_reseeds[0]  # each re-seed outputs the block mean
    np.testing.assert_array_equal(guarded[:, 1:], unguarded[:, 1:])  # the other axes are untouched


def test_the_adaptive_filter_recovers_by_itself_and_its_guard_reseeds():
    x = still(CAL + 5 * 60, seed=3)
    y = block_means(x)
    # a FIFO of posteriors running away quadratically, the LS model in use: the prior is 10^5 deg/s
    # off; the data are still, so the constancy test puts the axis back in the constant-rate model
    # with the mean of the latest 10 of its last 20 block means in that very block (hold.recent_mean)
    f = GyroFilter(FS, preset="adaptive_kalman", guard_blocks=0, backend="python")
    f.filter(x[: CAL + 5 * 30])
    f._akf.fifo[0, :] = np.roll(1e3 * np.arange(10.0) ** 2, f._akf.istate[adaptive_kalman.A_HEAD])
    f._akf.istate[adaptive_kalman.MODE] = adaptive_kalman.MOTION
    out = f.filter(x[CAL + 5 * 30 :])
    assert out[0, 0] == pytest.approx(y[21:31, 0].mean(), abs=1e-12)
    assert np.all(np.abs(out[:, 0] - y[30:, 0]) < 0.1)
    # the guard's re-seed path of the adaptive kernel: a limit so tight that every block counts
    g = GyroFilter(FS, preset="adaptive_kalman", guard_blocks=3, guard_k_sigma=1e-9, backend="python")
    out = g.filter(x)
    assert g.guard_reseeds == [len(y) // 3] * 3
    np.testing.assert_array_equal(out[2::3], y[2::3])
