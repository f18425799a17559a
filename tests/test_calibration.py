import json

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.calibration import Calibration, calibrate, stillness_z
from gyrofilter.errors import CalibrationError, SettingsError


def still(n=200, bias=(1.0, -2.0, 0.5), sigma=0.1, seed=0):
    rng = np.random.default_rng(seed)
    return np.asarray(bias) + rng.normal(0, sigma, (n, 3))


def test_still_window_gives_mean_bias_and_noise():
    x = still(2000)
    cal = calibrate(x, 100.0)
    np.testing.assert_allclose(cal.bias_dps, x.mean(axis=0))
    np.testing.assert_allclose(cal.noise_std_dps, 0.1, rtol=0.05)


def test_false_alarm_rate_of_the_stillness_check_is_low():
    # 300 still windows of white noise, quantised like an MPU6050: none may be refused
    for seed in range(300):
        x = np.round(still(200, seed=seed) * 131) / 131
        assert stillness_z(x).max() < 6.0


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_turn_during_calibration_is_refused(axis):
    x = still(200, seed=axis)
    x[120:160, axis] += 3.0  # a 0.4 s turn at 3 deg/s
    with pytest.raises(CalibrationError, match=f"axis {'xyz'[axis]}"):
        calibrate(x, 100.0)


def test_a_slow_ramp_is_refused_and_a_constant_spin_beyond_datasheet_bias_too():
    x = still(200)
    x[:, 2] += np.linspace(0, 1.5, 200)
    with pytest.raises(CalibrationError, match="moved"):
        calibrate(x, 100.0)
    with pytest.raises(CalibrationError, match="plausible bias"):
        calibrate(still(200, bias=(0, 45.0, 0)), 100.0)


def test_short_windows_of_low_sample_rates():
    with pytest.raises(SettingsError, match="at least 3 samples.*2 s at 1 Hz"):
        calibrate(still(2), 1.0)
    # 10 samples: 5 sub-windows of 2; a turn that speeds up is still refused
    x = still(10)
    assert calibrate(x, 5.0).bias_dps == pytest.approx(tuple(x.mean(axis=0)))
    x[:, 1] += np.linspace(0, 3.0, 10)
    with pytest.raises(CalibrationError, match="moved"):
        calibrate(x, 5.0)
    # 3 samples (3 s at 1 Hz): the mean and the noise level; too few to compare sub-windows
    x = still(3)
    x[2] += 1.0
    cal = calibrate(x, 1.0)
    assert cal.samples == 3 and min(cal.noise_std_dps) > 0


@pytest.mark.parametrize("preset", ["paper", "recommended"])
@pytest.mark.parametrize("rate_hz", [1.0, 2.0, 5.0])
def test_the_filter_runs_at_low_sample_rates(preset, rate_hz):
    rng = np.random.default_rng(int(rate_hz))
    x = np.array([0.5, -1.0, 2.0]) + rng.normal(0, 0.1, (600, 3))
    x[300:] += [10.0, 0.0, 0.0]                       # a turn at 10 deg/s after the first half
    f = GyroFilter(rate_hz, calibration_s=4.0, preset=preset)
    y = f.filter(x)
    n_cal = int(round(4.0 * rate_hz))
    assert len(y) == (600 - n_cal) // 5 and np.all(np.isfinite(y))
    assert np.allclose(y[-20:, 0], 10.0, atol=0.5)    # the turn is tracked
    with pytest.raises(SettingsError, match="at least 3"):
        GyroFilter(rate_hz, calibration_s=2.0 / rate_hz, preset=preset)


def test_save_load_round_trip_and_bad_files(tmp_path):
    cal = calibrate(still(500), 100.0)
    path = tmp_path / "cal.json"
    cal.save(path)
    assert Calibration.load(path) == cal
    path.write_text("{not json")
    with pytest.raises(CalibrationError, match="not a calibration JSON"):
        Calibration.load(path)
    path.write_text(json.dumps({"bias_dps": [1, 2], "noise_std_dps": [1, 1, 1], "samples": 3, "sample_rate_hz": 100}))
    with pytest.raises(CalibrationError, match="3 finite numbers"):
        Calibration.load(path)
    good = {"bias_dps": [1, 2, 3], "noise_std_dps": [0.1, 0.1, 0.1], "samples": 200, "sample_rate_hz": 100}
    for bad, message in (([], "expected an object"), ({**good, "sample_rate_hz": "abc"}, 'sample_rate_hz must be a finite number > 0, got "abc"'),
                         ({**good, "noise_std_dps": [0.1, -0.1, 0.1]}, "noise_std_dps must be 3 finite numbers >= 0"),
                         ({**good, "bias_dps": [1, "x", 3]}, "bias_dps must be 3 finite numbers, got"),
                         ({**good, "samples": 2.5}, "samples must be a whole number"),
                         ({**good, "sample_rate_hz": 0}, "sample_rate_hz must be a finite number > 0, got 0"),
                         ({k: v for k, v in good.items() if k != "samples"}, "lacks samples"),
                         ({**good, "temp_c": "warm"}, "temp_c must be a finite number")):
        path.write_text(json.dumps(bad))
        with pytest.raises(CalibrationError) as info:
            Calibration.load(path)
        assert str(info.value).startswith(f"{path}: ") and message in str(info.value), (bad, str(info.value))
    path.write_bytes(b"\x1f\x8b\x08binary")
    with pytest.raises(CalibrationError, match="not UTF-8 text"):
        Calibration.load(path)
    path.write_text(json.dumps(good))
    assert Calibration.load(path) == Calibration((1.0, 2.0, 3.0), (0.1, 0.1, 0.1), 200, 100.0)


def test_a_missing_calibration_file_is_a_calibration_error_naming_it(tmp_path):
    with pytest.raises(CalibrationError, match=r"nofile\.json: cannot read the calibration file"):
        Calibration.load(tmp_path / "nofile.json")


def test_a_window_with_a_non_finite_or_absurd_sample_is_refused_not_averaged():
    """calibrate() of a window with one NaN returned a NaN bias (NaN passes every comparison);
    1e300 an absurd one. Both are refused, naming the row and axis."""
    window = np.random.default_rng(4).normal(0, 0.05, (200, 3))
    for value, got in ((np.nan, "must be a finite number, got nan"), (1e300, "must be in [-100000, 100000], got 1e+300")):
        bad = window.copy()
        bad[17, 2] = value
        with pytest.raises(SettingsError) as info:
            calibrate(bad, 100.0)
        assert str(info.value) == f"calibration window row 17: gz (deg/s) {got}"
