"""Bias-augmented Kalman filter: bias tracking at rest, no drift in motion, streaming = batch, filterpy oracle."""
import math

import numpy as np
import pytest

from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter, BiasKFSettings
from gyrofilter.filter.calibration import Calibration
from gyrofilter.errors import SettingsError

FS = 100.0
BIAS0 = np.array([1.0, -0.5, 0.3])
STEP = np.array([0.3, -0.2, 0.1])


def scenario(seed, step_at_s=50.0, duration_s=80.0, noise_dps=0.1):
    """Rest 0-20 s, motion 20-40 s (sines up to 80 deg/s), rest 40-80 s; bias steps at ``step_at_s``."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * FS)) / FS
    rate = np.zeros((len(t), 3))
    m = (t >= 20) & (t < 40)
    tm = t[m] - 20
    rate[m] = np.column_stack([50 * np.sin(2 * np.pi * 0.5 * tm), 20 * np.sin(2 * np.pi * 1.3 * tm),
                               80 * np.sin(2 * np.pi * 0.2 * tm)])
    bias = np.tile(BIAS0, (len(t), 1))
    bias[t >= step_at_s] += STEP
    return t, rate, bias, rate + bias + rng.normal(0, noise_dps, (len(t), 3))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tracks_a_bias_step_during_rest(seed):
    t, rate, bias, x = scenario(seed)
    tr = BiasKalmanFilter(FS).run(x)
    n0 = len(x) - len(tr.bias_dps)
    err = tr.bias_dps - bias[n0:]
    at = lambda s: int(s * FS) - n0  # noqa: E731
    # start-up-only calibration is off by the whole step after it; the filter converges
    startup_err = np.abs(np.asarray(tr.calibration.bias_dps) - bias[at(75) + n0])
    assert np.allclose(startup_err, np.abs(STEP), atol=0.035)  # 5 sigma of a 2 s mean
    assert np.all(np.abs(err[at(70) :]) < 0.03)
    assert np.all(np.abs(err[at(75)]) < 0.2 * np.abs(STEP))
    # rest is detected as rest
    assert tr.still[at(60) : at(80) - 1].mean() > 0.95


@pytest.mark.parametrize("seed", [0, 1])
def test_bias_does_not_drift_during_motion(seed):
    t, rate, bias, x = scenario(seed)
    tr = BiasKalmanFilter(FS).run(x)
    n0 = len(x) - len(tr.bias_dps)
    i20, i40 = int(20 * FS) - n0, int(40 * FS) - n0
    assert tr.still[i20 + 5 : i40].mean() < 0.01  # motion is not taken for rest
    drift = np.abs(tr.bias_dps[i40 - 1] - tr.bias_dps[i20])
    assert np.all(drift < 0.005)
    # and the rate output follows the motion
    assert np.sqrt(np.mean((tr.rate_dps[i20:i40] - rate[i20 + n0 : i40 + n0]) ** 2)) < 0.2


def test_streaming_equals_batch():
    _, _, _, x = scenario(3, duration_s=30.0)
    batch = BiasKalmanFilter(FS).run(x)
    f = BiasKalmanFilter(FS)
    rows, biases = [], []
    for sample in x:
        y = f.update(tuple(sample))
        if y is not None:
            rows.append(y)
            biases.append(f.bias_dps)
    assert np.array_equal(np.array(rows), batch.rate_dps)
    assert np.array_equal(np.array(biases), batch.bias_dps)
    assert np.array_equal(BiasKalmanFilter(FS).filter(x), batch.rate_dps)


def test_numpy_kernel_matches_filterpy():
    _, _, _, x = scenario(4, step_at_s=25.0, duration_s=30.0)
    settings = BiasKFSettings(bias_tau_s=(math.inf, 50.0, 5.0), bias_sigma_dps=0.1)
    a = BiasKalmanFilter(FS, settings).run(x)
    b = BiasKalmanFilter(FS, settings, engine="filterpy").run(x)
    assert np.array_equal(a.still, b.still)
    assert np.allclose(a.rate_dps, b.rate_dps, atol=1e-9)
    assert np.allclose(a.bias_dps, b.bias_dps, atol=1e-9)
    assert np.allclose(a.bias_std_dps, b.bias_std_dps, rtol=1e-9)


def test_slow_constant_rotation_is_not_learnt_as_bias():
    rng = np.random.default_rng(5)
    n = int(30 * FS)
    x = BIAS0 + rng.normal(0, 0.1, (n, 3))
    x[int(10 * FS) :, 2] += 5.0  # a steady 5 deg/s turn: no variance, but far from the bias
    tr = BiasKalmanFilter(FS).run(x)
    n0 = n - len(tr.bias_dps)
    assert not tr.still[int(11 * FS) - n0 :].any()
    assert abs(tr.bias_dps[-1, 2] - BIAS0[2]) < 0.01
    assert tr.rate_dps[-1, 2] == pytest.approx(5.0, abs=0.5)


def test_gauss_markov_bias_relaxes_to_the_calibration_when_unobserved():
    # with tau = 1 s and no rest, the deviation state decays like exp(-t/tau)
    cal = Calibration((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), 200, FS)
    f = BiasKalmanFilter(FS, BiasKFSettings(bias_tau_s=1.0, bias_sigma_dps=0.5), calibration=cal)
    for state in f._x:
        state[1] = 0.2  # a learnt deviation d
    rng = np.random.default_rng(6)
    moving = 30 * np.sin(np.arange(300) / 10.0)[:, None] + rng.normal(0, 0.1, (300, 3))
    f.run(moving)
    assert np.all(np.abs(np.asarray(f.bias_dps)) < 0.2 * math.exp(-2.0))


def test_settings_from_arma_bias_model():
    from gyrofilter.analysis.arma.identify import BiasModel

    model = BiasModel(tau_s=100.0, bias_sigma_dps=0.01, bias_walk_dps_per_sqrt_s=0.0014, white_noise_dps_per_sqrt_hz=0.01, valid=True)
    s = BiasKFSettings.from_bias_model(model, calibration_s=1.0)
    f = BiasKalmanFilter(FS, s)
    assert f._phi == pytest.approx(np.full(3, math.exp(-0.01 / 100.0)))
    assert f._q_b == pytest.approx(np.full(3, 0.01**2 * (1 - math.exp(-0.02 / 100.0))))
    with pytest.raises(SettingsError):
        BiasKFSettings.from_bias_model(BiasModel(math.inf, 0.0, 0.0, 0.01, False))


def test_bad_settings():
    with pytest.raises(SettingsError, match="still_exit_ratio"):
        BiasKalmanFilter(FS, still_enter_ratio=3.0, still_exit_ratio=2.0)
    with pytest.raises(SettingsError, match="engine"):
        BiasKalmanFilter(FS, engine="cuda")
    with pytest.raises(SettingsError, match="calibration_s"):
        BiasKalmanFilter(FS, calibration_s=0.05)
    with pytest.raises(SettingsError, match="shape"):
        BiasKalmanFilter(FS).run(np.zeros((10, 2)))


def test_samples_after_the_calibration_are_checked_as_the_filter_checks_them():
    """Attack pass 22: the calibration window refused a NaN, but one NaN after it made every later
    rate and bias NaN (2500 of 2500 rows, no word); a masked 1e4 was filtered as data, an inf taken."""
    from gyrofilter.errors import SampleError

    x = np.random.default_rng(0).normal(0, 0.05, (3000, 3))
    bad = x.copy()
    bad[500, 0] = np.nan
    with pytest.raises(SampleError, match="row 500"):
        BiasKalmanFilter(FS).run(bad)
    masked = np.ma.masked_array(x, mask=np.arange(x.size).reshape(x.shape) == 1500)
    with pytest.raises(SampleError, match="row 500 is masked"):
        BiasKalmanFilter(FS).run(masked)
    f = BiasKalmanFilter(FS)
    for row in x[:400]:
        f.update(row)
    with pytest.raises(SampleError, match="finite"):
        f.update([math.inf, 0.0, 0.0])
    assert all(math.isfinite(v) for v in f.update(x[400]))


@pytest.mark.parametrize("name", ["bias_tau_s", "bias_sigma_dps", "bias_walk_dps_per_sqrt_s", "noise_std_dps"])
def test_an_array_of_3_per_axis_values_is_the_3_numbers(name):
    """Attack pass 31b: a per-axis setting given as a numpy array of 3 ended in numpy's "truth
    value of an array ... is ambiguous" (``bias_tau_s``) or was refused as "a finite number"
    (the others; taken before pass 30a): the 3 numbers, as a tuple of them is; an array of
    another shape refused, naming the setting."""
    as_tuple = BiasKalmanFilter(100.0, **{name: (10.0, 20.0, 30.0)}).settings
    assert BiasKalmanFilter(100.0, **{name: np.array([10.0, 20.0, 30.0])}).settings == as_tuple
    for bad in (np.ones((1, 3)), np.array([1.0, 2.0])):
        with pytest.raises(SettingsError, match=name):
            BiasKalmanFilter(100.0, **{name: bad})


@pytest.mark.parametrize("field, value", [("bias_dps", (math.nan, 0.0, 0.0)), ("noise_std_dps", (math.nan, 0.1, 0.1)),
                                          ("bias_dps", (500.0, 0.0, 0.0)), ("noise_std_dps", (-1.0, 0.1, 0.1)),
                                          ("samples", 0), ("bias_dps", "abc"), ("bias_dps", np.array(1.0))])
def test_a_calibration_given_in_code_is_checked_as_the_filters_is(field, value):
    """Attack pass 31b: ``BiasKalmanFilter(calibration=...)`` took a Calibration made in code as it
    was: a NaN bias or noise gave NaN rates, a 500 deg/s bias or a negative noise were used, a
    text ended in numpy's ValueError (GyroFilter refuses each: ``Calibration.checked``, one check),
    and a 0-d array of a bias in Python's "len() of unsized object" in both filters."""
    from gyrofilter import GyroFilter
    from gyrofilter.errors import CalibrationError
    args = dict(bias_dps=(0.5, 0.5, 0.5), noise_std_dps=(0.1, 0.1, 0.1), samples=200, sample_rate_hz=100.0)
    cal = Calibration(**{**args, field: value})
    for make in (BiasKalmanFilter, GyroFilter):
        with pytest.raises(CalibrationError, match=field):
            make(100.0, calibration=cal)
