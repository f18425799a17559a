"""Constant-rate hold with CUSUM change detection (gyrofilter.filter.hold)."""
import math

import numpy as np
import pytest

from gyrofilter.filter.hold import (ConstantRateHold, block_noise_std, chi2_lower_quantile, chi2_quantile,
                                   cusum_false_alarm_blocks)
from gyrofilter import GyroFilter
from gyrofilter.errors import SettingsError

SIGMA = 0.05  # deg/s, a block mean's noise


def test_chi2_quantile_matches_scipy():
    from scipy.stats import chi2

    for dof in (9, 19, 39):
        for p in (0.99, 0.999):
            assert chi2_quantile(p, dof) == pytest.approx(chi2.ppf(p, dof), rel=0.01)
    for dof in (19, 39, 99):  # the lower tail as block_noise_std uses it (m >= 20 blocks); at 9 dof it is 8 % low
        for p in (0.95, 0.999):
            assert chi2_lower_quantile(p, dof) == pytest.approx(chi2.ppf(1 - p, dof), rel=0.02)


def test_siegmund_run_length_by_hand():
    # (exp(2*0.5*(5 + 1.166)) - 2*0.5*6.166 - 1) / (2*0.25) = 938.1
    assert cusum_false_alarm_blocks(0.5, 5.0) == pytest.approx(938.1, abs=0.5)


def test_holds_white_noise_and_averages_it_down():
    rng = np.random.default_rng(10)
    y = rng.normal(scale=SIGMA, size=(20_000, 3))
    stage = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    out = stage.run(y, y)
    # false alarms are rare (about one per 1e5 blocks and side at h = 10) and cost a block or two
    assert sum(stage.switches) <= 6
    assert np.mean(out == y) < 1e-3
    # after max_blocks, an exponential mean with memory 400 blocks: std ~ sigma / sqrt(2 * 400 - 1)
    quiet = [a for a in range(3) if stage.switches[a] == 0]
    assert quiet
    for a in quiet:
        assert np.std(out[1000:, a]) == pytest.approx(SIGMA / math.sqrt(799), rel=0.25)
    assert np.all(np.std(out[1000:], axis=0) < SIGMA / 15)


def test_step_is_tracked_in_the_same_block_then_held():
    rng = np.random.default_rng(11)
    y = rng.normal(scale=SIGMA, size=(300, 3))
    y[100:, 0] += 1.0  # a 1 deg/s step on x (20 sigma)
    track = y + 1e-3  # a recognisable tracking output that agrees with the data
    stage = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    out = stage.run(y, track)
    is_track = out == track
    assert not is_track[99, 0] and is_track[100, 0]  # switched at the step block
    assert np.all(is_track[100:119, 0])  # tracking until the window (20 blocks) is constant again
    assert not is_track[-1, 0] and abs(out[-1, 0] - 1.0) < 4 * SIGMA / math.sqrt(20)  # held at the new level
    assert not is_track[:, 1:].any()  # the other axes never left hold


def test_slow_ramp_is_caught_within_a_few_blocks():
    y = np.zeros((200, 3))
    y[50:, 2] = 0.1 * np.arange(150)  # 2 deg/s^2 at 20 blocks/s: 0.1 deg/s per block = 2 sigma
    stage = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    out = stage.run(y, y)
    first_track = np.flatnonzero(out[:, 2] == y[:, 2])
    first_track = first_track[first_track >= 50][0]
    assert first_track - 50 <= 4


def test_streaming_equals_batch_and_numba_equals_python():
    rng = np.random.default_rng(12)
    y = rng.normal(scale=SIGMA, size=(3000, 3))
    y[1000:1500] += np.linspace(0, 20, 500)[:, None]
    y[1500:] += 20
    x = y + rng.normal(scale=0.01, size=y.shape)
    a = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    streamed = np.array([a.update(y[k], x[k]) for k in range(len(y))])
    b = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    batch = np.vstack([b.run(y[:1234], x[:1234]), b.run(y[1234:], x[1234:])])
    assert np.array_equal(streamed, batch)
    pytest.importorskip("numba")
    c = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="numba")
    assert np.allclose(c.run(y, x), batch, rtol=0, atol=1e-12)


def test_block_noise_std_white_and_coloured():
    rng = np.random.default_rng(13)
    w = rng.normal(scale=0.1, size=(20_000, 3))
    assert block_noise_std(w, 5) == pytest.approx(np.full(3, 0.1 / math.sqrt(5)), rel=0.05)
    # AR(1) noise with lag-1 correlation 0.8: block means are much noisier than sigma_w / sqrt(L)
    c = np.zeros_like(w)
    for i in range(1, len(w)):
        c[i] = 0.8 * c[i - 1] + w[i]
    means = c[: len(c) // 5 * 5].reshape(-1, 5, 3).mean(axis=1).std(axis=0)
    assert block_noise_std(c, 5) == pytest.approx(means, rel=0.01)


def test_bad_settings_raise():
    with pytest.raises(SettingsError):
        ConstantRateHold([SIGMA, SIGMA])
    with pytest.raises(SettingsError):
        ConstantRateHold([SIGMA] * 3, window_blocks=1)
    with pytest.raises(SettingsError):
        ConstantRateHold([SIGMA] * 3, cusum_h=-1)
    with pytest.raises(SettingsError):
        ConstantRateHold([SIGMA] * 3, accept_p=0.5)


def test_make_hold_from_window_or_from_a_loaded_calibration():
    from gyrofilter.filter.hold import make_hold

    rng = np.random.default_rng(14)
    window = rng.normal(scale=0.1, size=(200, 3))
    stage = make_hold(5, calibration_window_dps=window)
    assert stage.holding == [True, True, True]
    assert np.allclose(stage.sigma, block_noise_std(window, 5))
    loaded = make_hold(5, noise_std_dps=(0.1, 0.2, 0.3))
    assert loaded.holding == [False, False, False]
    assert np.allclose(loaded.sigma, np.array([0.1, 0.2, 0.3]) / math.sqrt(5))
    # a constant (simulated, noise-free) window must not give sigma 0
    assert np.all(make_hold(5, calibration_window_dps=np.ones((50, 3))).sigma > 0)
    with pytest.raises(SettingsError):
        make_hold(5)


def test_step_in_place_equals_run():
    rng = np.random.default_rng(15)
    y = rng.normal(scale=SIGMA, size=(500, 3))
    y[200:] += 3.0
    a = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    expected = a.run(y, y)
    b = ConstantRateHold([SIGMA] * 3, initial_blocks=40, backend="python")
    out = y.copy()
    for k in range(len(y)):
        row = out[k : k + 1]
        b.step(row, row, row)  # block mean as tracking output, written over itself
    assert np.array_equal(out, expected)


@pytest.mark.parametrize("preset", ["recommended", "hold"])
def test_after_a_turn_under_a_vibration_the_rest_reads_still(preset):
    """A new user's trial: a 90-degree turn about z under a 4-5 deg/s vibration; under the vibration sigma_b is large,
    the constancy test passed with the turn's tail in the window's older half, and the held value kept its mean:
    +0.3 deg/s for 7 s after the turn. The held value starts from the latest half (hold.recent_mean)."""
    fs, n = 100.0, 3000
    t = np.arange(n) / fs
    worst = 0.0
    for seed, (freq, amp) in enumerate([(33.0, 5.0), (45.0, 5.0), (10.0, 4.0), (27.0, 4.0)]):
        rng = np.random.default_rng(seed)
        x = np.array([-3.3, 1.1, -0.5]) + 0.1 * rng.standard_normal((n, 3))
        x[:, 2] += amp * np.sin(2 * np.pi * freq * t + rng.uniform(0, 2 * np.pi))
        turn = (t >= 10) & (t < 12)
        x[turn, 2] += 45 * (1 - np.cos(np.pi * (t[turn] - 10)))
        t_rows, rows = GyroFilter(fs, preset=preset).filter_timed(x, t)
        worst = max(worst, abs(rows[(t_rows > 13) & (t_rows <= 20), 2].mean()))
    assert worst < 0.06


@pytest.mark.parametrize("preset", ["recommended", "hold"])
@pytest.mark.parametrize("peak_dps,seconds,freq_hz", [(20.0, 3.0, 33.0), (10.0, 2.0, 23.0)])
def test_after_a_ramp_under_a_vibration_the_rest_reads_still(preset, peak_dps, seconds, freq_hz):
    """Attack pass 39: a rate ramp down to 0 under a 5-deg/s vibration, then rest. The chi-square constancy test has
    no power against a ramp where sigma_b is large (the vibrating calibration window's): the rest read +0.25 deg/s
    3-10 s after a 20 -> 0 deg/s ramp under 33 Hz. The constancy test also asks for no trend (hold.trend_free).
    Smaller ramps: test_after_a_small_ramp_under_a_vibration_the_rest_reads_still."""
    rng = np.random.default_rng(1)
    t = np.arange(3000) / 100.0
    x = np.array([0.8, -1.2, 0.4]) + 0.02 * rng.standard_normal((3000, 3))
    x[:, 2] += 5.0 * np.sin(2 * np.pi * freq_hz * t + rng.uniform(0, 2 * np.pi))
    ramp = (t >= 7) & (t < 7 + seconds)
    x[ramp, 2] += peak_dps * (1 - (t[ramp] - 7) / seconds)
    t_rows, rows = GyroFilter(100.0, preset=preset).filter_timed(x, t)
    after = (t_rows > 7 + seconds + 3) & (t_rows <= 7 + seconds + 10)
    assert abs(rows[after, 2].mean()) < 0.05


@pytest.mark.parametrize("preset", ["recommended", "hold"])
@pytest.mark.parametrize("peak_dps,seconds,freq_hz", [(5.0, 1.0, 45.0), (5.0, 1.0, 33.0), (10.0, 2.0, 45.0)])
def test_after_a_small_ramp_under_a_vibration_the_rest_reads_still(preset, peak_dps, seconds, freq_hz):
    """Attack pass 40: under a 5-deg/s vibration from power-up that the blocks average out, sigma_w / sqrt(L) of the
    calibration window is 4x the block means' scatter (2.2 against 0.5 deg/s at 45 Hz); the rest model missed the
    tail of a small ramp and read +0.36 deg/s 3-10 s after 5 -> 0 deg/s in 1 s, on every seed. sigma_b now
    follows the block means' scatter where it is significantly below the white-noise level (block_noise_std).
    One seed of five at 45 Hz still reads 0.14 (the window that holds the whole ramp passes: docs/evaluate.md)."""
    t = np.arange(3000) / 100.0
    after = []
    for seed in range(1, 6):
        rng = np.random.default_rng(seed)
        x = np.array([0.8, -1.2, 0.4]) + 0.02 * rng.standard_normal((3000, 3))
        x[:, 2] += 5.0 * np.sin(2 * np.pi * freq_hz * t + rng.uniform(0, 2 * np.pi))
        ramp = (t >= 7) & (t < 7 + seconds)
        x[ramp, 2] += peak_dps * (1 - (t[ramp] - 7) / seconds)
        t_rows, rows = GyroFilter(100.0, preset=preset).filter_timed(x, t)
        after.append(abs(rows[(t_rows > 7 + seconds + 3) & (t_rows <= 7 + seconds + 10), 2].mean()))
    assert np.median(after) < 0.03 and max(after) < 0.2


def test_sigma_b_of_a_white_window_is_its_white_noise_level_and_of_a_vibrating_one_its_block_means_scatter():
    """block_noise_std: white noise keeps max(s_b, sigma_w / sqrt(L)) on every seed; a 45-Hz vibration's window gets
    the upper 95 % bound of its block means' scatter, never below a quarter of the white-noise level."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        white = rng.normal(0, 0.1, (200, 3))
        np.testing.assert_allclose(block_noise_std(white, 5), 0.1 / math.sqrt(5), rtol=0.35)
    t = np.arange(200) / 100.0
    for amplitude in (1.0, 5.0):
        vibrating = rng.normal(0, 0.02, (200, 3)) + amplitude * np.sin(2 * np.pi * 45.0 * t[:, None] + [0, 1, 2])
        level = np.std(np.diff(vibrating, axis=0), axis=0, ddof=1) / math.sqrt(2 * 5)
        means = vibrating.reshape(40, 5, 3).mean(axis=1).std(axis=0, ddof=1)
        bound = means * math.sqrt(39 / chi2_lower_quantile(0.95, 39))
        np.testing.assert_allclose(block_noise_std(vibrating, 5), np.maximum(bound, 0.25 * level))
        assert np.all(block_noise_std(vibrating, 5) < 0.5 * level)


def test_sigma_b_of_the_shipped_recordings_windows_is_the_plain_rule():
    """The vibration rule must not touch a still sensor's window: a chi-square significance test (tried) took the
    real 655-s log's z window (block means' scatter 0.61 of the white level) for a vibration, and its copy with
    spikes lost a fifth of its static reduction; a trigger at 0.5 with 20 blocks (attack pass 43) took the same
    log's z at sample 55000 for one (0.49: 4 false switches, 3x the output std). Every 50th 2-s window of the shipped
    static logs keeps the plain rule."""
    from pathlib import Path

    from gyrofilter.filter.calibration import white_noise_std, without_gross_errors
    from gyrofilter.recording import read_recording

    paths = sorted((Path(__file__).resolve().parents[1] / "recordings").glob("*static*.csv.gz"))
    assert len(paths) >= 5
    for path in paths:
        rec = read_recording(path)
        n = int(2 * rec.sample_rate_hz)
        for start in [*range(0, len(rec.gyro_dps) - n, 50), 55000][: None if "655s" in path.name else -1]:
            window = without_gross_errors(rec.gyro_dps[start : start + n], 1.0)[0]
            m = len(window) // 5
            plain = np.maximum(window[: 5 * m].reshape(m, 5, 3).mean(axis=1).std(axis=0, ddof=1),
                               white_noise_std(window) / math.sqrt(5))
            np.testing.assert_array_equal(block_noise_std(window, 5), plain, err_msg=f"{path.name} at {start}")


def test_sigma_b_of_a_window_whose_few_block_means_are_equal_is_its_white_noise_level():
    """Attack pass 40: a cap of sigma_b at the block means' spread (tried) gave 0 for a short window of a quantised
    sensor whose two block means were equal, and the filter stopped averaging (20x the output std). sigma_b keeps
    sigma_w / sqrt(L)."""
    window = np.tile(np.array([[0.0], [0.05], [-0.05], [0.05], [-0.05]]), (2, 3))  # two blocks of 5, both of mean 0
    expected = np.std(np.diff(window, axis=0), axis=0, ddof=1) / math.sqrt(2 * 5)
    np.testing.assert_allclose(block_noise_std(window, 5), expected, rtol=0.3)
    assert np.all(block_noise_std(window, 5) > 0.01)


def _vibration_after_calibration(t, rng, amplitude, start_s, end_s=None):
    """A 45-Hz vibration of ``amplitude`` deg/s on every axis from ``start_s`` (ramped in over 2 s) to ``end_s``."""
    on = np.clip((t - start_s) / 2, 0, 1) * (t < (end_s if end_s is not None else np.inf))
    return (on * amplitude)[:, None] * np.sin(2 * np.pi * 45.0 * t[:, None] + rng.uniform(0, 2 * np.pi, 3))


@pytest.mark.parametrize("preset", ["recommended", "hold"])
def test_a_real_motion_under_or_after_a_vibration_is_never_taken_for_noise(preset):
    """Attack pass 42 (against a noise scale taken from the windows after the calibration, tried and dropped): under
    or after a vibration that began after the calibration, a clean 1-deg/s turn was held as noise (heading error
    4.1-7.8 degrees) and a 2-Hz swing flattened (correlation with the truth 0.15). The rest model's sigma_b is the
    calibration's: the turns are tracked (heading error <= 0.33 degrees) and the swing followed (0.81)."""
    fs = 100.0
    t = np.arange(int(45 * fs)) / fs
    for seed in range(3):
        rng = np.random.default_rng(seed)
        for truth, vibration in (
            (np.where((t >= 20) & (t < 25), 1.0, 0.0), _vibration_after_calibration(t, rng, 10.0, 5.0, 15.0)),
            (np.where((t >= 20) & (t < 23), 1.0, 0.0), _vibration_after_calibration(t, rng, 5.0, 5.0)),
        ):
            x = rng.normal(0, 0.05, (len(t), 3)) + vibration
            x[:, 2] += truth
            rows = GyroFilter(fs, preset=preset).filter(x)[:, 2]
            blocks = truth[200 : 200 + 5 * len(rows)].reshape(-1, 5).mean(axis=1)
            after = slice((17 - 2) * 20, None)
            assert abs((rows[after] - blocks[after]).sum() * 5 / fs) < 1.0, seed
    swing = np.where((t >= 20) & (t < 40), 2.0 * np.sin(2 * np.pi * 2.0 * t), 0.0)
    x = np.random.default_rng(1).normal(0, 0.05, (len(t), 3)) + _vibration_after_calibration(t, rng, 10.0, 5.0)
    x[:, 2] += swing
    rows = GyroFilter(fs, preset=preset).filter(x)[:, 2]
    blocks = swing[200 : 200 + 5 * len(rows)].reshape(-1, 5).mean(axis=1)
    during = slice((21 - 2) * 20, (39 - 2) * 20)
    assert np.corrcoef(rows[during], blocks[during])[0, 1] > 0.5
