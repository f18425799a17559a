"""The start-up calibration leaves out gross errors (gyrofilter.filter.calibration, step 0).

Before: one spike in the still window was averaged into the bias and raised the noise, and the
stillness statistic, scaled by that noise, let the window pass whatever the spike's size (pass 37f:
30 deg/s at 1 s of a 100-Hz window moved the bias by 0.15 deg/s; the default filter read -0.12 deg/s
for 28 s of a still sensor).
"""
import json

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter
from gyrofilter.cli import main
from gyrofilter.errors import CalibrationError
from gyrofilter.evaluation.filters import startup_bias
from gyrofilter.filter.calibration import Calibration, calibrate, white_noise_std, without_settings
from gyrofilter.recording import Recording, read_recording, write_recording


def still(n, rng, bias=(0.3, -1.2, 0.8), sigma=0.05):
    return np.asarray(bias) + rng.normal(0, sigma, (n, 3))


@pytest.mark.parametrize("seed", range(12))
def test_a_spike_of_any_size_on_any_axis_is_left_out(seed):
    rng = np.random.default_rng(seed)
    rate_hz = float(rng.choice([50.0, 100.0, 1000.0]))
    n = int(2 * rate_hz)
    axis, at = int(rng.integers(3)), int(rng.integers(n))
    size = float(rng.choice([-1, 1]) * 10 ** rng.uniform(np.log10(3.0), np.log10(500.0)))
    x = still(n, rng)
    clean_noise = white_noise_std(x)
    x[at, axis] += size
    cal = calibrate(x, rate_hz)
    others = np.delete(x[:, axis], at)
    assert cal.bias_dps[axis] == pytest.approx(others.mean(), abs=1e-12)
    assert cal.rejected == tuple(int(a == axis) for a in range(3))
    np.testing.assert_allclose(cal.noise_std_dps, clean_noise, rtol=0.03)  # two differences of n left out


def test_the_default_filter_reads_zero_on_a_still_sensor_after_a_spike_in_its_window():
    rng = np.random.default_rng(3)
    x = still(3000, rng)
    x[100, 0] += 30.0  # 1 s into the 2-s window
    f = GyroFilter(100.0)
    y = f.filter(x)
    assert f.calibration.rejected == (1, 0, 0)
    assert np.abs(y.mean(axis=0)).max() < 0.01  # before: x read -0.12 deg/s


def test_a_tap_within_10_percent_is_left_out_and_a_longer_one_refused():
    rng = np.random.default_rng(4)
    x = still(200, rng)
    clean_noise = white_noise_std(x)
    x[50:68, 1] += 50.0  # 18 samples, 9 %
    cal = calibrate(x, 100.0)
    assert cal.rejected == (0, 18, 0)
    assert cal.bias_dps[1] == pytest.approx(np.delete(x[:, 1], range(50, 68)).mean(), abs=1e-12)
    assert cal.noise_std_dps[1] == pytest.approx(clean_noise[1], rel=0.1)  # its differences left out, not shrunk
    x[68:72, 1] += 50.0  # 22 samples, 11 %
    with pytest.raises(CalibrationError, match=r"the sensor moved \(axis y: 22 of 200 samples lie beyond 1 deg/s "
                                               r"of the window's median, more than the 20 gross errors"):
        calibrate(x, 100.0)


def test_no_sample_of_a_still_sensor_is_left_out():
    rng = np.random.default_rng(5)
    # a quiet quantized sensor: 99 % of samples on one code, the rest 1 LSB off (the spread is 0)
    codes = np.where(rng.random((2000, 3)) < 0.99, 0.0, rng.choice([-1.0, 1.0], (2000, 3)))
    x = (codes + [40, -100, 7]) / 131.0
    assert calibrate(x, 1000.0).rejected == (0, 0, 0)
    # a sensor much noisier than q (0.45 deg/s at 8 kHz) and many ordinary windows: none left out
    windows = [still(16000, rng, sigma=0.45)] + [np.round(still(200, rng) * 131) / 131 for _ in range(200)]
    for x in windows:
        cal = calibrate(x, 100.0)
        assert cal.rejected == (0, 0, 0)
        np.testing.assert_allclose(cal.bias_dps, x.mean(axis=0), rtol=0, atol=1e-12)


def test_the_evaluation_baselines_and_the_bias_filter_take_the_same_calibration():
    rng = np.random.default_rng(6)
    x = still(1000, rng)
    x[190, 2] -= 80.0
    cal = calibrate(x[:200], 100.0)
    assert cal.bias_dps[2] == pytest.approx(np.delete(x[:200, 2], 190).mean(), abs=1e-12)
    np.testing.assert_allclose(startup_bias(x, 100.0, 2.0)[0], cal.bias_dps, rtol=0, atol=1e-12)
    f = BiasKalmanFilter(100.0)
    for row in x[:201]:
        f.update(row)
    np.testing.assert_allclose(f.calibration.bias_dps, cal.bias_dps, rtol=0, atol=1e-12)
    assert f.still  # the spike in the window's last 0.5 s (its stillness ring) does not read as motion


def test_rejected_is_saved_loaded_and_checked(tmp_path):
    rng = np.random.default_rng(7)
    x = still(200, rng)
    x[10, 0] += 9.0
    path = tmp_path / "cal.json"
    calibrate(x, 100.0).save(path)
    assert json.loads(path.read_text())["rejected"] == [1, 0, 0]
    assert Calibration.load(path).rejected == (1, 0, 0)
    data = json.loads(path.read_text())
    del data["rejected"]  # a file written before the key: none
    path.write_text(json.dumps(data))
    assert Calibration.load(path).rejected == (0, 0, 0)
    for bad, message in [([0, -1, 0], "rejected y must be in [0, 200], got -1"),
                         ([0, 0, 201], "rejected z must be in [0, 200], got 201"),
                         ([0.5, 0, 0], "rejected x must be a whole number, got 0.5"),
                         ("1", "rejected must be a list of 3 numbers")]:
        path.write_text(json.dumps({**data, "rejected": bad}))
        with pytest.raises(CalibrationError) as info:
            Calibration.load(path)
        assert str(info.value).startswith(f"{path}: rejected") and message in str(info.value), str(info.value)


def test_replay_says_how_many_it_left_out(tmp_path, capsys):
    rng = np.random.default_rng(8)
    x = still(1000, rng)
    x[120, 1] += 25.0
    src = tmp_path / "still.csv"
    write_recording(src, Recording.from_dps(x, 5000.0))  # 0.2 s paced
    assert main(["replay", str(src), "--realtime", "--calibration-s", "0.04"]) == 0
    out = capsys.readouterr().out
    assert "# calibrated: bias " + ", ".join(f"{b:+.4f}" for b in calibrate(x[:200], 5000.0).bias_dps) + \
        " deg/s, gross errors left out: x 0, y 1, z 0\n" in out
    assert main(["replay", str(src), "--calibration-s", "0.04"]) == 0
    assert "start-up calibration, 200 samples, gross errors left out: x 0, y 1, z 0)" in capsys.readouterr().out


@pytest.mark.parametrize("n, rate_hz, length", [(3, 100.0, "0.03 s"), (9, 1000.0, "0.009 s"), (5, 1.0, "5.0 s")])
def test_a_window_too_short_to_leave_out_a_spike_says_its_length_and_to_raise_calibration_s(n, rate_hz, length):
    """A still window of fewer than 10 samples may leave out no gross error (10 %): one spike refused it saying
    "keep it still for the first 0.0 s" at 100 Hz (attack pass 37h), advice a still sensor cannot follow."""
    x = still(n, np.random.default_rng(n))
    x[1, 0] += 30.0
    with pytest.raises(CalibrationError, match=f"keep it still for the first {length}.*fewer than 10 samples "
                                               "can leave out no gross error: raise calibration_s") as info:
        calibrate(x, rate_hz)
    # report and evaluate take no calibration_s: the words name the commands that do
    assert without_settings(info.value, "report filters with the default settings").endswith(
        "can leave out no gross error: replay and run take --calibration-s")


def test_replay_out_header_names_the_samples_left_out(tmp_path):
    """Pass 37h: replay --out's header named the bias but not the gross errors left out of it."""
    x = still(1000, np.random.default_rng(9))
    x[50, 2] -= 40.0
    src, out = tmp_path / "still.csv", tmp_path / "out.csv"
    write_recording(src, Recording.from_dps(x, 1000.0))
    assert main(["replay", str(src), "--calibration-s", "0.2", "--out", str(out)]) == 0
    header = read_recording(out).header
    assert json.loads(header["calibration_rejected"]) == [0, 0, 1]
    assert json.loads(header["bias_dps"]) == pytest.approx(list(calibrate(x[:200], 1000.0).bias_dps))
