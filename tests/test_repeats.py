"""Repeated rows (issue 36): the simulator's whole-row term ``repeated_samples`` and the count of
repeated rows against chance (gyrofilter/analysis/repeats.py, the gap detector's statistic)."""
import math

import numpy as np
import pytest

from gyrofilter.analysis.gap.detectors import REPEATS_ALPHA, detect_repeats
from gyrofilter.analysis.repeats import binomial_upper_tail, grid_step, repeated_rows
from gyrofilter.effects import REPEATED_SAMPLES
from gyrofilter.errors import SettingsError
from gyrofilter.sim.model import validate_model
from gyrofilter.sim.simulate import simulate, simulate_axis_dps, simulate_chunks

LSB_PER_DPS = 131.0


def model(fraction=None, pattern="random", sigma_lsb=1.6, sample_rate_hz=43.0, temperature=False, unit="lsb"):
    """MPU-9250-like at 43 Hz (issue 36): a per-sample noise of ``sigma_lsb`` LSB on every axis."""
    m = {"sample_rate_hz": sample_rate_hz, "gyro_unit": unit, "lsb_per_dps": LSB_PER_DPS,
         "axes": {a: {"bias_dps": 0.4 * i - 0.3, "arw_dps_per_sqrt_hz": sigma_lsb / LSB_PER_DPS / math.sqrt(sample_rate_hz)}
                  for i, a in enumerate("xyz")}}
    if fraction is not None:
        m[REPEATED_SAMPLES] = {"fraction": fraction, "pattern": pattern}
    if temperature:
        m["temperature"] = {"start_c": 25.0, "end_c": 30.0, "tau_s": 300.0, "noise_c": 0.02}
    return m


def equal_rows(gyro):
    return np.all(np.diff(gyro, axis=0) == 0, axis=1)


# ---------------------------------------------------------------------------------------------
# the simulator's term


@pytest.mark.parametrize("pattern", ["random", "beat"])
def test_the_fraction_of_repeated_rows_is_measured_back(pattern):
    rec = simulate(model(0.03, pattern, sigma_lsb=8.0), 2000.0, seed=5)
    rows = equal_rows(rec.gyro_dps)
    # chance of an equal row at 8 LSB of noise: about 3e-5; the count's sd at 86 000 rows: 0.0006
    assert abs(rows.mean() - 0.03) < 0.002
    gaps = np.diff(np.flatnonzero(rows))
    regular = np.mean(np.isin(gaps, [33, 34]))
    if pattern == "beat":  # the poll clock against the output clock: a repeat every 1/f rows (and a few by chance)
        assert regular > 0.99
    else:  # independent rows: geometric gaps, 33 or 34 about 2 f (1 - f)^32 of them
        assert regular < 0.05


def test_the_repeats_hit_every_column_and_every_block_alike():
    m = model(0.05, temperature=True)
    one = simulate(m, 300.0, seed=2, chunk_samples=10**6)
    parts = list(simulate_chunks(m, 300.0, seed=2, chunk_samples=97))
    assert np.array_equal(np.concatenate([p[1] for p in parts]), np.column_stack([one.columns[c] for c in ("gx", "gy", "gz")]))
    assert np.array_equal(np.concatenate([p[2] for p in parts]), one.columns["temp"])
    rows = equal_rows(one.gyro_dps)
    assert rows.mean() > 0.04
    # the temperature repeats with its row (the rows equal by chance, 0.5 % of them, need not)
    assert np.mean(np.diff(one.columns["temp"])[rows] == 0) > 0.85
    assert np.mean(np.diff(one.columns["temp"])[~rows] == 0) < 0.05
    for axis in range(3):  # one axis simulated alone repeats the same rows (the record's stream)
        alone = np.concatenate(list(simulate_axis_dps(m, 300.0, axis, seed=2, chunk_samples=61)))
        assert np.array_equal(alone, one.gyro_dps[:, axis])


def test_a_model_without_the_key_is_unchanged_and_the_axes_keep_their_draws():
    """A row that is no repeat is the plain model's row (common random numbers: the repeats have a
    stream of their own), so a gap's extended model shares the baseline's noise."""
    plain = simulate(model(), 100.0, seed=9).gyro_dps
    repeated = simulate(model(0.1), 100.0, seed=9).gyro_dps
    fresh = np.r_[0, np.flatnonzero(~equal_rows(repeated)) + 1]
    assert np.array_equal(repeated[fresh], plain[fresh])
    assert 0.08 < 1 - fresh.size / len(plain) < 0.12


def test_the_model_key_is_checked():
    spec, _ = validate_model(model(0.02))
    assert spec[REPEATED_SAMPLES] == {"effect": REPEATED_SAMPLES, "fraction": 0.02, "pattern": "random"}
    assert validate_model(model())[0][REPEATED_SAMPLES] is None
    with pytest.raises(SettingsError, match=r"^model: repeated_samples\.fraction: expected a number "
                                            r"<= 0\.5, got 0\.7$"):
        validate_model(model(0.7))
    with pytest.raises(SettingsError, match="pattern: expected one of random, beat"):
        validate_model(model(0.02, pattern="poll"))
    bad = model()
    bad["axes"]["x"]["effects"] = [{"effect": REPEATED_SAMPLES, "fraction": 0.02}]
    with pytest.raises(SettingsError, match="acts on whole rows, every axis at once: give it as the model's top-level"):
        validate_model(bad)
    bad = model()
    bad[REPEATED_SAMPLES] = [0.02]
    with pytest.raises(SettingsError, match="^model: repeated_samples: expected an object"):
        validate_model(bad)


# ---------------------------------------------------------------------------------------------
# the count against chance


def test_the_binomial_tail_matches_scipy():
    from scipy.stats import binom

    for k, m, p in [(5, 100, 0.01), (250, 40000, 0.005), (0, 10, 0.3), (40, 50, 0.9), (1000, 41279, 0.0046)]:
        assert binomial_upper_tail(k, m, p) == pytest.approx(binom.sf(k - 1, m, p), rel=1e-9, abs=1e-300)


@pytest.mark.parametrize("sigma_lsb", [0.8, 1.6, 4.0])
def test_the_chance_level_matches_clean_quantized_records(sigma_lsb):
    """The chance level read off the ±1, ±2, ±3-step differences against the observed share of
    equal rows on clean records (averaged over seeds: the count's own noise averages out)."""
    ratio = []
    for seed in range(8):
        counted = repeated_rows(simulate(model(sigma_lsb=sigma_lsb), 960.0, seed=seed).gyro_dps, 1 / LSB_PER_DPS)
        ratio.append(counted.fraction / counted.chance)
    assert abs(np.mean(ratio) - 1.0) < 0.06


def test_clean_quantized_records_raise_few_false_alarms():
    """50 clean 16-min records at 43 Hz (chance of an equal row about 0.5 %, issue 36's): none below
    the test's level (its expected count 50 alpha = 0.05), and the smallest p-value far above it."""
    p_values = [repeated_rows(simulate(model(), 960.0, seed=100 + seed).gyro_dps, 1 / LSB_PER_DPS).p_value
                for seed in range(50)]
    assert sum(p < REPEATS_ALPHA for p in p_values) == 0
    assert min(p_values) > 10 * REPEATS_ALPHA


@pytest.mark.parametrize("sigma_lsb", [0.3, 0.45, 0.6])
def test_a_clean_record_of_noise_near_the_step_is_not_applicable_not_a_false_alarm(sigma_lsb):
    """Issue 37 (attack 4): clean white noise of 0.3-0.62 LSB, its means anywhere on the step
    (here 0.2 steps off the codes), rounded: the rows equal by chance far more often
    than the sampled Gaussian of the ±1-3-step differences says (36 % against 24.5 % at 0.3 LSB),
    and allan warned of repeated rows, "an excess of 15.70 %", at p < 1e-300, in up to half of
    such records. There the count is not applicable, saying why."""
    rng = np.random.default_rng(11)
    codes = np.round(rng.normal(0.2, sigma_lsb, (60000, 3)))  # at 0.45 LSB: p = 2.5e-59 before
    counted = repeated_rows(codes / LSB_PER_DPS, 1 / LSB_PER_DPS)
    assert not counted.applicable and "too near the step" in counted.why, counted


@pytest.mark.parametrize("pattern", ["random", "beat"])
def test_two_percent_of_repeated_rows_are_found_with_their_fraction(pattern):
    counted, cand = detect_repeats(simulate(model(0.02, pattern), 960.0, seed=3).gyro_dps, 1 / LSB_PER_DPS)
    assert cand is not None and cand.effect == REPEATED_SAMPLES
    low, high = counted.excess_ci95
    assert low < 0.02 < high and high - low < 0.006
    assert abs(cand.params["fraction"] - 0.02) < 0.003
    assert 0.004 < counted.chance < 0.007  # issue 36: about 0.5 % at this quantization


def test_deg_per_s_records_on_a_grid_and_records_off_any_grid():
    gyro = simulate(model(0.02, unit="dps"), 960.0, seed=4).gyro_dps
    assert grid_step(gyro[:, 0]) == pytest.approx(1 / LSB_PER_DPS, rel=1e-9)
    counted = repeated_rows(gyro)  # the step inferred from the values
    assert counted.applicable and counted.more_than_chance(REPEATS_ALPHA)
    assert counted.step_dps["y"] == pytest.approx(1 / LSB_PER_DPS, rel=1e-9)
    smooth = gyro + np.random.default_rng(0).normal(0.0, 1e-4, gyro.shape)
    off = repeated_rows(smooth)
    assert not off.applicable and "sit on no grid" in off.why
    assert off.as_dict() == {"applicable": False, "why": off.why}
    below = repeated_rows(simulate(model(sigma_lsb=0.1), 960.0, seed=4).gyro_dps, 1 / LSB_PER_DPS)
    assert not below.applicable and "far below or far above the step" in below.why


def test_the_colored_noise_detector_takes_the_repeats_correlation_out():
    """A repeat copies its row: white noise with 5 % of its rows repeated reads a lag-1 of about
    0.05, above the colored noise's smallest (0.03); told the fraction, the detector finds none,
    and a low pass of lag-1 0.5 under the same repeats reads 0.5 again (unquantized rates; without
    the repeats this seed reads 0.4965)."""
    from gyrofilter.analysis.gap.detectors import detect_colored

    fs = 100.0
    white = {"sample_rate_hz": fs, REPEATED_SAMPLES: {"fraction": 0.05},
             "axes": {a: {"arw_dps_per_sqrt_hz": 0.01} for a in "xyz"}}
    x = simulate(white, 1800.0, seed=6).gyro_dps[:, 0]
    assert detect_colored(x, fs) is not None and abs(detect_colored(x, fs).params["lag1"] - 0.05) < 0.015
    assert detect_colored(x, fs, repeated_fraction=0.05) is None
    white["axes"]["x"]["effects"] = [{"effect": "colored_noise", "lag1": 0.5}]
    x = simulate(white, 1800.0, seed=6).gyro_dps[:, 0]
    assert detect_colored(x, fs).params["lag1"] > 0.505  # f + (1 - f) ((1 - f) 0.5 + f 0.25) = 0.513
    assert abs(detect_colored(x, fs, repeated_fraction=0.05).params["lag1"] - 0.5) < 0.01
