"""Tests for gyrofilter.allan: Stable32/NBS14 reference values, allantools as oracle, bad input."""
import math

import numpy as np
import pytest

from gyrofilter.allan import (AllanInputError, adev, default_cluster_sizes, overlapping_adev)
from gyrofilter.errors import GyroFilterError, SettingsError

# NBS14 frequency data set with Stable32 results (NIST SP 1065 Table 31; used by allantools).
NBS14 = np.array([892, 809, 823, 798, 671, 644, 883, 903, 677], dtype=float)


def test_nbs14_non_overlapping_adev_matches_stable32():
    tau, dev = adev(NBS14, 1.0, taus_s=[1, 2])
    assert tau.tolist() == [1.0, 2.0]
    assert dev[0] == pytest.approx(91.22945, rel=1e-7)
    assert dev[1] == pytest.approx(115.8082, rel=1e-6)


def test_nbs14_overlapping_adev_matches_stable32():
    tau, dev = overlapping_adev(NBS14, 1.0, taus_s=[1, 2])
    assert dev[0] == pytest.approx(91.22945, rel=1e-7)  # m = 1: overlapping = non-overlapping
    assert dev[1] == pytest.approx(85.95287, rel=1e-6)


def test_matches_allantools_oadev_on_random_data():
    allantools = pytest.importorskip("allantools")
    rng = np.random.default_rng(4)
    fs = 100.0
    x = 0.3 + rng.normal(0.0, 0.05, 20000) + np.cumsum(rng.normal(0.0, 1e-4, 20000))
    tau, dev = overlapping_adev(x, fs)
    t_ref, d_ref, _, _ = allantools.oadev(x, rate=fs, data_type="freq", taus=tau)
    np.testing.assert_array_equal(t_ref, tau)
    np.testing.assert_allclose(dev, d_ref, rtol=1e-9, atol=0)


def test_chunked_sums_equal_direct_formula_across_chunk_boundaries():
    # 150000 samples spans several 65536-sample chunks of the cumulative sum and the work buffer
    rng = np.random.default_rng(1)
    x = rng.normal(-3.3, 0.1, 150000)
    taus = np.array([1, 7, 1000, 40000]) / 50.0
    _, dev = overlapping_adev(x, 50.0, taus)
    phase = np.concatenate([[0.0], np.cumsum(x - x.mean())]) / 50.0
    for m, d in zip([1, 7, 1000, 40000], dev):
        diff = phase[2 * m:] - 2 * phase[m:-m] + phase[:-2 * m]
        ref = math.sqrt(np.mean(diff ** 2) / 2) / (m / 50.0)
        assert d == pytest.approx(ref, rel=1e-10)


def test_white_noise_level_and_slope():
    rng = np.random.default_rng(7)
    fs, arw = 100.0, 0.01  # deg/sqrt(s) -> per-sample std arw * sqrt(fs)
    x = rng.normal(0.0, arw * math.sqrt(fs), 200000)
    tau, dev = overlapping_adev(x, fs)
    # sigma(tau) = N / sqrt(tau) (paper 000); within a few % over the well-averaged taus
    ok = tau <= 20
    np.testing.assert_allclose(dev[ok] * np.sqrt(tau[ok]), arw, rtol=0.08)


def test_default_taus_ten_per_decade_up_to_a_ninth():
    m = default_cluster_sizes(90000)
    assert m[0] == 1 and m[-1] == 10000
    assert 35 <= m.size <= 41  # 4 decades, ~10 per decade (small m merge after rounding)
    tau, dev = overlapping_adev(np.random.default_rng(0).normal(size=90000), 10.0)
    assert tau[-1] == pytest.approx(1000.0)
    assert np.all(np.diff(tau) > 0)


def test_constant_data_gives_zero_deviation():
    tau, dev = overlapping_adev(np.full(100, 2.5), 1.0)
    assert np.all(dev == 0.0)


@pytest.mark.parametrize("x, rate, taus, match", [
    (np.array([1.0, np.nan, 2.0, 3.0] * 5), 1.0, None, "NaN"),
    (np.array([1.0, 2.0]), 1.0, None, "at least 3"),
    (np.ones((100, 3)), 1.0, None, "1-D"),
    (np.ones(100), 1.0, [60.0], "too short"),
    (np.ones(100), 1.0, [0.2], "shorter than one sample"),
    (np.ones(5), 1.0, None, "fewer than 9 clusters"),
])
def test_bad_input_raises_clear_error(x, rate, taus, match):
    with pytest.raises(AllanInputError, match=match):
        overlapping_adev(x, rate, taus)


@pytest.mark.parametrize("rate", [None, 0.0, -1.0, float("nan"), "fast"])
def test_missing_or_bad_rate(rate):
    with pytest.raises(SettingsError, match="sample_rate_hz"):
        overlapping_adev(np.ones(100), rate)
    assert issubclass(SettingsError, GyroFilterError)
