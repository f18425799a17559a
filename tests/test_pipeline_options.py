"""Opt-in pipeline settings: the median_slope gross-error rule and temperature compensation."""
import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.filter.averaging import (average_block_line_if_cut, average_block_median_slope, average_blocks,
                                  average_blocks_line_if_cut, average_blocks_median_slope)
from gyrofilter.filter.calibration import Calibration
from gyrofilter.errors import SettingsError
from gyrofilter.filter.tempcomp import coefficients_from_model
from support import stream

FS = 100.0


# ---------------------------------------------------------------- by_model (the adaptive filter's rule)


def test_by_model_keeps_the_paper_rule_at_rest_and_the_median_slope_rule_in_motion():
    rng = np.random.default_rng(11)
    cal, rest, moving = 200, 1000, 2000
    x = rng.normal(0.0, 0.05, (cal + rest + moving, 3))
    spikes = cal + rng.choice(rest, 40, replace=False)
    x[spikes, 0] += 3.0  # gross errors at rest
    t = np.arange(moving) / FS
    truth = 30.0 * np.sin(2 * np.pi * 1.0 * t)  # a 1-Hz sine: the rate changes by ~4 deg/s within a block
    x[cal + rest :, 1] += truth
    # q fixed (outlier_range_k=0): a q that follows the range keeps the sine's samples by itself
    by_model = GyroFilter(FS, preset="adaptive_kalman", backend="python", outlier_range_k=0)
    paper_rule = GyroFilter(FS, preset="adaptive_kalman", outlier_rule="paper", backend="python", outlier_range_k=0)
    out_m, out_p = by_model.filter(x), paper_rule.filter(x)
    m_rest = rest // 5
    # at rest: the same numbers as the paper's rule (the filter stays in its constant-rate model)
    np.testing.assert_array_equal(out_m[:m_rest], out_p[:m_rest])
    assert by_model.rejected[0] == paper_rule.rejected[0] >= 35
    # in motion: the paper's rule rejects real samples and biases the block means, by_model does not
    blocks = truth[: 5 * ((moving) // 5)].reshape(-1, 5).mean(axis=1)
    err = lambda out: np.sqrt(np.mean((out[m_rest + 10 :, 1] - blocks[10:]) ** 2))  # noqa: E731
    assert err(out_m) < 0.5 * err(out_p)
    assert by_model.rejected[1] < 0.1 * paper_rule.rejected[1]
    # streaming gives the same rows and counts
    f = GyroFilter(FS, preset="adaptive_kalman", backend="python")
    np.testing.assert_array_equal(stream(f, x), out_m)
    assert f.rejected.tolist() == by_model.rejected.tolist()
    assert f.fallback_blocks.tolist() == by_model.fallback_blocks.tolist()


def test_the_motion_rule_is_the_mean_unless_the_paper_rule_cuts_and_its_two_paths_agree():
    rng = np.random.default_rng(5)
    blocks = rng.normal(0.0, 0.1, (600, 5, 3)) + np.cumsum(rng.normal(0.0, 0.6, (600, 5, 3)), axis=1)
    blocks[::13, 2, 0] += 4.0  # spikes
    out, replaced, fallback = average_blocks_line_if_cut(blocks, 1.0)
    paper, rejected, _ = average_blocks(blocks, 1.0)
    line, line_replaced, _ = average_blocks_median_slope(blocks, 1.0)
    cut = rejected > 0
    assert 0.2 < cut.mean() < 0.9 and not fallback.any()
    np.testing.assert_array_equal(out[~cut], paper[~cut])
    np.testing.assert_array_equal(out[cut], line[cut])
    np.testing.assert_array_equal(replaced, np.where(cut, line_replaced, 0))
    for k in range(0, 600, 7):
        for a in range(3):
            value, n, _ = average_block_line_if_cut(blocks[k, :, a].tolist(), 1.0)
            assert value == out[k, a] and n == replaced[k, a]


def test_by_model_needs_the_adaptive_kalman_filter():
    for kw in ({"preset": "paper"}, {"preset": "hold"}, {"preset": "adaptive_kalman", "tracker": "block_mean"}):
        with pytest.raises(SettingsError, match="by_model"):
            GyroFilter(FS, outlier_rule="by_model", **kw)


# ---------------------------------------------------------------- median_slope


@pytest.mark.parametrize("length", [2, 3, 4, 5, 6, 7])
def test_median_slope_streaming_and_vectorised_agree_bit_for_bit(length):
    rng = np.random.default_rng(length)
    blocks = rng.normal(size=(500, length, 3)) * rng.choice([0.05, 3.0], size=(500, length, 3))
    blocks += np.cumsum(rng.normal(size=(500, length, 3)), axis=1)  # ramps of every slope
    out, replaced, fallback = average_blocks_median_slope(blocks, 1.0)
    assert not fallback.any()
    for k in range(0, 500, 7):
        for a in range(3):
            value, n, _ = average_block_median_slope(blocks[k, :, a].tolist(), 1.0)
            assert value == out[k, a] and n == replaced[k, a]


def test_median_slope_keeps_fast_smooth_motion_that_the_paper_rule_cuts():
    # a 3-Hz, 200-deg/s sine at 100 Hz: the rate moves by up to 38 deg/s within a sample
    rng = np.random.default_rng(3)
    t = np.arange(2000) / 100.0
    truth = (200.0 * np.sin(2 * np.pi * 3.0 * t))[:, None] * np.ones(3)
    blocks = (truth + rng.normal(0, 0.1, truth.shape)).reshape(400, 5, 3)
    true_means = truth.reshape(400, 5, 3).mean(axis=1)
    paper, paper_rej, _ = average_blocks(blocks, 1.0)
    robust, robust_rej, _ = average_blocks_median_slope(blocks, 1.0)
    assert paper_rej.sum() > 1000                                   # the paper's rule rejects real motion
    assert robust_rej.sum() <= 0.001 * blocks.size                 # almost nothing replaced
    rmse = [np.sqrt(np.mean((y - true_means) ** 2)) for y in (paper, robust)]
    assert rmse[0] > 2.0 and rmse[1] < 0.1, rmse


@pytest.mark.parametrize("slope,low", [(0.0, 1.5), (3.0, 5.0)])
def test_median_slope_replaces_a_spike_by_the_line(slope, low):
    # at rest spikes beyond q go (a few of 1.5-3 deg/s slip through: the line through 5 noisy
    # samples widens the limit); on a 3-deg/s-per-sample ramp spikes from 5 deg/s go
    rng = np.random.default_rng(5)
    n = 2000
    blocks = slope * np.arange(5)[None, :, None] + rng.normal(0, 0.1, (n, 5, 3))
    clean = blocks.mean(axis=1)
    where = rng.integers(0, 5, size=n)
    blocks[np.arange(n), where, 0] += rng.choice([-1, 1], size=n) * rng.uniform(low, 50.0, size=n)
    robust, replaced, _ = average_blocks_median_slope(blocks, 1.0)
    assert replaced[:, 0].sum() >= 0.995 * n and replaced[:, 1:].sum() <= n // 100
    err = np.abs(robust[:, 0] - clean[:, 0])
    assert np.median(err) < 0.05 and np.mean(err < 0.3) >= 0.995     # a 50-deg/s spike leaves < 0.3 deg/s
    assert np.median(np.abs(blocks.mean(axis=1)[:, 0] - clean[:, 0])) > 1.0


def test_median_slope_in_the_pipeline_streams_like_the_batch_and_counts():
    rng = np.random.default_rng(8)
    x = rng.normal(0, 0.1, (4000, 3)) + [0.5, -1.0, 2.0]
    x[1000:3000] += np.linspace(0, 400, 2000)[:, None]
    x[rng.random((4000, 3)) < 0.01] += 5.0
    for preset in ("paper", "recommended"):
        a = stream(GyroFilter(FS, preset=preset, outlier_rule="median_slope"), x)
        f = GyroFilter(FS, preset=preset, outlier_rule="median_slope")
        assert np.array_equal(a, f.filter(x))
        assert f.rejected.sum() > 0 and f.fallback_blocks.sum() == 0


# ---------------------------------------------------------------- temperature


def warming(n, coef, seed=0):
    """Still sensor whose bias follows c (T - 25), T warming from 30 to 45 deg C."""
    rng = np.random.default_rng(seed)
    temps = 30.0 + 15.0 * (1 - np.exp(-np.arange(n) / (0.3 * n)))
    x = np.array([1.0, -2.0, 0.5]) + np.outer(temps - 25.0, coef) + rng.normal(0, 0.1, (n, 3))
    return x, temps


def test_temperature_compensation_removes_a_known_drift():
    coef = (0.02, -0.05, 0.0)
    x, temps = warming(30000, coef)
    plain = GyroFilter(FS, preset="recommended").filter(x)
    comp = GyroFilter(FS, preset="recommended", temp_coefficient_dps_per_c=coef).filter(x, temps)
    late = slice(-1000, None)
    # uncompensated: the bias learnt at ~30 C is wrong by c * (T - T0) once warm
    assert abs(plain[late, 1].mean()) > 0.5
    assert np.abs(comp[late].mean(axis=0)).max() < 0.03     # the calibration's own error: 0.1 / sqrt(200)
    assert np.array_equal(comp[:, 2], plain[:, 2])          # c = 0 on z: untouched


def test_temperature_compensation_streams_like_the_batch_and_saves_t0(tmp_path):
    x, temps = warming(5000, (0.03, 0.01, -0.02), seed=1)
    f = GyroFilter(FS, preset="paper", temp_coefficient_dps_per_c=(0.03, 0.01, -0.02))
    whole = f.filter(x, temps)
    parts = GyroFilter(FS, preset="paper", temp_coefficient_dps_per_c=(0.03, 0.01, -0.02))
    pieces = [parts.filter(x[:333], temps[:333]), stream(parts, x[333:1001], temps[333:1001]), parts.filter(x[1001:], temps[1001:])]
    assert np.array_equal(np.concatenate(pieces), whole)
    assert f.calibration.temp_c == pytest.approx(temps[:200].mean())
    path = tmp_path / "cal.json"
    f.calibration.save(path)
    loaded = GyroFilter(FS, preset="paper", calibration=path, temp_coefficient_dps_per_c=(0.03, 0.01, -0.02))
    assert loaded.calibration.temp_c == f.calibration.temp_c
    # its running median of T starts without the window's temperatures (the first 10 of fewer): c x their noise
    assert np.allclose(loaded.filter(x[200:], temps[200:]), whole, rtol=0, atol=0.01)


def test_temperature_compensation_refuses_missing_temperatures():
    x, temps = warming(1000, (0.01, 0.01, 0.01))
    f = GyroFilter(FS, preset="paper", temp_coefficient_dps_per_c=0.01)
    with pytest.raises(SettingsError, match="needs temp_c"):
        f.filter(x)
    with pytest.raises(SettingsError, match="shape"):
        f.filter(x, temps[:-1])
    bad = temps.copy()
    bad[17] = np.nan
    with pytest.raises(SettingsError, match="row 17"):
        f.filter(x, bad)
    with pytest.raises(SettingsError, match="needs temp_c"):
        f.update((0.0, 0.0, 0.0))
    no_temp = Calibration((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), 200, FS)
    with pytest.raises(SettingsError, match="has none"):
        GyroFilter(FS, preset="paper", calibration=no_temp, temp_coefficient_dps_per_c=0.01)
    with pytest.raises(SettingsError, match="needs a start-up calibration"):
        GyroFilter(FS, preset="paper", calibration_s=0, temp_coefficient_dps_per_c=0.01)
    for bad_coef in ((0.1, 0.2), "0.1", (0.1, float("inf"), 0.0), True):
        with pytest.raises(SettingsError, match="temp_coefficient_dps_per_c"):
            GyroFilter(FS, preset="paper", temp_coefficient_dps_per_c=bad_coef)
    # without compensation the temperatures are not needed, and not used
    assert np.array_equal(GyroFilter(FS, preset="paper").filter(x), GyroFilter(FS, preset="paper").filter(x, temps))


def test_a_calibration_without_compensation_keeps_the_windows_temperature_when_given():
    """A calibration saved from a source with temperatures can serve a later compensated run."""
    x, temps = warming(1000, (0.0, 0.0, 0.0), seed=2)
    f = GyroFilter(FS, preset="paper")
    f.filter(x[:150], temps[:150])
    stream(f, x[150:400], temps[150:400])
    assert f.calibration.temp_c == pytest.approx(temps[:200].mean())
    later = GyroFilter(FS, preset="paper", calibration=f.calibration, temp_coefficient_dps_per_c=0.01)
    assert later.calibration.temp_c == f.calibration.temp_c
    # a window with any sample lacking a temperature keeps none (no invented T0)
    for feed in ("no temps in one call", "nan", "update without"):
        g = GyroFilter(FS, preset="paper")
        if feed == "no temps in one call":
            g.filter(x[:100], temps[:100])
            g.filter(x[100:400])
        elif feed == "nan":
            bad = temps.copy()
            bad[123] = np.nan
            g.filter(x[:400], bad[:400])
        else:
            g.filter(x[:50], temps[:50])
            g.update(tuple(x[50]))
            g.filter(x[51:400], temps[51:400])
        assert g.calibration is not None and g.calibration.temp_c is None, feed
    # a retried window keeps the temperatures of the window that passed
    moved = x.copy()
    moved[:200] += np.linspace(0, 30, 200)[:, None]
    r = GyroFilter(FS, preset="paper", calibration_retry_s=5.0)
    r.filter(moved[:300], temps[:300])
    r.filter(moved[300:], None)
    assert r.calibration is not None and r.calibration.temp_c is None
    r2 = GyroFilter(FS, preset="paper", calibration_retry_s=5.0)
    r2.filter(moved[:600], temps[:600])
    assert r2.calibration.temp_c == pytest.approx(temps[200:400].mean())
    with pytest.raises(SettingsError, match="shape"):
        GyroFilter(FS, preset="paper").filter(x, temps[:-1])


def test_coefficients_come_from_a_gap_or_simulator_model():
    model = {"axes": {"x": {"effects": [{"effect": "white_noise", "arw_dps_per_sqrt_hz": 0.01},
                                        {"effect": "temperature", "coefficient_dps_per_c": 0.02}]},
                      "z": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": -0.01}]}}}
    assert coefficients_from_model(model) == (0.02, 0.0, -0.01)
